"""Plate characters drawn from geometry: a stroke font after the forms of GOST R 50577-93
(Russian plates) and DIN 1451 / FE-Schrift (German plates), whose official fonts are not
packaged.

Each glyph is a set of centrelines -- polylines and circular arcs -- in a box of the character's
width and height (y up, the baseline at 0, the cap line at 1), stroked with a constant width,
flat ends and round joins, as the standards draw them: condensed grotesque forms whose round
letters are stadiums (two half circles joined by straight flanks), the same form for O and 0.
:func:`glyph_coverage` rasterizes a glyph (anti-aliased from the exact distance to its
centrelines) at any size and stroke, so a plate texture has the standard's character
heights and stroke widths in millimetres.

NOTE: the distance to a polyline is the minimum over its segments of the distance to each as
a flat-ended box, plus discs at its inner vertices (round joins); to an arc, | |p - c| - r |
within its angular range, else the distance to its nearer end (flat ends: the end's half
plane). Coverage = clamp(0.5 - (d - stroke / 2) / pixel, 0, 1) (a one-pixel ramp).
"""
from __future__ import annotations

import math
from typing import Dict, List, Optional, Tuple

import numpy as np

__all__ = ["GLYPHS", "WIDTH", "glyph_primitives", "glyph_coverage"]

Prim = Tuple  # ("line", [(x, y), ...]) or ("arc", cx, cy, r, a0_deg, a1_deg) (counter-clockwise a0 -> a1)

#: Width of each glyph's box in units of its height (the standards' proportions: DIN 1451's
#: normal width is about 0.63 of the height; M and W are wider, I and 1 narrower in ink only).
WIDTH: Dict[str, float] = {c: 0.62 for c in "0123456789ABCDEFGHIJKLNOPQRSTUVXYZ"}
WIDTH.update({"M": 0.74, "W": 0.82})


def _stadium_parts(W: float, h: float, lo: float, hi: float):
    """Centre x, half width R, the lower and the upper arc centres' y of a stadium between
    heights lo and hi (centreline coordinates) in a box of width W, stroke half width h."""
    R = 0.5 * (W - 2 * h)
    R = min(R, 0.5 * (hi - lo))
    return 0.5 * W, R, lo + R, hi - R


