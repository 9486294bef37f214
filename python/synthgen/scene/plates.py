"""Licence plates: valid random registrations and plate textures for Russia and Germany.

* Russia (GOST R 50577-93, type 1): 520 x 112 mm, ``A 123 BC`` + region code (2 or 3
  digits) over ``RUS`` and the flag. Letters are the 12 Cyrillic letters with Latin
  look-alikes (А В Е К М Н О Р С Т У Х); the number is 001-999.
* Germany (FZV / DIN 74069): 520 x 110 mm, the blue EU band with ``D``, the district code
  (1-3 letters), the two seals, 1-2 recognition letters and 1-4 digits (no leading zero), at
  most 8 letters and digits together; recognition letters without umlauts, and the
  combinations HJ, KZ, NS, SA, SS are not issued.

Characters are drawn from geometry by :mod:`synthgen.scene.glyphs` (a stroke font after the
standards' forms: the official GOST and FE-Schrift fonts are not packaged), at the standards'
heights and stroke widths: Russian digits 76 mm (strokes 11 mm), letters and region code 58 mm
(9 mm), "RUS" 20 mm (3 mm); German characters 75 mm (10 mm), letters 47.5 and digits 44.5 mm
wide (the narrow 40.5 / 38.5 mm form for long registrations). :func:`render_plate` returns the colour texture, an embossing normal map
(tangent space, the characters and the rim raised) and the text with every character's
pixel box, for OCR datasets. Russian letters are drawn with their Latin look-alike glyphs
(as on real plates); the metadata has the Cyrillic text and `text_latin`.
"""
from __future__ import annotations

import re
from typing import Any, Dict, List

import numpy as np

from . import glyphs as G
from . import raster as R

__all__ = ["COUNTRIES", "random_registration", "is_valid_registration", "render_plate", "RU_LETTERS",
           "RU_REGIONS", "DE_DISTRICTS"]

COUNTRIES = ("ru", "de")
#: Cyrillic letters allowed on Russian plates (those with Latin look-alikes).
RU_LETTERS = "АВЕКМНОРСТУХ"
#: Their Latin look-alikes (the glyphs drawn, and the common transliteration in datasets).
RU_TO_LATIN = dict(zip("АВЕКМНОРСТУХ", "ABEKMHOPCTYX"))
#: Region codes in use (two-digit codes and the three-digit ones of the large regions).
RU_REGIONS = tuple(f"{i:02d}" for i in range(1, 90)) + ("92", "93", "94", "95", "99") + (
    "102", "113", "116", "121", "123", "124", "125", "126", "134", "136", "138", "142", "147", "150", "152", "154",
    "159", "161", "163", "164", "173", "174", "177", "178", "186", "190", "196", "197", "198", "199", "702", "716",
    "725", "750", "761", "763", "774", "777", "790", "797", "799")
#: A sample of German district codes (codes with umlauts are left out: the text renderer
#: draws ASCII only).
DE_DISTRICTS = ("A", "AC", "B", "BN", "BO", "BS", "D", "DD", "DO", "DU", "E", "F", "FR", "GE", "H", "HB", "HD",
                "HH", "HI", "HN", "K", "KA", "KI", "KS", "L", "LU", "M", "MA", "MS", "MZ", "N", "OF", "OS", "PB",
                "R", "S", "SB", "TR", "UL", "WI", "GAP", "HSK", "MTK", "OHZ")
DE_BANNED = ("HJ", "KZ", "NS", "SA", "SS")
SIZE_MM = {"ru": (520.0, 112.0), "de": (520.0, 110.0)}


def _check_country(country: str) -> str:
    c = str(country).lower()
    if c not in COUNTRIES:
        raise ValueError(f"unknown country {country!r}; supported: {', '.join(COUNTRIES)}")
    return c


