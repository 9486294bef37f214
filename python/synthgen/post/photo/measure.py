"""Measurements of a camera's look on an image: its noise and its sharpness, as
:mod:`synthgen.post.photo.camera_match` estimates them on a photo and checks them on the
inserted objects (pure functions on arrays; images in [0, 1], the space they are measured in).

* :func:`fit_noise` -- the photo's signal-dependent noise, sigma^2(y) = a y + b (Foi et al. 2008);
* :func:`noise_sigma` -- one region's noise (robust second differences);
* :func:`flat_mask` -- where a render is flat (albedo and normal), so what varies is noise;
* :func:`sharpness` -- gradient / contrast of the strong step edges;
* :func:`ring_statistics` -- an inserted object's noise and the sharpness around it against the photo's;
* :func:`dilate` -- a mask grown by some pixels.
"""
from __future__ import annotations

import functools
import math
from typing import Any, Dict, Optional, Tuple

import numpy as np

__all__ = ["fit_noise", "noise_sigma", "flat_mask", "sharpness", "ring_statistics", "srgb", "linear", "dilate"]

_MAD = 1.4826  # NOTE: sigma = 1.4826 MAD for a normal distribution


def srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 encoding of linear values (clamped to [0, 1])."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055).astype(np.float32)


def linear(e: np.ndarray) -> np.ndarray:
    e = np.clip(e, 0.0, 1.0)
    return np.where(e <= 0.04045, e / 12.92, np.power((e + 0.055) / 1.055, 2.4)).astype(np.float32)


def _grey(img: np.ndarray) -> np.ndarray:
    return img.mean(axis=2) if img.ndim == 3 else img


