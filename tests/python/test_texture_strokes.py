"""The "strokes" texture (scratches as strokes): measured on a plane, directional strokes have
a clearly peaked orientation histogram around their direction, strokes in every direction do
not, and swirl marks are arcs (each mark fits a circle of the radii asked for), which straight
strokes are not."""
import math
from collections import deque

import numpy as np
import pytest

from synthgen._core import Scene

N, CELLS = 384, 6.0  # samples across, cells across (64 samples per cell)


def _values(params, seed=3):
    s = Scene()
    ys, xs = np.mgrid[0:N, 0:N] / N * CELLS
    pts = np.stack([xs.ravel(), ys.ravel(), np.zeros(N * N)], 1).astype(np.float32)
    t = s.add_texture("strokes", dict(params, seed=seed))
    return s.texture_values(t, pts)[:, 0].reshape(N, N)


def _orientations(v):
    """Line orientation (degrees in [0, 180), x to y) at the stroke pixels, from the smoothed
    structure tensor (the line runs across the gradient)."""
    gy, gx = np.gradient(v)
    k = np.ones(5) / 5
    sm = lambda a: np.apply_along_axis(lambda r: np.convolve(r, k, "same"), 0,  # noqa: E731
                                       np.apply_along_axis(lambda r: np.convolve(r, k, "same"), 1, a))
    jxx, jyy, jxy = sm(gx * gx), sm(gy * gy), sm(gx * gy)
    grad_angle = 0.5 * np.arctan2(2 * jxy, jxx - jyy)
    line = (np.degrees(grad_angle) + 90.0) % 180.0
    sel = v > 0.3
    return line[sel]


def _hist_peak(angles, centre, half=15.0):
    d = np.abs((angles - centre + 90.0) % 180.0 - 90.0)
    return float((d <= half).mean())


def test_directional_strokes_peak_around_their_direction():
    v = _values({"direction": [1.0, 0.3, 0.0], "spread": 8, "density": 3, "width": 0.04})
    expect = math.degrees(math.atan2(0.3, 1.0))
    peak = _hist_peak(_orientations(v), expect)
    iso = _hist_peak(_orientations(_values({"density": 3, "width": 0.04})), expect)
    print(f"\nstrokes within 15 deg of their direction: {peak:.2f} (directional), {iso:.2f} (every direction)")
    assert peak > 0.7 and iso < 0.35


def _components(mask, min_size=40):
    seen = np.zeros(mask.shape, bool)
    out = []
    for y0, x0 in zip(*np.nonzero(mask)):
        if seen[y0, x0]:
            continue
        q, comp = deque([(y0, x0)]), []
        seen[y0, x0] = True
        while q:
            y, x = q.popleft()
            comp.append((y, x))
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    yy, xx = y + dy, x + dx
                    if 0 <= yy < mask.shape[0] and 0 <= xx < mask.shape[1] and mask[yy, xx] and not seen[yy, xx]:
                        seen[yy, xx] = True
                        q.append((yy, xx))
        if len(comp) >= min_size:
            out.append(np.asarray(comp, float))
    return out


def _line_residual(pts):
    """RMS distance (pixels) of points (y, x) from their best-fitting straight line."""
    c = np.cov((pts - pts.mean(0)).T)
    return float(math.sqrt(max(np.linalg.eigvalsh(c)[0], 0.0)))


def _circle_fit(pts):
    """(radius, rms residual) of the algebraic (Kasa) circle fit of points (y, x)."""
    y, x = pts[:, 0], pts[:, 1]
    A = np.c_[2 * x, 2 * y, np.ones(len(x))]
    b = x * x + y * y
    (cx, cy, c), *_ = np.linalg.lstsq(A, b, rcond=None)
    r = math.sqrt(max(c + cx * cx + cy * cy, 0.0))
    return r, float(np.sqrt(np.mean((np.hypot(x - cx, y - cy) - r) ** 2)))


def test_swirl_marks_are_arcs_of_their_radii_and_straight_strokes_are_not():
    per_cell = N / CELLS
    swirl = _components(_values({"mode": "swirl", "density": 1, "width": 0.04, "radius": [0.3, 0.5],
                                 "arc": [90, 150]}) > 0.3)
    straight = _components(_values({"density": 1, "width": 0.04, "length": [0.8, 1.0]}) > 0.3)
    fits = [_circle_fit(c) for c in swirl]
    # An arc: a circle of the radii asked for fits it far better than a straight line. (Marks
    # that cross another merge into one component and fit neither: the shares allow for them.)
    good = [0.25 * per_cell <= r <= 0.55 * per_cell and res < 0.3 * _line_residual(c)
            for (r, res), c in zip(fits, swirl)]
    lines = [_line_residual(c) < 1.0 for c in straight]
    print(f"\nswirl marks that are arcs of 0.3-0.5 cells: {sum(good)}/{len(good)}; straight strokes that are lines "
          f"(within 1 px): {sum(lines)}/{len(lines)}")
    assert len(good) >= 10 and np.mean(good) > 0.7
    assert len(lines) >= 10 and np.mean(lines) > 0.7


def test_same_seed_same_strokes_and_bad_ranges_refused():
    a, b = _values({"density": 2}, seed=7), _values({"density": 2}, seed=7)
    assert np.array_equal(a, b) and not np.array_equal(a, _values({"density": 2}, seed=8))
    s = Scene()
    with pytest.raises(Exception, match="length"):
        s.add_texture("strokes", {"length": [0.5, 3.0]})
    with pytest.raises(Exception, match="radius"):
        s.add_texture("strokes", {"mode": "swirl", "radius": [0.5, 1.5]})


def test_footprints_of_a_cell_or_more_give_the_patterns_mean():
    """Band-limiting: a footprint of at least a cell returns the texture's mean (the pixel integral
    of the pattern), the same everywhere; below half a cell the strokes are drawn; in between the
    value blends from the one to the other."""
    s = Scene()
    rng = np.random.default_rng(5)
    pts = (rng.random((20000, 3)) * [40.0, 40.0, 0.0]).astype(np.float32)  # 1600 cells of a plane z = 0
    t = s.add_texture("strokes", {"mapping": "world", "density": 4, "width": 0.08, "seed": 2})
    fine = s.texture_values(t, pts, world_footprint=0.0)[:, 0]
    mean = float(fine.mean())
    for fp in (1.0, 3.0, 50.0):
        wide = s.texture_values(t, pts, world_footprint=fp)[:, 0]
        assert np.ptp(wide) == 0.0, "one value everywhere"
        assert abs(float(wide[0]) - mean) < 0.1 * mean + 1e-3, (fp, float(wide[0]), mean)
    drawn = s.texture_values(t, pts, world_footprint=0.25)[:, 0]
    assert np.ptp(drawn) > 0.1, "strokes are still drawn below half a cell"
    mid = s.texture_values(t, pts, world_footprint=0.75)[:, 0]
    assert np.ptp(mid) > 0.0 and np.ptp(mid) < np.ptp(drawn), "between: partly blended"
    off = s.add_texture("strokes", {"mapping": "world", "density": 4, "width": 0.08, "seed": 2, "band_limit": False})
    assert np.array_equal(s.texture_values(off, pts, world_footprint=3.0)[:, 0], fine), "band_limit false: unfiltered"
