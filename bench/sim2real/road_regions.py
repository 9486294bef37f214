"""Placement regions per frame for the side-facing highway camera: where the asphalt lies.

The camera looks sideways from a car driving along multi-lane roads, so every road in its
frames is a horizontal band below the horizon (near lanes at the bottom, a grass or concrete
median, far lanes just below the horizon, a verge). Which bands are road changes from frame to
frame, so the placement region is computed per frame from its pixels:

1. colour per cell: the frame averaged over `cell` x `cell` pixel cells (lane markings, cracks
   and JPEG noise averaged away);
2. asphalt = blue-grey: blue at least the largest of red and green less `max_warm` levels
   (in these dusk frames the asphalt reflects the blue sky: (47, 68, 94), (60, 74, 83); grass
   and dry verge have B below G or R: (59, 67, 53), (128, 118, 104) is a warm concrete kerb),
   saturation ((max - min) / max) below `max_saturation` (blue signs), neither black (shadows
   under trees) nor white, and below the horizon (`horizon` + `margin` rows);
3. cleaned: a binary closing over 3 x 3 cells (bridges lane markings and strips up to two cells
   tall: a kerb, a thin median), an opening (drops specks), holes filled,
   components smaller than `min_area` of the frame dropped;
4. polygons: each component becomes one band polygon, its top and bottom edge sampled every
   `step` columns (the longest run of the component in that column; the bands of this camera
   have one run per column).

`road_mask(rgb, horizon)` gives the cleaned mask, `mask_polygons(mask)` its polygons,
`road_region(path, horizon)` both steps from a file, `polygon_mask(polygons, size)` rasterises
polygons again (as synthgen's placement reads them) and `car_hits(boxes, polygons, size)` counts
the boxes whose bottom-centre lies in the region.

Pure numpy, Pillow and scipy.ndimage. Deterministic: no randomness anywhere.
"""
from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw
from scipy import ndimage

from synthgen import SynthgenError

# The defaults, chosen on the car-free frames by looking at overlays (docs/sim2real.md) and
# measured on the frames with cars (road_region_car_hits).
CELL = 4
MAX_SATURATION = 0.72
MAX_WARM = 3.0         # 8-bit levels: G - B or R - B above this is grass, verge or kerb
MIN_VALUE = 25.0       # darker cells are shadows under trees, not road
MAX_VALUE = 215.0      # brighter cells are concrete kerbs and sidewalks or sky
MARGIN = 3             # rows below the horizon where the region starts
MIN_AREA = 0.01        # of the frame
STEP = 8               # polygon vertices every STEP columns
MAX_HOLE_WIDTH = 160   # pixels: holes in the road up to this wide are filled (a car, its shadow)