def _g(ch: str, W: float, h: float) -> List[Prim]:
    t, b = 1.0 - h, h                  # centreline top and bottom
    l, r = h, W - h                    # centreline left and right
    c = 0.5 * W
    m = 0.5                            # middle
    cx, R, yb, yt = _stadium_parts(W, h, b, t)
    if ch in "0O":
        return [("arc", cx, yt, R, 0, 180), ("arc", cx, yb, R, 180, 360), ("line", [(l, yb), (l, yt)]),
                ("line", [(r, yb), (r, yt)])]
    if ch == "Q":
        return _g("O", W, h) + [("line", [(c - 0.05 * R, b + 0.75 * R), (r + 0.6 * h, b - 0.6 * h)])]
    if ch == "C":
        return [("arc", cx, yt, R, 20, 180), ("arc", cx, yb, R, 180, 340), ("line", [(l, yb), (l, yt)])]
    if ch == "G":
        return [("arc", cx, yt, R, 20, 180), ("arc", cx, yb, R, 180, 360), ("line", [(l, yb), (l, yt)]),
                ("line", [(c + 0.05 * R, m - 0.05), (r, m - 0.05), (r, yb)])]
    if ch == "D":
        return [("line", [(c - 0.2 * R, t), (l, t), (l, b), (c - 0.2 * R, b)]),
                ("arc", c - 0.2 * R, t - 1.2 * R, 1.2 * R, 0, 90), ("arc", c - 0.2 * R, b + 1.2 * R, 1.2 * R, 270, 360),
                ("line", [(c + R, t - 1.2 * R), (c + R, b + 1.2 * R)])]
    if ch == "U":
        return [("line", [(l, t), (l, yb)]), ("line", [(r, t), (r, yb)]), ("arc", cx, yb, R, 180, 360)]
    if ch == "J":
        return [("line", [(r, t), (r, yb)]), ("arc", cx, yb, R, 180, 360), ("line", [(l, yb), (l, yb + 0.12)])]
    if ch == "1":
        x = c + 0.25 * R
        return [("line", [(x, b), (x, t), (c - 0.75 * R, t - 0.3)])]
    if ch == "I":
        return [("line", [(c, b), (c, t)])]
    if ch == "2":
        a = math.radians(-35)
        return [("arc", cx, yt, R, -35, 165), ("line", [(cx + R * math.cos(a), yt + R * math.sin(a)), (l, b), (r, b)])]
    if ch == "3":
        ru, rl = min(0.5 * (t - 0.54), R), min(0.5 * (0.54 - b), R)
        return [("arc", r - ru, t - ru, ru, -90, 160), ("arc", r - rl, b + rl, rl, -160, 90),
                ("line", [(r - min(ru, rl), 0.54), (c - 0.25 * R, 0.54)])]
    if ch == "4":
        x = c + 0.45 * R
        return [("line", [(x, b), (x, t), (l, b + 0.3), (r, b + 0.3)])]
    if ch == "5":
        rr = min(R, 0.5 * (0.6 - b))
        return [("line", [(r, t), (l + 0.03, t), (l + 0.01, b + 2 * rr), (cx, b + 2 * rr)]),
                ("arc", cx, b + rr, rr, -150, 90)]
    if ch == "6":
        rr = min(R, 0.5 * (0.62 - b))
        return [("arc", cx, b + rr, rr, 0, 360), ("line", [(l, b + rr), (l, yt)]), ("arc", cx, yt, R, 30, 180)]
    if ch == "9":
        return [_rot180(p, W) for p in _g("6", W, h)]
    if ch == "7":
        return [("line", [(l, t), (r, t), (l + 0.12 * (r - l), b)])]
    if ch == "8":
        r_u = min(R * 0.86, 0.5 * (t - 0.55))
        r_l = min(R, 0.5 * (0.55 - b) + 0.01)
        return [("arc", c, t - r_u, r_u, 0, 360), ("arc", c, b + r_l, r_l, 0, 360)]
    if ch == "A":
        return [("line", [(l, b), (c, t), (r, b)]), ("line", [(l + 0.3 * (c - l), b + 0.3), (r - 0.3 * (r - c), b + 0.3)])]
    if ch in "BPR":
        ru = 0.5 * (t - m)
        out: List[Prim] = [("line", [(l, b), (l, t), (r - ru, t)]), ("arc", r - ru, t - ru, ru, -90, 90),
                           ("line", [(r - ru, m), (l, m)])]
        if ch == "B":
            rl = 0.5 * (m - b)
            out += [("line", [(r - rl, m), (l, m)]), ("arc", r - rl, b + rl, rl, -90, 90), ("line", [(r - rl, b), (l, b)])]
        if ch == "R":
            out += [("line", [(c, m), (r, b)])]
        return out
    if ch == "E":
        return [("line", [(r, t), (l, t), (l, b), (r, b)]), ("line", [(l, m), (r - 0.1, m)])]
    if ch == "F":
        return [("line", [(r, t), (l, t), (l, b)]), ("line", [(l, m), (r - 0.1, m)])]
    if ch == "H":
        return [("line", [(l, b), (l, t)]), ("line", [(r, b), (r, t)]), ("line", [(l, m), (r, m)])]
    if ch == "K":
        return [("line", [(l, b), (l, t)]), ("line", [(r, t), (l + 0.02, 0.42)]), ("line", [(l + 0.3 * (r - l), 0.55), (r, b)])]
    if ch == "L":
        return [("line", [(l, t), (l, b), (r, b)])]
    if ch == "M":
        return [("line", [(l, b), (l, t), (c, 0.3), (r, t), (r, b)])]
    if ch == "N":
        return [("line", [(l, b), (l, t), (r, b), (r, t)])]
    if ch == "S":
        ru, rl = min(R, 0.5 * (t - 0.52)), min(R, 0.5 * (0.52 - b))
        return [("arc", cx, t - ru, ru, 15, 270), ("arc", cx, b + rl, rl, 195, 450)]
    if ch == "T":
        return [("line", [(l, t), (r, t)]), ("line", [(c, t), (c, b)])]
    if ch == "V":
        return [("line", [(l, t), (c, b), (r, t)])]
    if ch == "W":
        return [("line", [(l, t), (l + 0.27 * (r - l), b), (c, 0.62), (r - 0.27 * (r - l), b), (r, t)])]
    if ch == "X":
        return [("line", [(l, t), (r, b)]), ("line", [(r, t), (l, b)])]
    if ch == "Y":
        return [("line", [(l, t), (c, 0.45), (r, t)]), ("line", [(c, 0.45), (c, b)])]
    if ch == "Z":
        return [("line", [(l, t), (r, t), (l, b), (r, b)])]
    raise KeyError(f"no glyph for {ch!r}")