def random_registration(country: str, rng: np.random.Generator) -> Dict[str, Any]:
    """A random valid registration: {'country', 'text' (as printed, parts separated by
    spaces), 'parts'}."""
    c = _check_country(country)
    if c == "ru":
        l1 = RU_LETTERS[int(rng.integers(len(RU_LETTERS)))]
        num = f"{int(rng.integers(1, 1000)):03d}"
        l23 = "".join(RU_LETTERS[int(i)] for i in rng.integers(len(RU_LETTERS), size=2))
        region = RU_REGIONS[int(rng.integers(len(RU_REGIONS)))]
        parts = [l1, num, l23, region]
        return {"country": c, "text": " ".join(parts), "parts": parts}
    district = DE_DISTRICTS[int(rng.integers(len(DE_DISTRICTS)))]
    while True:
        n_letters = int(rng.integers(1, 3))
        letters = "".join(chr(ord("A") + int(i)) for i in rng.integers(26, size=n_letters))
        if letters in DE_BANNED or (district + letters) in ("NSU",):
            continue
        max_digits = min(4, 8 - len(district) - n_letters)
        if max_digits < 1:
            continue
        n_digits = int(rng.integers(1, max_digits + 1))
        digits = str(int(rng.integers(10 ** (n_digits - 1), 10 ** n_digits)))
        break
    parts = [district, letters, digits]
    return {"country": c, "text": " ".join(parts), "parts": parts}


_RU_RE = re.compile(f"^[{RU_LETTERS}] (\\d{{3}}) [{RU_LETTERS}]{{2}} (\\d{{2,3}})$")
_DE_RE = re.compile(r"^([A-Z]{1,3}) ([A-Z]{1,2}) ([1-9]\d{0,3})$")


def is_valid_registration(country: str, text: str) -> bool:
    """Whether `text` follows the country's format rules."""
    c = _check_country(country)
    if c == "ru":
        m = _RU_RE.match(text)
        return bool(m) and m.group(1) != "000" and m.group(2) in RU_REGIONS
    m = _DE_RE.match(text)
    if not m:
        return False
    district, letters, digits = m.groups()
    return (district in DE_DISTRICTS and letters not in DE_BANNED and
            len(district) + len(letters) + len(digits) <= 8)


def _group_width(text: str, widths: Dict[str, float], gap: float) -> float:
    """Width of a group of characters laid out by :func:`_place_glyphs` (boxes and gaps)."""
    cs = [ch for ch in text if ch != " "]
    return float(sum(_box_width(ch, widths) for ch in cs) + gap * max(0, len(cs) - 1))


def _box_width(ch: str, widths: Dict[str, float]) -> float:
    """A character's box width: its group's (``widths[ch]`` or ``widths["*"]``), wider for the
    glyphs the standards draw wider (M, W)."""
    latin = RU_TO_LATIN.get(ch, ch)
    return widths.get(ch, widths["*"]) * G.WIDTH.get(latin, 0.62) / 0.62


def _place_glyphs(img: np.ndarray, ink: np.ndarray, text: str, x_left: float, x_right: float, baseline: float,
                  height: float, stroke: float, widths: Dict[str, float], gap: float, color,
                  chars: List[Dict[str, Any]]) -> None:
    """Draws ``text`` (its Latin look-alikes) with the plate stroke font
    (:mod:`synthgen.scene.glyphs`), centred in [x_left, x_right]: each character ``height``
    pixels tall standing on ``baseline`` (image row), its box ``widths[ch]`` (``widths["*"]``
    by default) wide, ``gap`` pixels between boxes, strokes ``stroke`` pixels wide; records each
    character's ink box."""
    cs = [ch for ch in text if ch != " "]
    if not cs:
        return
    x = 0.5 * (x_left + x_right - _group_width(text, widths, gap))
    H, W = ink.shape
    for ch in cs:
        wd = _box_width(ch, widths)
        m, (ox, oy) = G.glyph_coverage(RU_TO_LATIN.get(ch, ch), height, stroke, width_px=wd)
        # NOTE: the glyph is rasterized at an integer origin, so x is rounded (1/2 px at 2 px/mm
        # is a quarter of a millimetre).
        gx0 = int(round(x - ox))
        gy0 = int(round(baseline - height - oy))
        h, w = m.shape
        ys, xs = slice(max(0, gy0), min(H, gy0 + h)), slice(max(0, gx0), min(W, gx0 + w))
        sub = m[ys.start - gy0: ys.stop - gy0, xs.start - gx0: xs.stop - gx0]
        ink[ys, xs] = np.maximum(ink[ys, xs], sub)
        cover = np.zeros((H, W), np.float32)
        cover[ys, xs] = sub
        R.paint(img, cover, color)
        rows, cols = np.nonzero(cover > 0.5)
        chars.append({"char": ch, "bbox": [int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1]})
        x += wd + gap


