"""Licence plates (synthgen.scene.plates) and road-sign pictograms (synthgen.scene.signs)."""
from __future__ import annotations

import numpy as np
import pytest

from synthgen.scene import plates, signs


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
    """The plate's text read by an OCR engine that was not written from our glyph code
    (tesseract), field by field as an ANPR reader does (tests/python/plate_ocr.py)."""
    import plate_ocr

    if not plate_ocr.available():
        pytest.skip("tesseract-ocr is not installed (make deps installs it)")
    h, w = p["rgb"].shape[:2]
    return plate_ocr.read_plate(plate_ocr.srgb_gray(p["rgb"]), np.array([[0, 0], [w, 0], [w, h], [0, h]], float),
                                p["country"])


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
        assert _read_back(p).replace("O", "0") == expect.replace("O", "0"), r["text"]
        # Each box holds its whole character and nothing of its neighbours': no ink on the ring
        # of pixels just outside it.
        ink = p["ink"] > 0.5
        for x0, y0, x1, y1 in boxes:
            ring = np.zeros(ink.shape, bool)
            ring[y0 - 1:y1 + 1, x0 - 1:x1 + 1] = True
            ring[y0:y1, x0:x1] = False
            assert not (ink & ring).any(), (x0, y0, x1, y1)
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


def _erode(m: np.ndarray, r: float) -> np.ndarray:
    """``m`` eroded by a disc of radius ``r`` pixels."""
    out = m.copy()
    R = int(np.ceil(r))
    p = np.pad(m, R)
    for dy in range(-R, R + 1):
        for dx in range(-R, R + 1):
            if dx * dx + dy * dy <= r * r:
                out &= p[R + dy:R + dy + m.shape[0], R + dx:R + dx + m.shape[1]]
    return out


@pytest.mark.parametrize("country", ["ru", "de"])
def test_plate_characters_have_the_standards_heights_and_strokes(country):
    """GOST R 50577-93: digits 76 mm high, letters and the region code 58 mm, strokes at least
    11 and 9 mm; FE-Schrift: 75 mm, strokes 10 mm. Measured on the texture: each character box's
    height; the stroke by erosion: a disc a little under the stroke's width leaves the
    character's spine from top to bottom, one a little over it leaves (nearly) nothing."""
    mm = 2.0
    rng = np.random.default_rng(3)
    for _ in range(2):
        r = plates.random_registration(country, rng)
        p = plates.render_plate(r, px_per_mm=mm)
        ink = p["ink"] > 0.5
        for c in p["characters"]:
            x0, y0, x1, y1 = c["bbox"]
            if country == "ru":
                height, stroke = (76, 11) if x0 < 400 * mm and c["char"].isdigit() else (58, 9)
            else:
                height, stroke = 75, 10
            assert abs((y1 - y0) - height * mm) <= 2, (c, (y1 - y0) / mm)
            g = ink[y0:y1, x0:x1]
            spine = _erode(g, 0.5 * stroke * mm - 1.5)
            rows = np.nonzero(spine.any(axis=1))[0]
            assert rows.size and (rows.max() - rows.min()) > 0.6 * (y1 - y0), (c, "strokes thinner than the standard's")
            assert _erode(g, 0.5 * stroke * mm + 2.0).sum() < 0.02 * g.sum(), (c, "strokes wider than the standard's")