def _rot180(p: Prim, W: float) -> Prim:
    if p[0] == "line":
        return ("line", [(W - x, 1.0 - y) for x, y in p[1]])
    _, cx, cy, r, a0, a1 = p
    return ("arc", W - cx, 1.0 - cy, r, a0 + 180, a1 + 180)


def glyph_primitives(ch: str, stroke: float, width: Optional[float] = None) -> Tuple[float, List[Prim]]:
    """(box width, centrelines) of ``ch`` for a stroke of ``stroke`` (fraction of the height)."""
    W = WIDTH[ch] if width is None else width
    hw = 0.5 * stroke
    prims = []
    for p in _g(ch, W, hw):
        if p[0] == "line":
            if len(p[1]) < 2:
                continue
            pts = [tuple(q) for q in p[1]]
            # A stroke that ends on the baseline or the cap line (a stem, a leg) runs through it:
            # extended past it and cut there by the coverage's clip (a font's horizontal cut),
            # so that the ink spans exactly the character height.
            for end, nb in ((0, 1), (-1, -2)):
                (x, y), (xn, yn) = pts[end], pts[nb]
                dx, dy = x - xn, y - yn
                L = math.hypot(dx, dy)
                if L > 0 and abs(dy) / L > 1e-6 and (abs(y - hw) < 1e-9 or abs(y - (1 - hw)) < 1e-9):
                    k = 2.0 * hw / (abs(dy) / L)
                    pts[end] = (x + dx / L * k, y + dy / L * k)
            p = ("line", pts)
        prims.append(p)
    return W, prims


GLYPHS = tuple(sorted(WIDTH))


def _coverage_line(px, py, pts, hw, pix):
    """Coverage of a stroked polyline: flat ends, round joins."""
    cov = np.zeros(px.shape)
    for k, ((x0, y0), (x1, y1)) in enumerate(zip(pts[:-1], pts[1:])):
        dx, dy = x1 - x0, y1 - y0
        L = math.hypot(dx, dy)
        if L < 1e-12:
            continue
        ux, uy = dx / L, dy / L
        u = (px - x0) * ux + (py - y0) * uy
        v = -(px - x0) * uy + (py - y0) * ux
        # Signed distance to the box [0, L] x [-hw, hw] (flat ends).
        qx, qy = np.abs(u - 0.5 * L) - 0.5 * L, np.abs(v) - hw
        sd = np.hypot(np.maximum(qx, 0), np.maximum(qy, 0)) + np.minimum(np.maximum(qx, qy), 0.0)
        cov = np.maximum(cov, np.clip(0.5 - sd / pix, 0.0, 1.0))
        if 0 < k:  # round join at the segment's start (an inner vertex)
            sd = np.hypot(px - x0, py - y0) - hw
            cov = np.maximum(cov, np.clip(0.5 - sd / pix, 0.0, 1.0))
    return cov


