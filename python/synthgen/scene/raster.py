"""Small 2D rasterizer for generated textures (plates, sign pictograms): anti-aliased shape
coverage from signed distances, text through OpenImageIO's FreeType text renderer with the
DejaVu fonts (Debian fonts-dejavu-core), alpha compositing. Pure functions on numpy arrays
(H x W x C float32, linear RGB), deterministic.
"""
from __future__ import annotations

import os
from typing import Sequence, Tuple

import numpy as np

__all__ = ["FONT_DIR", "font_path", "canvas", "coverage_sdf", "circle_sdf", "polygon_sdf", "rounded_rect_sdf",
           "paint", "text_mask", "text_box"]

FONT_DIR = "/usr/share/fonts/truetype/dejavu"


def font_path(name: str = "DejaVuSans-Bold") -> str:
    p = os.path.join(FONT_DIR, name + ".ttf")
    if not os.path.isfile(p):
        raise FileNotFoundError(f"font {p} not found (Debian package fonts-dejavu-core)")
    return p


def canvas(h: int, w: int, color=(1.0, 1.0, 1.0), alpha: float = 1.0) -> np.ndarray:
    """An H x W x 4 RGBA image filled with `color` and `alpha`."""
    img = np.empty((h, w, 4), np.float32)
    img[..., :3] = np.asarray(color, np.float32)
    img[..., 3] = alpha
    return img


def _grid(h: int, w: int) -> Tuple[np.ndarray, np.ndarray]:
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    return x + 0.5, y + 0.5


def coverage_sdf(sdf: np.ndarray) -> np.ndarray:
    """Pixel coverage of the region sdf < 0 (signed distance in pixels): a linear ramp over one
    pixel, the standard anti-aliasing of distance fields."""
    return np.clip(0.5 - sdf, 0.0, 1.0).astype(np.float32)


def circle_sdf(h: int, w: int, cx: float, cy: float, r: float) -> np.ndarray:
    x, y = _grid(h, w)
    return np.hypot(x - cx, y - cy) - r


def polygon_sdf(h: int, w: int, pts: Sequence[Tuple[float, float]]) -> np.ndarray:
    """Signed distance to a simple polygon (pixels; negative inside), after Quilez's
    polygon SDF (winding by crossings)."""
    x, y = _grid(h, w)
    p = np.asarray(pts, np.float64)
    d = (x - p[0, 0]) ** 2 + (y - p[0, 1]) ** 2
    s = np.ones_like(x)
    n = len(p)
    for i in range(n):
        j = (i - 1) % n
        ex, ey = p[j, 0] - p[i, 0], p[j, 1] - p[i, 1]
        wx, wy = x - p[i, 0], y - p[i, 1]
        t = np.clip((wx * ex + wy * ey) / (ex * ex + ey * ey), 0.0, 1.0)
        bx, by = wx - ex * t, wy - ey * t
        d = np.minimum(d, bx * bx + by * by)
        c1 = y >= p[i, 1]
        c2 = y < p[j, 1]
        c3 = ex * wy > ey * wx
        flip = (c1 & c2 & c3) | (~c1 & ~c2 & ~c3)
        s = np.where(flip, -s, s)
    return s * np.sqrt(d)


def rounded_rect_sdf(h: int, w: int, x0: float, y0: float, x1: float, y1: float, r: float = 0.0) -> np.ndarray:
    x, y = _grid(h, w)
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    hx, hy = 0.5 * (x1 - x0) - r, 0.5 * (y1 - y0) - r
    qx, qy = np.abs(x - cx) - hx, np.abs(y - cy) - hy
    return np.hypot(np.maximum(qx, 0), np.maximum(qy, 0)) + np.minimum(np.maximum(qx, qy), 0) - r


def paint(img: np.ndarray, coverage: np.ndarray, color, alpha: float = 1.0) -> np.ndarray:
    """Composites `color` over `img` (RGBA) with the given coverage ("over" operator)."""
    a = (coverage * alpha)[..., None]
    img[..., :3] = img[..., :3] * (1.0 - a) + np.asarray(color, np.float32) * a
    img[..., 3:4] = img[..., 3:4] * (1.0 - a) + a
    return img


def text_box(text: str, size: float, font: str) -> Tuple[int, int, int, int]:
    """(x0, y0, x1, y1) of `text` rendered at the origin baseline (OpenImageIO text_size)."""
    import OpenImageIO as oiio

    roi = oiio.ImageBufAlgo.text_size(text, int(round(size)), font)
    return roi.xbegin, roi.ybegin, roi.xend, roi.yend


def text_mask(h: int, w: int, text: str, x: float, baseline: float, size: float, font: str) -> np.ndarray:
    """Coverage of `text` drawn with its left edge at x and baseline at `baseline` (pixels)."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(oiio.ImageSpec(w, h, 1, oiio.FLOAT))
    oiio.ImageBufAlgo.zero(buf)
    if not oiio.ImageBufAlgo.render_text(buf, int(round(x)), int(round(baseline)), text, int(round(size)), font,
                                         (1.0,)):
        raise RuntimeError(f"text rendering failed: {oiio.geterror()}")
    return np.asarray(buf.get_pixels(oiio.FLOAT), np.float32).reshape(h, w)