def _details(z: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(local mean, detail along x, detail along y) of a grey image: the details are the
    normalized second differences (z[-1] - 2 z[0] + z[1]) / sqrt(6), whose variance is the
    noise's for i.i.d. noise on a locally linear signal; the mean is over the 5 pixels used."""
    dx = (z[1:-1, :-2] - 2.0 * z[1:-1, 1:-1] + z[1:-1, 2:]) / math.sqrt(6.0)
    dy = (z[:-2, 1:-1] - 2.0 * z[1:-1, 1:-1] + z[2:, 1:-1]) / math.sqrt(6.0)
    mean = (z[:-2, 1:-1] + z[2:, 1:-1] + z[1:-1, :-2] + z[1:-1, 2:] + z[1:-1, 1:-1]) / 5.0
    return mean, dx, dy


def _clipped_sigma(d: np.ndarray) -> float:
    """Noise sigma of details ``d``: the root mean square of those within 3 sigma, iterated.

    NOTE: the median absolute deviation (1.4826 MAD, Donoho) is the usual robust estimate, but
    on 8-bit images with a noise of about one code value the details sit on a lattice and the
    median jumps by whole steps (1 / (255 sqrt 6) = 0.0016 at a time: ratios 0.5 or 1.5 where
    the truth is 1). The clipped RMS is continuous in the data and, like the MAD, ignores edges
    (beyond 3 sigma); E[d^2 | |d| < 3 sigma] = 0.97334 sigma^2 for normal d (truncated normal
    variance). Started from the larger of the MAD and the 80th percentile (1.2816 sigma), so that
    a lattice's zero median does not clip everything."""
    a = np.abs(np.asarray(d, np.float64)).ravel()
    if a.size == 0:
        return float("nan")
    s = max(_MAD * float(np.median(a)), float(np.quantile(a, 0.8)) / 1.2816)
    if s <= 0.0:
        return 0.0
    for _ in range(4):
        sel = a[a <= 3.0 * s]
        if sel.size == 0:
            break
        s_new = math.sqrt(float(np.mean(sel * sel)) / 0.97334)
        if abs(s_new - s) <= 1e-4 * s:
            s = s_new
            break
        s = s_new
    return s


def _robust_sigma(dx: np.ndarray, dy: np.ndarray) -> float:
    """The smaller of the two directions' estimates (texture along one direction spoils only the
    other)."""
    return min(_clipped_sigma(dx), _clipped_sigma(dy))


def _block_details(z: np.ndarray, mask: Optional[np.ndarray], block: int) -> Tuple[np.ndarray, np.ndarray]:
    """(local mean, detail variance) of the ``block`` x ``block`` tiles of the details grid of
    :func:`_details` that lie wholly in ``mask``: the variance is the smaller of the mean squared
    x and y details (texture along one direction spoils only the other)."""
    mean, dx, dy = _details(z)
    m = np.ones(mean.shape, bool) if mask is None else np.asarray(mask, bool)[1:-1, 1:-1]
    by, bx = mean.shape[0] // block, mean.shape[1] // block

    def tiles(a: np.ndarray) -> np.ndarray:
        return a[:by * block, :bx * block].reshape(by, block, bx, block).swapaxes(1, 2).reshape(by * bx, -1)

    ok = tiles(m).all(1)
    v = np.minimum((tiles(dx) ** 2).mean(1), (tiles(dy) ** 2).mean(1))
    return tiles(mean).mean(1)[ok], v[ok]


@functools.lru_cache(maxsize=None)
def _flat_quantile(block: int, q: float) -> float:
    """The ``q`` quantile of :func:`_block_details`' variance for i.i.d. unit normal noise (by
    simulation, fixed seed: 20000 tiles; the statistic's law is awkward in closed form: the
    details of neighbouring pixels are correlated and the x / y minimum is taken)."""
    z = np.random.default_rng(20261208).standard_normal((block * 200 + 2, block * 100 + 2))
    _, v = _block_details(z, None, block)
    return float(np.quantile(v, q))


def fit_noise(img: np.ndarray, mask: Optional[np.ndarray] = None, bins: int = 16, block: int = 8,
              quantile: float = 0.1, min_blocks: int = 20) -> Dict[str, Any]:
    """Fits sigma^2(y) = a y + b to the noise of ``img`` (grey or RGB, values in [0, 1], the space
    it is to be matched in) over ``mask`` (default: everywhere).

    NOTE: noise is measured where the image is flattest, since texture finer than a few pixels
    (foliage, asphalt, gravel) is indistinguishable from noise pixel by pixel, and a photo may
    hold far more of it than flat area: a robust estimate over all pixels (which takes edges and
    texture for outliers only while they are rare) measured a dusk road photo's foliage as noise
    15 times the road's (0.0307 against 0.0021, sRGB). The image is cut into ``block`` x ``block`` tiles of second-difference
    details (:func:`_details`); per intensity bin (quantiles of the tiles' mean), the ``quantile``
    of the tiles' detail variance, divided by the same quantile for pure unit noise
    (:func:`_flat_quantile`), estimates the noise variance from the flattest tenth of the bin
    (the weak-texture patch idea of Liu, Tanaka & Okutomi 2013, "Single-image noise level
    estimation for blind denoising", with a quantile in place of their iterative selection).
    a, b by weighted least squares, clipped at 0 (Foi et al. 2008 fit the same model on wavelet
    details with clipping-aware maximum likelihood)."""
    z = _grey(np.asarray(img, np.float64))
    y, v = _block_details(z, mask, block)
    # Saturated tiles carry no noise.
    keep = (y > 0.02) & (y < 0.98)
    y, v = y[keep], v[keep]
    if y.size < min_blocks:
        return {"a": 0.0, "b": 0.0, "bins": [], "blocks": int(y.size)}
    nb = max(1, min(bins, y.size // min_blocks))
    edges = np.quantile(y, np.linspace(0.0, 1.0, nb + 1))
    c = _flat_quantile(block, quantile)
    ys, vs, ns = [], [], []
    for i in range(nb):
        sel = (y >= edges[i]) & (y <= edges[i + 1])
        if sel.sum() < min_blocks:
            continue
        ys.append(float(np.mean(y[sel])))
        vs.append(float(np.quantile(v[sel], quantile)) / c)
        ns.append(int(sel.sum()))
    if not ys:
        return {"a": 0.0, "b": 0.0, "bins": [], "blocks": int(y.size)}
    ys_, vs_, ns_ = np.array(ys), np.array(vs), np.array(ns, float)
    # NOTE: a bin with no flat tile at all (dark foliage) reads its texture as noise: texture
    # only ever adds variance, so the fit is of the lower envelope. Bins more than 1.5 x the
    # fit's variance are dropped and the rest refitted, until the kept set settles (a bin of
    # pure noise is that far off by chance about never: its variance is estimated to ~10 %).
    keep = np.ones(len(ys_), bool)
    for _ in range(8):
        a, b = _fit_line(ys_[keep], vs_[keep], ns_[keep])
        model = np.maximum(a * ys_ + b, 1e-12)
        new_keep = vs_ <= 1.5 * model
        if new_keep.sum() < min(2, len(ys_)):
            new_keep = np.zeros(len(ys_), bool)
            new_keep[np.argsort(vs_ / model, kind="stable")[:2]] = True
        if np.array_equal(new_keep, keep):
            break
        keep = new_keep
    return {"a": float(a), "b": float(b), "bins": [[u, v] for u, v in zip(ys, vs)], "blocks": int(y.size)}


def _fit_line(ys: np.ndarray, vs: np.ndarray, ns: np.ndarray) -> Tuple[float, float]:
    """a, b of v = a y + b by weighted least squares, clipped at 0.

    NOTE: a variance estimated from n samples has a standard deviation ~ v sqrt(2 / n): weights
    sqrt(n) / v make the residuals comparable (low bins pin b down, high ones a)."""
    if len(ys) < 2:
        return 0.0, float(vs[0])
    w = np.sqrt(ns) / np.maximum(vs, 1e-12)
    A = np.stack([ys, np.ones_like(ys)], 1) * w[:, None]
    a, b = np.linalg.lstsq(A, vs * w, rcond=None)[0]
    if a < 0:
        a, b = 0.0, float(np.average(vs, weights=w))
    if b < 0:
        b = 0.0
        a = float(np.sum(w * w * ys * vs) / max(np.sum(w * w * ys * ys), 1e-30))
    return float(a), float(b)


def noise_sigma(img: np.ndarray, mask: np.ndarray) -> Tuple[float, float]:
    """(noise sigma, mean level) of ``img`` over ``mask``: the robust second-difference estimate
    (as :func:`fit_noise`, one bin)."""
    z = _grey(np.asarray(img, np.float64))
    mean, dx, dy = _details(z)
    m = np.asarray(mask, bool)[1:-1, 1:-1]
    if m.sum() < 20:
        return float("nan"), float("nan")
    return _robust_sigma(dx[m], dy[m]), float(mean[m].mean())


def flat_mask(mask: np.ndarray, albedo: Optional[np.ndarray] = None, normal: Optional[np.ndarray] = None,
              min_pixels: int = 50) -> np.ndarray:
    """The pixels of ``mask`` whose 3 x 3 neighbourhood is in the mask with the same albedo and
    normal (within 0.01 and 0.02): where a render should be flat, so that what varies there is
    noise, not texture or shape (the photo's noise is measured the same way: robustly, on flat
    regions). ``mask`` itself when fewer than ``min_pixels`` remain."""
    m = np.asarray(mask, bool)
    ys, xs = np.nonzero(m)
    if len(ys) == 0:
        return m
    # Only the mask's box (and a pixel around it) matters.
    y0, y1 = max(0, ys.min() - 1), min(m.shape[0], ys.max() + 2)
    x0, x1 = max(0, xs.min() - 1), min(m.shape[1], xs.max() + 2)
    mb = m[y0:y1, x0:x1]
    flat = mb.copy()
    for a, tol in ((albedo, 0.01), (normal, 0.02)):
        if a is None:
            continue
        a = np.asarray(a[y0:y1, x0:x1], np.float32)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                b = np.roll(a, (dy, dx), axis=(0, 1))
                flat &= np.roll(mb, (dy, dx), axis=(0, 1)) & (np.abs(b - a).max(axis=2) < tol)
    if flat.sum() < min_pixels:
        return m
    out = np.zeros(m.shape, bool)
    out[y0:y1, x0:x1] = flat
    return out


def sharpness(img: np.ndarray, mask: Optional[np.ndarray] = None) -> float:
    """Sharpness of the strong edges in ``mask``: the mean of (steepest gradient) / (the edge's
    contrast), ~ 1 / (sqrt(2 pi) sigma) for a step blurred by a Gaussian of sigma pixels.

    NOTE: an edge pixel is where the central-difference gradient along x (or y) is the largest of
    its 3 neighbours along that axis; its contrast is the difference of 3-pixel means 3..5 pixels
    to either side, and edges count when that contrast is over 8 noise sigmas (the noise is the
    MAD estimate of :func:`noise_sigma`): so noise barely moves the measure, unlike
    Laplacian-based ones."""
    z = _grey(np.asarray(img, np.float64))
    h, w = z.shape
    if h < 12 or w < 12:
        return float("nan")
    m = np.ones((h, w), bool) if mask is None else np.asarray(mask, bool)
    _, dx, dy = _details(z)
    sig = _robust_sigma(dx, dy)
    vals = []
    for axis in (1, 0):
        a = z if axis == 1 else z.T
        mm = m if axis == 1 else m.T
        g = np.zeros_like(a)
        g[:, 1:-1] = 0.5 * (a[:, 2:] - a[:, :-2])
        ag = np.abs(g)
        peak = np.zeros_like(a, bool)
        peak[:, 6:-6] = (ag[:, 6:-6] >= ag[:, 5:-7]) & (ag[:, 6:-6] > ag[:, 7:-5])
        # 3-pixel means at x-5 .. x-3 and x+3 .. x+5 (for x = 6 .. w-7), and how flat each side is.
        lo_mean = (a[:, 1:-11] + a[:, 2:-10] + a[:, 3:-9]) / 3.0
        hi_mean = (a[:, 9:-3] + a[:, 10:-2] + a[:, 11:-1]) / 3.0
        c = np.zeros_like(a)
        flat = np.full_like(a, np.inf)
        c[:, 6:-6] = np.abs(hi_mean - lo_mean)
        flat[:, 6:-6] = np.maximum(np.abs(a[:, 3:-9] - a[:, 1:-11]), np.abs(a[:, 11:-1] - a[:, 9:-3]))
        # A step, not a ramp: flat on both sides (a ramp's sides change by a quarter of its contrast).
        sel = peak & mm & (c > max(8.0 * sig, 1e-3)) & (flat < 0.12 * c + 3.0 * sig)
        if sel.any():
            vals.append(ag[sel] / c[sel])
    if not vals:
        return float("nan")
    v = np.concatenate(vals)
    return float(np.mean(v)) if v.size >= 5 else float("nan")


def dilate(m: np.ndarray, steps: int) -> np.ndarray:
    """``m`` grown by ``steps`` pixels (4-neighbourhood dilation, repeated)."""
    grown = np.asarray(m, bool).copy()
    for _ in range(int(steps)):
        g = grown.copy()
        g[1:] |= grown[:-1]
        g[:-1] |= grown[1:]
        g[:, 1:] |= grown[:, :-1]
        g[:, :-1] |= grown[:, 1:]
        grown = g
    return grown


def _inner(m: np.ndarray) -> np.ndarray:
    """``m`` less its border pixels (4-neighbourhood erosion)."""
    inner = m.copy()
    inner[1:] &= m[:-1]
    inner[:-1] &= m[1:]
    inner[:, 1:] &= m[:, :-1]
    inner[:, :-1] &= m[:, 1:]
    return inner


def ring_statistics(img_srgb: np.ndarray, object_mask: np.ndarray, box, noise: Dict[str, Any]) -> Dict[str, float]:
    """For one inserted object: its noise sigma (inside its mask, one pixel in from the mask's
    edge: with :func:`flat_mask`, two pixels from any edge, clear of the JPEG's ringing)
    against the photo's fitted sigma at the same level, and the sharpness of a ring around it
    (its box grown by half its size: the object's edges and the photo around) against the
    photo's own sharpness over the image."""
    m = np.asarray(object_mask, bool)
    s, level = noise_sigma(img_srgb, _inner(m))
    expected = math.sqrt(max(noise["a"] * level + noise["b"], 0.0)) if math.isfinite(level) else float("nan")
    h, w = m.shape
    x0, y0, x1, y1 = box
    bw, bh = x1 - x0, y1 - y0
    ring = np.zeros((h, w), bool)
    ring[max(0, int(y0 - bh / 2)):min(h, int(y1 + bh / 2)), max(0, int(x0 - bw / 2)):min(w, int(x1 + bw / 2))] = True
    return {"noise": s, "photo_noise": expected, "noise_ratio": s / expected if expected > 0 else float("nan"),
            "level": level, "ring_sharpness": sharpness(img_srgb, ring)}
