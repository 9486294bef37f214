"""The ``plates`` randomizer: a library vehicle wears a registration front and rear at its
mounting rectangles; the metadata's plate corners are where the plate is drawn (the albedo
label there is the plate's), the characters' boxes lie on it, those of a plate facing away are
not seen, and an OCR engine reads the plate from the recorded corners."""
import json
import os

import numpy as np

from synthgen import run as runner
from synthgen.scene import plates as P

import OpenImageIO as oiio

import plate_ocr
from test_output_kitti import _asset

CAR = "mesh/sumo-car-normal-citrus"


def _inside(poly, xs, ys):
    """Points inside a convex quad (image corners in order)."""
    p = np.asarray(poly)
    s = []
    for a, b in zip(p, np.roll(p, -1, 0)):
        s.append((b[0] - a[0]) * (ys - a[1]) - (b[1] - a[1]) * (xs - a[0]))
    s = np.stack(s)
    return np.all(s >= 0, axis=0) | np.all(s <= 0, axis=0)


def test_a_vehicle_wears_its_registration_where_the_labels_say(tmp_path):
    _asset(CAR)
    scen = tmp_path / "s.yaml"
    scen.write_text(f"""
seed: 3
resolution: [480, 360]
camera: {{fov_y: 14, pose: {{type: orbit, target: [0, 0.6, 0], distance: 10, elevation: 6, azimuth: 255}}}}
lights: [{{type: sky, elevation: 45, azimuth: 120, turbidity: 3, strength: 0.02}}]
ground: {{material: {{type: diffuse, albedo: 0.3}}}}
objects: [{{class: car, asset: {CAR}, yaw: 0, plates: {{country: ru}}}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 16, max_depth: 4}}
outputs: [rgb, albedo, instance]
""")
    out = str(tmp_path / "ds")
    s = runner.run(str(scen), out, count=1, progress=False)
    assert not s["failures"], s.text()
    meta = json.load(open(os.path.join(out, "meta", "000000.json")))
    rec = meta["objects"][0]["plates"]
    assert P.is_valid_registration("ru", rec["text"])
    views = {v["mount"]: v for v in rec["image"]}
    assert set(views) == {"front", "rear"}
    seen = views["rear"]  # the camera stands behind the car, to its side
    albedo = oiio.ImageBuf(os.path.join(out, "albedo", "000000.exr")).get_pixels(oiio.FLOAT)
    ys, xs = np.mgrid[0:albedo.shape[0], 0:albedo.shape[1]] + 0.5
    quad = _inside(seen["corners"], xs, ys)
    # Inside the quad shrunk a little: the plate's own albedo (its light ground or black ink).
    c = np.mean(seen["corners"], axis=0)
    inner = _inside([c + 0.8 * (np.asarray(p) - c) for p in seen["corners"]], xs, ys)
    a = albedo[inner]
    # (The texture is minified: its light ground and black ink filter to greys; the car is yellow.)
    plate_like = (np.ptp(a, axis=1) < 0.02) & (a.max(axis=1) < 0.87)
    assert inner.sum() > 300 and plate_like.mean() > 0.95, (inner.sum(), plate_like.mean())
    # Just outside it: the car's body, not the plate.
    ring = _inside([c + 1.5 * (np.asarray(p) - c) for p in seen["corners"]], xs, ys) & ~quad
    b = albedo[ring]
    assert ((np.abs(b - 0.85).max(axis=1) < 0.03)).mean() < 0.2
    # Each character's box lies on the plate, in reading order, and is seen.
    x0, y0, x1, y1 = seen["bbox"]
    chars = seen["characters"]
    assert [ch["char"] for ch in chars] == [ch for ch in rec["text"] if ch != " "]
    for ch in chars:
        bx0, by0, bx1, by1 = ch["bbox"]
        assert x0 - 0.5 <= bx0 < bx1 <= x1 + 0.5 and y0 - 0.5 <= by0 < by1 <= y1 + 0.5, ch
        assert ch["visible"], ch
    # The front plate faces away: its characters are not seen.
    assert not any(ch["visible"] for ch in views["front"]["characters"])
    if plate_ocr.available():
        rgb = oiio.ImageBuf(os.path.join(out, "images", "000000.png")).get_pixels(oiio.FLOAT)
        got = plate_ocr.read_plate(plate_ocr.srgb_gray(rgb), np.asarray(seen["corners"]), "ru")
        truth = rec["text_latin"]
        width = float(np.hypot(*(np.subtract(seen["corners"][1], seen["corners"][0]))))
        print(f"\nrear plate {truth!r}, {width:.0f} px wide: read {got!r}")
        assert plate_ocr.characters_read(truth, got) >= len(truth.replace(" ", "")) - 1