def _coverage_arc(px, py, cx, cy, r, a0, a1, hw, pix):
    """Coverage of a stroked circular arc (counter-clockwise a0 -> a1 degrees), flat ends."""
    ang = np.degrees(np.arctan2(py - cy, px - cx))
    span = (a1 - a0) % 360.0 if (a1 - a0) % 360.0 > 1e-9 else 360.0
    if a1 - a0 >= 360.0:
        span = 360.0
    rel = (ang - a0) % 360.0
    rho = np.hypot(px - cx, py - cy)
    inside = rel <= span
    sd_ring = np.abs(rho - r) - hw
    sd = np.where(inside, sd_ring, np.inf)
    if span < 360.0:
        for a, sgn in ((a0, -1.0), (a1, 1.0)):
            ex, ey = cx + r * math.cos(math.radians(a)), cy + r * math.sin(math.radians(a))
            # Tangent at the end (pointing out of the arc) and the radial direction.
            tx, ty = -math.sin(math.radians(a)) * sgn, math.cos(math.radians(a)) * sgn
            u = (px - ex) * tx + (py - ey) * ty      # beyond the end: u > 0
            v = (px - ex) * math.cos(math.radians(a)) + (py - ey) * math.sin(math.radians(a))
            qx, qy = u, np.abs(v) - hw
            sd_end = np.hypot(np.maximum(qx, 0), np.maximum(qy, 0)) + np.minimum(np.maximum(qx, qy), 0.0)
            sd = np.where(~inside, np.minimum(sd, np.where(u > -hw, sd_end, np.inf)), sd)
    return np.clip(0.5 - sd / pix, 0.0, 1.0)


def glyph_coverage(ch: str, height_px: float, stroke_px: float, width_px: Optional[float] = None,
                   pad: int = 2) -> Tuple[np.ndarray, Tuple[float, float]]:
    """Anti-aliased coverage of ``ch`` with a cap height of ``height_px`` pixels and a stroke of
    ``stroke_px`` (``width_px``: the box's width, default the glyph's proportion). Returns (H x W
    array, rows top to bottom with ``pad`` pixels around the box; the box's (x, y) offset in it)."""
    s = stroke_px / height_px
    W, prims = glyph_primitives(ch, s, None if width_px is None else width_px / height_px)
    Wpx = W * height_px
    h_img, w_img = int(math.ceil(height_px)) + 2 * pad, int(math.ceil(Wpx)) + 2 * pad
    ys, xs = np.mgrid[0:h_img, 0:w_img].astype(np.float64)
    # Pixel centres in glyph units (y up from the baseline).
    px = (xs + 0.5 - pad) / height_px
    py = (height_px - (ys + 0.5 - pad)) / height_px
    pix = 1.0 / height_px
    hw = 0.5 * s
    cov = np.zeros((h_img, w_img))
    ends: List[Tuple[float, float]] = []
    for p in prims:
        if p[0] == "line":
            cov = np.maximum(cov, _coverage_line(px, py, p[1], hw, pix))
            ends += [p[1][0], p[1][-1]]
        else:
            cov = np.maximum(cov, _coverage_arc(px, py, *p[1:], hw, pix))
            _, cx, cy, r, a0, a1 = p
            if a1 - a0 < 360:
                ends += [(cx + r * math.cos(math.radians(a)), cy + r * math.sin(math.radians(a))) for a in (a0, a1)]
    # Where two strokes meet end to end (a bowl and its stem), a round join: no notch.
    for i, (x, y) in enumerate(ends):
        if any(math.hypot(x - u, y - v) < 1e-3 for j, (u, v) in enumerate(ends) if j != i):
            cov = np.maximum(cov, np.clip(0.5 - (np.hypot(px - x, py - y) - hw) / pix, 0.0, 1.0))
    # The baseline and the cap line cut what runs through them.
    cov *= np.clip(py / pix + 0.5, 0.0, 1.0) * np.clip((1.0 - py) / pix + 0.5, 0.0, 1.0)
    return cov.astype(np.float32), (float(pad), float(pad))
