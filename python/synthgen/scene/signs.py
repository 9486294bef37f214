"""Road-sign pictograms, generated procedurally with their class names (Vienna Convention
families, proportions after the German StVO / Russian GOST R 52290 sign drawings, simplified):

=================  ===========================================  ===============================
family             shape and colours                            class name
=================  ===========================================  ===============================
``prohibitory``    white disc, red ring, black number           ``speed_limit_<number>``
``warning``        white triangle (point up), red border,       ``warning_<symbol>``
                   black symbol (``!`` by default)
``stop``           red octagon, white border and ``STOP``       ``stop``
``give_way``       white triangle (point down), red border      ``give_way``
``information``    blue square, white symbol (``P``)            ``information_<symbol>``
=================  ===========================================  ===============================

:func:`render_sign` returns an RGBA texture (alpha 0 outside the sign, for alpha cut-outs on a
plate mesh) and the class name; :func:`load_pictogram` accepts image files for other signs.
"""
from __future__ import annotations

import math
from typing import Any, Dict, Optional

import numpy as np

from . import raster as R

__all__ = ["FAMILIES", "render_sign", "on_background", "load_pictogram", "RED", "BLUE", "WHITE", "BLACK"]

FAMILIES = ("prohibitory", "warning", "stop", "give_way", "information")
RED = (0.55, 0.02, 0.02)
BLUE = (0.0, 0.12, 0.45)
WHITE = (0.85, 0.85, 0.85)
BLACK = (0.02, 0.02, 0.02)


def _text(img: np.ndarray, text: str, cx: float, cy: float, height: float, color, font: str) -> None:
    """Draws `text` centred at (cx, cy) with cap height `height` pixels."""
    size = height / 0.73
    x0, y0, x1, y1 = R.text_box(text, size, font)
    h, w = img.shape[:2]
    m = R.text_mask(h, w, text, cx - 0.5 * (x1 - x0) - x0, cy + 0.5 * height, size, font)
    R.paint(img, m, color)


def render_sign(family: str, text: Optional[str] = None, size: int = 256) -> Dict[str, Any]:
    """{'rgba' (size x size x 4, linear), 'class_name', 'family', 'text'} of a sign of
    `family`; `text` is the number of a prohibitory sign (default "50"), the symbol of a
    warning (default "!") or information sign (default "P")."""
    if family not in FAMILIES:
        import difflib

        m = difflib.get_close_matches(str(family), FAMILIES, n=1)
        raise ValueError(f"unknown sign family {family!r}" + (f" (did you mean {m[0]!r}?)" if m else "") +
                         f"; families: {', '.join(FAMILIES)}")
    if not (16 <= int(size) <= 8192):
        raise ValueError(f"sign size {size} out of range [16, 8192]")
    n = int(size)
    img = R.canvas(n, n, (0.0, 0.0, 0.0), 0.0)
    c = 0.5 * n
    font = R.font_path("DejaVuSans-Bold")
    if family == "prohibitory":
        t = str(text if text is not None else "50")
        outer = R.circle_sdf(n, n, c, c, 0.49 * n)
        R.paint(img, R.coverage_sdf(outer), RED)
        R.paint(img, R.coverage_sdf(outer + 0.11 * n), WHITE)  # ring width: 11% of the size
        _text(img, t, c, c, 0.36 * n if len(t) < 3 else 0.3 * n, BLACK, font)
        cls = f"speed_limit_{t}"
    elif family in ("warning", "give_way"):
        up = family == "warning"
        r = 0.49 * n
        ys = (c + 0.5 * r, c - r) if up else (c - 0.5 * r, c + r)
        hw = r * math.sqrt(3) * 0.5
        tri = [(c - hw, ys[0]), (c, ys[1]), (c + hw, ys[0])]
        sdf = R.polygon_sdf(n, n, tri)
        R.paint(img, R.coverage_sdf(sdf), RED)
        R.paint(img, R.coverage_sdf(sdf + 0.09 * n), WHITE)
        if up:
            t = str(text if text is not None else "!")
            _text(img, t, c, c + 0.06 * n, 0.24 * n, BLACK, font)
            cls = f"warning_{'exclamation' if t == '!' else t}"
        else:
            t = ""
            cls = "give_way"
    elif family == "stop":
        r = 0.49 * n / math.cos(math.pi / 8)
        octo = [(c + r * math.cos(math.pi / 8 + k * math.pi / 4), c + r * math.sin(math.pi / 8 + k * math.pi / 4))
                for k in range(8)]
        sdf = R.polygon_sdf(n, n, octo)
        R.paint(img, R.coverage_sdf(sdf), WHITE)
        R.paint(img, R.coverage_sdf(sdf + 0.03 * n), RED)
        t = "STOP"
        _text(img, t, c, c, 0.2 * n, WHITE, font)
        cls = "stop"
    else:
        t = str(text if text is not None else "P")
        sdf = R.rounded_rect_sdf(n, n, 0.02 * n, 0.02 * n, 0.98 * n, 0.98 * n, 0.06 * n)
        R.paint(img, R.coverage_sdf(sdf), WHITE)
        R.paint(img, R.coverage_sdf(sdf + 0.03 * n), BLUE)
        _text(img, t, c, c, 0.6 * n if len(t) == 1 else 0.3 * n, WHITE, font)
        cls = f"information_{t.lower()}"
    return {"rgba": img, "class_name": cls, "family": family, "text": t}


def on_background(rgba: np.ndarray, grey: float = 0.85) -> np.ndarray:
    """The sign composited over a uniform grey (RGB), e.g. for projection as an opaque decal."""
    a = rgba[..., 3:4]
    return (rgba[..., :3] * a + np.float32(grey) * (1 - a)).astype(np.float32)


def load_pictogram(path: str, class_name: str) -> Dict[str, Any]:
    """An image file (PNG with alpha, JPEG, EXR, ...) as a sign texture with `class_name`.

    Colours are linear (8- and 16-bit files are sRGB-decoded; alpha is kept as stored), as
    every texture synthgen renders; the file is decoded by the isolated reader."""
    from .._core import read_image

    px = np.asarray(read_image(path), np.float32)
    if px.ndim == 2:
        px = px[..., None]
    c = px.shape[2]
    rgba = np.ones(px.shape[:2] + (4,), np.float32)
    rgba[..., :3] = px[..., :3] if c >= 3 else np.repeat(px[..., :1], 3, axis=2)
    if c in (2, 4):
        rgba[..., 3] = px[..., -1]
    return {"rgba": rgba, "class_name": str(class_name), "family": "image", "text": ""}
