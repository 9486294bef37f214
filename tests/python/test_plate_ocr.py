"""Plates are read by an OCR engine that was not written from our glyph code (tesseract): the
plates are rendered by the path tracer at three distances (plates 60 px wide and more) and
three angles up to 45 degrees, rectified from their labelled corners, and read field by field;
at least 90 % of their characters must come back (O and 0 alike). The rate is printed."""
import json
import os

import numpy as np
import pytest

from synthgen import run as runner

import OpenImageIO as oiio

import plate_ocr as P

pytestmark = pytest.mark.skipif(not P.available(), reason="tesseract-ocr is not installed (make deps installs it)")

FOCAL = 1361.0  # px: fov_y 10 degrees at 240 rows
#: Plate widths (px, seen frontally) and the camera's angle to the plate's normal.
WIDTHS = (85, 130, 200)
ANGLES = (0, 25, 45)


def _render(tmp_path, country, width, angle, seed):
    d = FOCAL * 0.52 / width
    scen = tmp_path / f"{country}_{width}_{angle}.yaml"
    scen.write_text(f"""
seed: {seed}
resolution: [320, 240]
camera: {{fov_y: 10, pose: {{type: orbit, target: [0, 0.66, 0], distance: {d:.3f}, elevation: 3, azimuth: {angle}}}}}
lights: [{{type: sky, elevation: 40, azimuth: 150, turbidity: 3, strength: 0.02}}]
ground: {{material: {{type: diffuse, albedo: 0.3}}}}
objects: [{{class: plate, plate: {{country: {country}, mount_height: 0.6}}, yaw: 0}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 8, max_depth: 3}}
outputs: [rgb, instance]
""")
    out = str(tmp_path / f"o_{country}_{width}_{angle}")
    s = runner.run(str(scen), out, count=2, progress=False)
    assert not s["failures"], s.text()
    rows = []
    for k in range(2):
        meta = json.load(open(os.path.join(out, "meta", f"{k:06d}.json")))
        obj = meta["objects"][0]
        rgb = oiio.ImageBuf(os.path.join(out, "images", f"{k:06d}.png")).get_pixels(oiio.FLOAT)
        corners = P.plate_corners(meta, obj)
        seen_width = float(np.hypot(*(corners[1] - corners[0])))
        assert seen_width >= 59.0, seen_width
        got = P.read_plate(P.srgb_gray(rgb), corners, country)
        rows.append((country, seen_width, angle, obj["plate"]["text_latin"], got))
    return rows


def test_rendered_plates_are_read_back_by_tesseract(tmp_path):
    rows = []
    for country in ("ru", "de"):
        for i, width in enumerate(WIDTHS):
            for j, angle in enumerate(ANGLES):
                rows += _render(tmp_path, country, width, angle, seed=100 + 10 * i + j)
    total = sum(len(t.replace(" ", "")) for *_, t, _ in rows)
    right = sum(P.characters_read(t, g) for *_, t, g in rows)
    print("\n" + "\n".join(P.summary(rows)))
    for country in ("ru", "de"):
        sub = [r for r in rows if r[0] == country]
        n = sum(len(t.replace(" ", "")) for *_, t, _ in sub)
        print(f"plate read-back {country}: {sum(P.characters_read(t, g) for *_, t, g in sub)}/{n} characters")
    print(f"plate read-back: {right}/{total} characters ({right / total:.1%}) of {len(rows)} plates, "
          f"widths {min(r[1] for r in rows):.0f}-{max(r[1] for r in rows):.0f} px, angles {ANGLES} deg")
    assert right >= 0.9 * total