def _normal_map(height: np.ndarray, strength: float) -> np.ndarray:
    """Tangent-space normal map (RGB in [0, 1]) of a height field (image rows go down, the
    texture's v goes up)."""
    k = np.array([1, 4, 6, 4, 1], np.float32) / 16.0
    h = height.astype(np.float32)
    for axis in (0, 1):
        h = np.apply_along_axis(lambda r: np.convolve(np.pad(r, 2, mode="edge"), k, mode="valid"), axis, h)
    dx = np.gradient(h, axis=1)
    dy = -np.gradient(h, axis=0)
    n = np.stack([-strength * dx, -strength * dy, np.ones_like(h)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return (0.5 * n + 0.5).astype(np.float32)


def render_plate(registration: Dict[str, Any], px_per_mm: float = 2.0, emboss: float = 2.0) -> Dict[str, Any]:
    """The plate texture of a registration from :func:`random_registration` (or any dict with
    'country' and 'parts'): {'rgb' (H x W x 3 linear), 'normal' (embossing normal map),
    'size_mm', 'px_per_mm', 'country', 'text', 'characters' ([{'char', 'bbox' [x0, y0, x1, y1]
    in pixels}] in reading order)}."""
    c = _check_country(registration["country"])
    parts = list(registration["parts"])
    wmm, hmm = SIZE_MM[c]
    W, H = int(round(wmm * px_per_mm)), int(round(hmm * px_per_mm))
    mm = px_per_mm
    img = R.canvas(H, W, (0.85, 0.85, 0.85))
    ink = np.zeros((H, W), np.float32)
    chars: List[Dict[str, Any]] = []
    black = (0.02, 0.02, 0.02)
    # Rim: a black border 1.5 mm inside the plate edge, 2 mm wide.
    outer = R.rounded_rect_sdf(H, W, 1.5 * mm, 1.5 * mm, W - 1.5 * mm, H - 1.5 * mm, 4 * mm)
    rim = R.coverage_sdf(np.maximum(outer, -(outer + 2.0 * mm)))
    R.paint(img, rim, black)
    ink = np.maximum(ink, rim)
    if c == "ru":
        split = 400.0 * mm
        line = R.coverage_sdf(R.rounded_rect_sdf(H, W, split - mm, 1.5 * mm, split + mm, H - 1.5 * mm))
        R.paint(img, line, black)
        ink = np.maximum(ink, line)
        # GOST R 50577-93, type 1: digits 76 mm high (strokes 11 mm), letters and the region code
        # 58 mm (9 mm), "RUS" 20 mm (3 mm); the letters stand on the digits' baseline.
        l1, num, l23, region = parts
        base = H - 18 * mm
        letters = {"*": 42 * mm}
        digits = {"*": 47 * mm}
        total = _group_width(l1, letters, 0) + 12 * mm + _group_width(num, digits, 8 * mm) + 12 * mm + \
            _group_width(l23, letters, 8 * mm)
        x = 0.5 * (split - total)
        for text, wds, height, stroke, gap in ((l1, letters, 58, 9, 0), (num, digits, 76, 11, 8),
                                               (l23, letters, 58, 9, 8)):
            wd = _group_width(text, wds, gap * mm)
            _place_glyphs(img, ink, text, x, x + wd, base, height * mm, stroke * mm, wds, gap * mm, black, chars)
            x += wd + 12 * mm
        narrow = len(region) == 3
        _place_glyphs(img, ink, region, split, W - 3.5 * mm, 68 * mm, 58 * mm, 9 * mm,
                      {"*": (30 if narrow else 38) * mm}, (4 if narrow else 6) * mm, black, chars)
        # "RUS" and the flag below the region code (not part of the registration text).
        rus: List[Dict[str, Any]] = []
        _place_glyphs(img, ink, "RUS", split + 6 * mm, W - 34 * mm, 98 * mm, 20 * mm, 3 * mm, {"*": 12.5 * mm},
                      3 * mm, black, rus)
        for k, col in enumerate(((0.9, 0.9, 0.9), (0.0, 0.2, 0.6), (0.75, 0.05, 0.05))):
            y0 = 78 * mm + k * 6.7 * mm
            R.paint(img, R.coverage_sdf(R.rounded_rect_sdf(H, W, W - 36 * mm, y0, W - 12 * mm, y0 + 5 * mm)), col)
    else:
        band = R.coverage_sdf(R.rounded_rect_sdf(H, W, 3.5 * mm, 3.5 * mm, 45 * mm, H - 3.5 * mm, 2 * mm))
        R.paint(img, band, (0.0, 0.12, 0.55))
        for k in range(12):  # the EU circle of stars (dots)
            a = 2 * np.pi * k / 12
            R.paint(img, R.coverage_sdf(R.circle_sdf(H, W, 24 * mm + 11 * mm * np.cos(a), 35 * mm + 11 * mm * np.sin(a),
                                                     1.6 * mm)), (0.9, 0.75, 0.0))
        country: List[Dict[str, Any]] = []
        _place_glyphs(img, ink, "D", 5 * mm, 44 * mm, 97 * mm, 26 * mm, 4 * mm, {"*": 18 * mm}, 0,
                      (0.95, 0.95, 0.95), country)
        district, letters, digits = parts
        # DIN 1451 / FE-Schrift: 75 mm high, strokes 10 mm; letters 47.5 mm and digits 44.5 mm
        # wide, or the narrow form (40.5 and 38.5 mm) when a long registration would not fit
        # between the EU band and the rim (FZV Anlage 4), then narrower still if need be.
        gap, seal = 4 * mm, 44 * mm
        avail = W - 50 * mm - 8 * mm

        def need(wl: float, wd: float) -> float:
            return (_group_width(district, {"*": wl}, gap) + _group_width(letters, {"*": wl}, gap) +
                    _group_width(digits, {"*": wd}, gap) + seal + 2 * 8 * mm + 12 * mm)

        wl, wd = 47.5 * mm, 44.5 * mm
        if need(wl, wd) > avail:
            wl, wd = 40.5 * mm, 38.5 * mm
        f = min(1.0, avail / need(wl, wd))
        wl, wd = wl * f, wd * f
        base = 0.5 * H + 0.5 * 75 * mm
        x = 50 * mm
        w_d = _group_width(district, {"*": wl}, gap)
        _place_glyphs(img, ink, district, x, x + w_d, base, 75 * mm, 10 * mm, {"*": wl}, gap, black, chars)
        x += w_d + 8 * mm
        # The two seals (registration and inspection stickers), as coloured discs.
        r_seal = 0.5 * seal
        sx = x + r_seal
        R.paint(img, R.coverage_sdf(R.circle_sdf(H, W, sx, 0.5 * H - 1.05 * r_seal * 0.5, r_seal * 0.5)),
                (0.2, 0.45, 0.25))
        R.paint(img, R.coverage_sdf(R.circle_sdf(H, W, sx, 0.5 * H + 1.05 * r_seal * 0.5, r_seal * 0.5)),
                (0.75, 0.6, 0.2))
        x = sx + r_seal + 8 * mm
        w_l = _group_width(letters, {"*": wl}, gap)
        _place_glyphs(img, ink, letters, x, x + w_l, base, 75 * mm, 10 * mm, {"*": wl}, gap, black, chars)
        x += w_l + 12 * mm
        _place_glyphs(img, ink, digits, x, x + _group_width(digits, {"*": wd}, gap), base, 75 * mm, 10 * mm,
                      {"*": wd}, gap, black, chars)
    return {"rgb": img[..., :3].copy(), "normal": _normal_map(ink, emboss), "ink": ink, "size_mm": (wmm, hmm),
            "px_per_mm": px_per_mm, "country": c, "text": registration["text"],
            "text_latin": "".join(RU_TO_LATIN.get(ch, ch) for ch in registration["text"]), "characters": chars}