def test_plates_on_a_model_without_mounts_are_refused(tmp_path):
    scen = tmp_path / "s.yaml"
    scen.write_text("""
seed: 1
resolution: [64, 48]
objects: [{class: box, primitive: box, plates: {country: de}}]
render: {spp: 1}
outputs: [rgb]
""")
    from test_randomize_paint import _refused_before_and_by_the_frame

    _refused_before_and_by_the_frame(scen, tmp_path, "plates", "declares no plate mounts")


def test_plate_only_boxes_are_labels_of_their_own_class(tmp_path):
    """``plates: {class: plate}``: the visible plate becomes a label of its own class in COCO,
    YOLO and KITTI: its pixels (exact: pixel centres inside the plate whose first hit is the
    plate) lie on the vehicle, fill the projected plate when nothing hides it, and its boxes
    in the three formats are the metadata's."""
    from synthgen.outputs.coco import rle_decode
    from synthgen.outputs.kitti import parse_kitti
    from synthgen.outputs.yolo import parse_yolo

    _asset(CAR)
    scen = tmp_path / "s.yaml"
    scen.write_text(f"""
seed: 3
resolution: [480, 360]
camera: {{fov_y: 14, pose: {{type: orbit, target: [0, 0.6, 0], distance: 10, elevation: 6, azimuth: 255}}}}
lights: [{{type: sky, elevation: 45, azimuth: 120, turbidity: 3, strength: 0.02}}]
objects: [{{class: car, asset: {CAR}, yaw: 0, plates: {{country: de, class: plate}}}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 4, max_depth: 2}}
outputs: [rgb, instance, depth, coco, yolo, kitti]
""")
    out = str(tmp_path / "ds")
    s = runner.run(str(scen), out, count=1, progress=False)
    assert not s["failures"], s.text()
    meta = json.load(open(os.path.join(out, "meta", "000000.json")))
    assert meta["class_names"] == ["car", "plate"]
    parts = meta["parts"]
    assert [p["mount"] for p in parts] == ["rear"]  # the front plate faces away
    p = parts[0]
    mask = rle_decode(p["mask"])
    ids = oiio.ImageBuf(os.path.join(out, "instance", "000000.png")).get_pixels(oiio.UINT16)[..., 0]
    assert mask.sum() == p["visible_pixels"] > 200
    assert (ids[mask] == meta["objects"][0]["instance_id"]).all()
    ys, xs = np.mgrid[0:mask.shape[0], 0:mask.shape[1]] + 0.5
    quad = _inside(p["corners"], xs, ys)
    assert not (mask & ~quad).any()
    print(f"\nplate: {mask.sum()} visible px of {quad.sum()} inside its projection")
    assert mask.sum() >= 0.97 * quad.sum()
    x, y, w, h = p["bbox"]
    coco = json.load(open(os.path.join(out, "annotations", "coco.json")))
    assert [c["name"] for c in coco["categories"]] == ["car", "plate"]
    plate_anns = [a for a in coco["annotations"] if a["category_id"] == 2]
    assert len(plate_anns) == 1 and plate_anns[0]["bbox"] == [x, y, w, h] and plate_anns[0]["area"] == mask.sum()
    yolo = parse_yolo(open(os.path.join(out, "labels", "000000.txt")).read(), 480, 360)
    assert [c for c, _ in yolo] == [0, 1]
    np.testing.assert_allclose(yolo[1][1], [x, y, w, h], atol=0.01)
    kitti = parse_kitti(open(os.path.join(out, "kitti", "000000.txt")).read())
    plate = [o for o in kitti if o["type"] == "plate"]
    assert len(plate) == 1
    np.testing.assert_allclose(plate[0]["bbox"], [x, y, w, h], atol=0.01)
    np.testing.assert_allclose(plate[0]["dimensions"], [0.112, 0.52, 0.005], atol=0.006)  # KITTI: 2 decimals