def road_mask(rgb, horizon, *, cell=CELL, max_saturation=MAX_SATURATION, max_warm=MAX_WARM,
              min_value=MIN_VALUE, max_value=MAX_VALUE, margin=MARGIN, min_area=MIN_AREA,
              max_hole_width=MAX_HOLE_WIDTH):
    """Boolean H x W mask of the asphalt of an H x W x 3 8-bit frame (see the module's steps).
    `horizon`: the image row of the horizon (pixels)."""
    a = np.asarray(rgb, dtype=np.float64)
    if a.ndim != 3 or a.shape[2] < 3:
        raise SynthgenError(f"road_mask: an H x W x 3 image expected, got shape {a.shape}")
    a = a[..., :3]
    h, w = a.shape[:2]
    gh, gw = -(-h // cell), -(-w // cell)
    # NOTE: cells at the right and bottom border are padded by edge replication, so every
    # cell averages cell x cell values and the mask is upsampled back by repetition.
    pad = np.pad(a, ((0, gh * cell - h), (0, gw * cell - w), (0, 0)), mode="edge")
    c = pad.reshape(gh, cell, gw, cell, 3).mean(axis=(1, 3))
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    mx, mn = c.max(axis=2), c.min(axis=2)
    sat = (mx - mn) / np.maximum(mx, 1e-6)
    ok = (sat < max_saturation) & (np.maximum(r, g) - b <= max_warm)
    ok &= (mx >= min_value) & (mx <= max_value)
    rows = (np.arange(gh) * cell)[:, None]            # a cell's top row
    ok &= rows >= horizon + margin
    # NOTE: closed and opened with the border cells replicated outward, so that the image's
    # border neither erodes a road reaching it nor grows one.
    ok = np.pad(ok, 2, mode="edge")
    ok = ndimage.binary_closing(ok, structure=np.ones((3, 3)))
    ok = ndimage.binary_opening(ok, structure=np.ones((2, 2)))[2:-2, 2:-2]
    # Holes up to a car's size (a car's shadow, a manhole) are road; longer ones (a median
    # strip between two carriageways) are not.
    holes, nh = ndimage.label(ndimage.binary_fill_holes(ok) & ~ok)
    for k, sl in enumerate(ndimage.find_objects(holes), start=1):
        if sl is not None and (sl[1].stop - sl[1].start) * cell <= max_hole_width:
            ok[sl] |= holes[sl] == k
    ok &= rows >= horizon + margin                    # the closing may grow above it
    lab, n = ndimage.label(ok)
    if n:
        sizes = ndimage.sum(ok, lab, index=np.arange(1, n + 1)) * cell * cell
        keep = np.zeros(n + 1, bool)
        keep[1:] = sizes >= min_area * h * w
        ok = keep[lab]
    full = np.repeat(np.repeat(ok, cell, axis=0), cell, axis=1)[:h, :w]
    return full


def mask_polygons(mask, *, step=STEP):
    """Band polygons ([[u, v], ...], pixels) of a boolean mask: one per connected component,
    its top and bottom edge sampled every `step` columns (and at its last column)."""
    mask = np.asarray(mask, bool)
    h, w = mask.shape
    lab, n = ndimage.label(mask)
    polys = []
    for k in range(1, n + 1):
        comp = lab == k
        cols = np.nonzero(comp.any(axis=0))[0]
        us = list(range(int(cols[0]), int(cols[-1]) + 1, step))
        if us[-1] != cols[-1]:
            us.append(int(cols[-1]))
        top, bot, uu = [], [], []
        for u in us:
            rows = np.nonzero(comp[:, u])[0]
            if len(rows) == 0:
                continue
            # the longest run of the component in this column
            breaks = np.nonzero(np.diff(rows) > 1)[0]
            starts = np.r_[0, breaks + 1]
            ends = np.r_[breaks, len(rows) - 1]
            i = int(np.argmax(ends - starts))
            top.append(int(rows[starts[i]]))
            bot.append(int(rows[ends[i]]) + 1)
            uu.append(u)
        if len(uu) < 2:
            continue
        uu[-1] = uu[-1] + 1                            # the last column's right edge
        poly = [[u, t] for u, t in zip(uu, top)] + [[u, b] for u, b in zip(uu[::-1], bot[::-1])]
        polys.append(poly)
    return polys


def road_region(path, horizon, **kw):
    """(polygons, mask) of the photo at `path` (module docstring); `kw` as road_mask."""
    with Image.open(path) as im:
        rgb = np.asarray(im.convert("RGB"))
    step = kw.pop("step", STEP)
    mask = road_mask(rgb, horizon, **kw)
    return mask_polygons(mask, step=step), mask


def polygon_mask(polygons, size):
    """Boolean mask (height x width) of polygons rasterised over an image of `size` = (w, h)."""
    im = Image.new("L", tuple(size), 0)
    d = ImageDraw.Draw(im)
    for p in polygons:
        d.polygon([tuple(map(float, q)) for q in p], fill=1)
    return np.asarray(im, bool)


def car_hits(boxes, polygons, size, *, tolerance=2):
    """Number of boxes [x0, y0, x1, y1] whose bottom-centre lies in the region (within
    `tolerance` pixels: the box's bottom edge is the wheels' lowest pixel, on the region's edge
    for a car on the outer lane)."""
    m = polygon_mask(polygons, size)
    if tolerance:
        m = ndimage.binary_dilation(m, iterations=tolerance)
    w, h = size
    hits = 0
    for x0, y0, x1, y1 in boxes:
        u = min(max(int((x0 + x1) / 2), 0), w - 1)
        v = min(max(int(y1) - 1, 0), h - 1)
        hits += bool(m[v, u])
    return hits
