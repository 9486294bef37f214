"""Licence plates (synthgen.scene.plates) and road-sign pictograms (synthgen.scene.signs)."""
from __future__ import annotations

import numpy as np
import pytest

from synthgen.scene import plates, raster, signs


@pytest.mark.parametrize("country", ["ru", "de"])
def test_random_registrations_follow_the_format_rules(country):
    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(2000):
        r = plates.random_registration(country, rng)
        assert plates.is_valid_registration(country, r["text"]), r["text"]
        seen.add(r["text"])
    assert len(seen) > 1900, "registrations vary"


@pytest.mark.parametrize("country, text", [
    ("ru", "Б 123 ВС 77"),     # Б has no Latin look-alike: not allowed
    ("ru", "А 000 ВС 77"),     # number 000
    ("ru", "А 123 ВС 00"),     # no region 00
    ("ru", "A 123 BC 77"),     # Latin letters instead of Cyrillic
    ("de", "HH SS 123"),       # banned combination
    ("de", "HH AB 0123"),      # leading zero
    ("de", "HH AB 12345"),     # five digits
    ("de", "GAP AB 1234"),     # nine characters
    ("de", "XYZ A 1"),         # no such district in the list
])
def test_invalid_registrations_are_rejected(country, text):
    assert not plates.is_valid_registration(country, text)


def _read_back(p) -> str:
    """Template OCR: each character box of the rendered plate is compared with every
    candidate glyph rendered alone at the same box size; the best match is the character
    read. Verifies that what is drawn at each recorded position is the recorded text."""
    img = p["rgb"]
    dark = img.mean(axis=-1) < 0.3
    font = raster.font_path("DejaVuSansCondensed-Bold")
    alphabet = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ"
    templates = {}
    for ch in alphabet:
        m = raster.text_mask(200, 200, ch, 20, 170, 150, font) > 0.5
        rows, cols = np.nonzero(m)
        templates[ch] = m[rows.min():rows.max() + 1, cols.min():cols.max() + 1]
    out = []
    for c in p["characters"]:
        x0, y0, x1, y1 = c["bbox"]
        crop = dark[y0:y1, x0:x1]
        best, best_iou = None, -1.0
        for ch, t in templates.items():
            yi = (np.arange(crop.shape[0]) * t.shape[0] / crop.shape[0]).astype(int)
            xi = (np.arange(crop.shape[1]) * t.shape[1] / crop.shape[1]).astype(int)
            tt = t[yi][:, xi]
            iou = (tt & crop).sum() / max(1, (tt | crop).sum())
            if iou > best_iou:
                best, best_iou = ch, iou
        assert best_iou > 0.75, f"character box {c} does not hold a clean glyph (IoU {best_iou:.2f})"
        out.append(best)
    return "".join(out)


@pytest.mark.parametrize("country", ["ru", "de"])
def test_plate_text_metadata_equals_what_is_drawn(country):
    rng = np.random.default_rng(11)
    for _ in range(4):
        r = plates.random_registration(country, rng)
        p = plates.render_plate(r, px_per_mm=2.0)
        w, h = p["size_mm"]
        assert p["rgb"].shape == (int(round(h * 2)), int(round(w * 2)), 3)
        assert (w, h) == ((520.0, 112.0) if country == "ru" else (520.0, 110.0))
        expect = p["text_latin"].replace(" ", "")
        assert [c["char"] for c in p["characters"]] == [ch for ch in r["text"] if ch != " "]
        boxes = [c["bbox"] for c in p["characters"]]
        # Reading order, left to right, boxes not overlapping (the Russian region code sits in
        # its own field on the right).
        assert all(b[2] <= a[0] for b, a in zip(boxes, boxes[1:])), boxes
        assert _read_back(p) == expect, r["text"]
        n = p["normal"]
        assert n.shape == p["rgb"].shape and np.all(n[..., 2] > 0.5), "normals point out of the plate"
        assert np.abs(n[..., :2] - 0.5).max() > 0.05, "the embossing tilts normals at character edges"


def test_signs_have_their_shape_colours_and_class_names():
    for family, text, cls in (("prohibitory", "70", "speed_limit_70"), ("warning", None, "warning_exclamation"),
                              ("stop", None, "stop"), ("give_way", None, "give_way"),
                              ("information", None, "information_p")):
        s = signs.render_sign(family, text, 128)
        a = s["rgba"]
        assert s["class_name"] == cls and a.shape == (128, 128, 4)
        assert a[0, 0, 3] == 0.0 or family == "information", "corners are outside round/triangular signs"
        assert a[64, 64, 3] == 1.0, "the centre is on the sign"
    ring = signs.render_sign("prohibitory", "50", 128)["rgba"]
    assert ring[64, 3, 0] > 0.4 and ring[64, 3, 1] < 0.1, "red ring at the rim"
    stop = signs.render_sign("stop", None, 128)["rgba"]
    assert stop[20, 64, 0] > 0.4 and stop[20, 64, 1] < 0.1, "red octagon"
    with pytest.raises(ValueError, match="did you mean 'stop'"):
        signs.render_sign("stp")


def test_pictogram_files_are_linear_and_read_in_isolation(tmp_path):
    """An 8-bit PNG pictogram is sRGB-decoded (128/255 -> 0.2159 linear) with its alpha kept, as
    every texture; a corrupt file raises FileError naming it (synthgen-reader decodes it)."""
    import synthgen as sg
    from synthgen.outputs.files import write_srgb_png

    rgb = np.full((4, 6, 3), 0.2158605, np.float32)
    path = str(tmp_path / "grey.png")
    write_srgb_png(path, rgb)
    p = signs.load_pictogram(path, "custom_sign")
    assert p["rgba"].shape == (4, 6, 4) and p["class_name"] == "custom_sign"
    assert np.allclose(p["rgba"][..., :3], 0.2158605, atol=2e-3), p["rgba"][0, 0]
    assert np.all(p["rgba"][..., 3] == 1.0)
    assert np.array_equal(sg.read_image(path, "linear")[0, 0], np.full(3, 128 / 255, np.float32))
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n" + b"x" * 50)
    with pytest.raises(sg.FileError, match=f"^{bad}: "):
        signs.load_pictogram(str(bad), "x")
    with pytest.raises(sg.SynthgenError, match="color_space must be"):
        sg.read_image(path, "rgb")
