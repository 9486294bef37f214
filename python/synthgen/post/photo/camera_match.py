"""Camera matching: what a real camera did to the photo, estimated from it and applied to the
inserted render only, so that a detector cannot learn "sharp, clean object = target".

Pure functions (arrays + parameters -> arrays). Photos are gamma-encoded (and often JPEG
compressed): noise and sharpness are measured and matched in the encoded (sRGB) space where
they live; colour and light in linear light.

* :func:`fit_noise` -- the photo's signal-dependent noise, sigma^2(y) = a y + b (Foi et al. 2008,
  "Practical Poissonian-Gaussian noise modeling and fitting for single-image raw-data": a
  Poisson term a y plus a Gaussian floor b), y the local mean;
* :func:`sharpness` and :func:`match_blur` -- a no-reference sharpness (high-frequency energy
  at edges) and the Gaussian blur that gives the render the photo's;
* :func:`vignette`, :func:`chromatic_aberration` -- optional lens effects;
* :func:`jpeg_roundtrip` -- the frame re-encoded as the photo was (its estimated quality);
* :func:`match_camera` -- all of it on a composite, with the parameters for the metadata.
"""
from __future__ import annotations

import math
import os
import tempfile
from typing import Any, Dict, Optional, Tuple

import numpy as np

__all__ = ["fit_noise", "noise_sigma", "sharpness", "gaussian_blur", "match_blur", "vignette",
           "chromatic_aberration", "jpeg_roundtrip", "match_camera", "ring_statistics", "srgb", "linear"]

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


def _robust_sigma(dx: np.ndarray, dy: np.ndarray) -> float:
    """The smaller of the two directions' MAD estimates (texture along one direction spoils
    only the other)."""
    return float(_MAD * min(np.median(np.abs(dx)), np.median(np.abs(dy))))


def fit_noise(img: np.ndarray, mask: Optional[np.ndarray] = None, bins: int = 16) -> Dict[str, Any]:
    """Fits sigma^2(y) = a y + b to the noise of ``img`` (grey or RGB, values in [0, 1], the space
    it is to be matched in) over ``mask`` (default: everywhere).

    NOTE: per intensity bin (quantiles of the local mean y), the noise variance is estimated
    robustly as (1.4826 MAD)^2 of the second-difference details (Donoho's MAD estimator; edges and
    texture are the outliers it ignores), the smaller of the x and y estimates; a, b by weighted
    least squares, clipped at 0 (Foi et al. 2008 fit the same model on wavelet
    details with clipping-aware maximum likelihood)."""
    z = _grey(np.asarray(img, np.float64))
    mean, dx, dy = _details(z)
    m = np.ones(mean.shape, bool) if mask is None else np.asarray(mask, bool)[1:-1, 1:-1]
    # Saturated pixels carry no noise.
    m &= (mean > 0.02) & (mean < 0.98)
    y, rx, ry = mean[m], dx[m], dy[m]
    if y.size < 200:
        return {"a": 0.0, "b": 0.0, "bins": [], "pixels": int(y.size)}
    edges = np.quantile(y, np.linspace(0.0, 1.0, bins + 1))
    ys, vs, ns = [], [], []
    for i in range(bins):
        sel = (y >= edges[i]) & (y <= edges[i + 1])
        if sel.sum() < 50:
            continue
        s = _robust_sigma(rx[sel], ry[sel])
        ys.append(float(np.mean(y[sel])))
        vs.append(float(s * s))
        ns.append(int(sel.sum()))
    # NOTE: a variance estimated from n samples has a standard deviation ~ v sqrt(2 / n): weights
    # sqrt(n) / v make the residuals comparable (low bins pin b down, high ones a).
    ys_, vs_ = np.array(ys), np.array(vs)
    w = np.sqrt(np.array(ns, float)) / np.maximum(vs_, 1e-12)
    A = np.stack([ys_, np.ones_like(ys_)], 1) * w[:, None]
    a, b = np.linalg.lstsq(A, vs_ * w, rcond=None)[0]
    if a < 0:
        a, b = 0.0, float(np.average(vs_, weights=w))
    if b < 0:
        b = 0.0
        a = float(np.sum(w * w * ys_ * vs_) / max(np.sum(w * w * ys_ * ys_), 1e-30))
    return {"a": float(a), "b": float(b), "bins": [[u, v] for u, v in zip(ys, vs)], "pixels": int(y.size)}


def noise_sigma(img: np.ndarray, mask: np.ndarray) -> Tuple[float, float]:
    """(noise sigma, mean level) of ``img`` over ``mask``: the robust second-difference estimate
    (as :func:`fit_noise`, one bin)."""
    z = _grey(np.asarray(img, np.float64))
    mean, dx, dy = _details(z)
    m = np.asarray(mask, bool)[1:-1, 1:-1]
    if m.sum() < 20:
        return float("nan"), float("nan")
    return _robust_sigma(dx[m], dy[m]), float(mean[m].mean())


def gaussian_blur(img: np.ndarray, sigma: float) -> np.ndarray:
    """Separable Gaussian blur (edges extended), per channel."""
    if sigma <= 0.05:
        return np.asarray(img, np.float32)
    r = max(1, int(math.ceil(3.0 * sigma)))
    x = np.arange(-r, r + 1, dtype=np.float64)
    k = np.exp(-0.5 * (x / sigma) ** 2)
    k /= k.sum()
    a = np.asarray(img, np.float64)
    pad = [(r, r), (0, 0)] + [(0, 0)] * (a.ndim - 2)
    t = np.pad(a, pad, mode="edge")
    a = sum(k[i] * t[i:i + a.shape[0]] for i in range(2 * r + 1))
    pad = [(0, 0), (r, r)] + [(0, 0)] * (a.ndim - 2)
    t = np.pad(a, pad, mode="edge")
    a = sum(k[i] * t[:, i:i + a.shape[1]] for i in range(2 * r + 1))
    return a.astype(np.float32)


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


def match_blur(render: np.ndarray, target: float, mask: np.ndarray,
               sigmas: Tuple[float, ...] = tuple(np.round(np.arange(0.0, 3.01, 0.1), 2))) -> float:
    """The Gaussian blur sigma (pixels) whose result has sharpness ``target`` over ``mask`` (the
    smallest sigma that brings it down to the target; 0 when the render is already as soft)."""
    if not math.isfinite(target):
        return 0.0
    prev_s, prev_v = 0.0, sharpness(render, mask)
    if not math.isfinite(prev_v) or prev_v <= target:
        return 0.0
    for s in sigmas[1:]:
        v = sharpness(gaussian_blur(render, s), mask)
        if not math.isfinite(v):
            return prev_s
        if v <= target:
            # Linear interpolation between the last two sigmas.
            return float(prev_s + (s - prev_s) * (prev_v - target) / max(prev_v - v, 1e-12))
        prev_s, prev_v = s, v
    return float(sigmas[-1])


def denoise_objects(img: np.ndarray, inside: np.ndarray, ids: np.ndarray, albedo: Optional[np.ndarray] = None,
                    normal: Optional[np.ndarray] = None, radius: int = 3, sigma_s: float = 2.0,
                    sigma_albedo: float = 0.04, sigma_normal: float = 0.15) -> np.ndarray:
    """The rendered objects' Monte Carlo noise filtered away before the photo's noise is added:
    a joint (cross) bilateral filter over the pixels ``inside`` (wholly covered by one object),
    averaging only pixels of the same instance with a similar albedo and normal, so texture and
    geometric edges stay (Eisemann & Durand 2004, Petschnigg et al. 2004: the guides are
    noise-free feature buffers, as the first-hit labels are here).

    NOTE: weights exp(-d^2 / 2 sigma_s^2) exp(-|da|^2 / 2 sigma_a^2) exp(-|dn|^2 / 2 sigma_n^2) over
    a (2 radius + 1)^2 window; pixels outside ``inside`` are left as they are."""
    out = np.array(img, np.float32)
    ys, xs = np.nonzero(inside)
    if len(ys) == 0:
        return out
    y0, y1 = max(0, ys.min() - radius), min(img.shape[0], ys.max() + radius + 1)
    x0, x1 = max(0, xs.min() - radius), min(img.shape[1], xs.max() + radius + 1)
    src = np.asarray(img[y0:y1, x0:x1], np.float32)
    m = np.asarray(inside[y0:y1, x0:x1], bool)
    idc = np.asarray(ids[y0:y1, x0:x1])
    alb = None if albedo is None else np.asarray(albedo[y0:y1, x0:x1], np.float32)
    nrm = None if normal is None else np.asarray(normal[y0:y1, x0:x1], np.float32)
    h, w = m.shape
    acc = np.zeros((h, w, 3), np.float64)
    wsum = np.zeros((h, w), np.float64)
    pad = ((radius, radius), (radius, radius))

    def padded(a):
        return np.pad(a, pad + ((0, 0),) * (a.ndim - 2), mode="edge")

    ps, pm, pid = padded(src), padded(m), padded(idc)
    pa = None if alb is None else padded(alb)
    pn = None if nrm is None else padded(nrm)
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            sl = (slice(radius + dy, radius + dy + h), slice(radius + dx, radius + dx + w))
            wgt = math.exp(-(dx * dx + dy * dy) / (2.0 * sigma_s * sigma_s)) * (pm[sl] & (pid[sl] == idc) & m)
            wgt = wgt.astype(np.float64)
            if pa is not None:
                wgt *= np.exp(-np.sum((pa[sl] - alb) ** 2, axis=2) / (2.0 * sigma_albedo ** 2))
            if pn is not None:
                wgt *= np.exp(-np.sum((pn[sl] - nrm) ** 2, axis=2) / (2.0 * sigma_normal ** 2))
            acc += wgt[..., None] * ps[sl]
            wsum += wgt
    filt = np.where(wsum[..., None] > 0, acc / np.maximum(wsum, 1e-12)[..., None], src)
    out[y0:y1, x0:x1] = np.where(m[..., None], filt, src).astype(np.float32)
    return out


def vignette(img: np.ndarray, strength: float, cx: float, cy: float, f: float) -> np.ndarray:
    """Natural vignetting: cos^4 of the angle off the optical axis, mixed in by ``strength``
    (1: the full cos^4 law of a thin lens; 0: none)."""
    if strength <= 0:
        return img
    h, w = img.shape[:2]
    ys, xs = np.mgrid[0:h, 0:w]
    r2 = ((xs + 0.5 - cx) ** 2 + (ys + 0.5 - cy) ** 2) / (f * f)
    fall = 1.0 / (1.0 + r2) ** 2  # cos^4(theta), tan^2(theta) = r2
    g = (1.0 - strength) + strength * fall
    return (img * g[..., None]).astype(np.float32)


def chromatic_aberration(img: np.ndarray, shift: float, cx: float, cy: float) -> np.ndarray:
    """Lateral chromatic aberration: red magnified and blue shrunk about the principal point so
    that at the image's corner they are displaced by ``shift`` pixels (bilinear resampling)."""
    if shift == 0:
        return img
    h, w = img.shape[:2]
    rmax = math.hypot(max(cx, w - cx), max(cy, h - cy))
    out = np.array(img, np.float32)
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
    for c, sgn in ((0, 1.0), (2, -1.0)):
        s = 1.0 + sgn * shift / rmax
        u = cx + (xs + 0.5 - cx) / s - 0.5
        v = cy + (ys + 0.5 - cy) / s - 0.5
        u0, v0 = np.clip(np.floor(u).astype(int), 0, w - 1), np.clip(np.floor(v).astype(int), 0, h - 1)
        u1, v1 = np.clip(u0 + 1, 0, w - 1), np.clip(v0 + 1, 0, h - 1)
        fu, fv = np.clip(u - u0, 0, 1), np.clip(v - v0, 0, 1)
        ch = img[..., c]
        out[..., c] = ((1 - fu) * (1 - fv) * ch[v0, u0] + fu * (1 - fv) * ch[v0, u1] + (1 - fu) * fv * ch[v1, u0] +
                       fu * fv * ch[v1, u1])
    return out


def jpeg_roundtrip(img_linear: np.ndarray, quality: float) -> np.ndarray:
    """The image as a JPEG at ``quality`` (1..100, IJG scale; 4:2:0 as cameras write) would give it
    back: sRGB 8-bit encode, compress, decode, linearize."""
    import OpenImageIO as oiio

    q = int(round(min(100.0, max(1.0, quality))))
    enc = np.round(srgb(img_linear) * 255.0).astype(np.uint8)
    h, w = enc.shape[:2]
    fd, path = tempfile.mkstemp(suffix=".jpg", prefix="synthgen-")
    os.close(fd)
    try:
        spec = oiio.ImageSpec(w, h, 3, oiio.UINT8)
        spec.attribute("Compression", f"jpeg:{q}")
        out = oiio.ImageOutput.create(path)
        out.open(path, spec)
        out.write_image(enc)
        out.close()
        dec = oiio.ImageBuf(path).get_pixels(oiio.FLOAT)
    finally:
        os.unlink(path)
    return linear(np.asarray(dec, np.float32).reshape(h, w, 3))


def ring_statistics(img_srgb: np.ndarray, object_mask: np.ndarray, box, noise: Dict[str, Any]) -> Dict[str, float]:
    """For one inserted object: its noise sigma (inside its mask, one pixel in from the edge)
    against the photo's fitted sigma at the same level, and the sharpness of a ring around it
    (its box grown by half its size: the object's edges and the photo around) against the
    photo's own sharpness over the image."""
    m = np.asarray(object_mask, bool)
    inner = m.copy()
    inner[1:] &= m[:-1]
    inner[:-1] &= m[1:]
    inner[:, 1:] &= m[:, :-1]
    inner[:, :-1] &= m[:, 1:]
    s, level = noise_sigma(img_srgb, inner)
    expected = math.sqrt(max(noise["a"] * level + noise["b"], 0.0)) if math.isfinite(level) else float("nan")
    h, w = m.shape
    x0, y0, x1, y1 = box
    bw, bh = x1 - x0, y1 - y0
    ring = np.zeros((h, w), bool)
    ring[max(0, int(y0 - bh / 2)):min(h, int(y1 + bh / 2)), max(0, int(x0 - bw / 2)):min(w, int(x1 + bw / 2))] = True
    return {"noise": s, "photo_noise": expected, "noise_ratio": s / expected if expected > 0 else float("nan"),
            "level": level, "ring_sharpness": sharpness(img_srgb, ring)}


def match_camera(photo: np.ndarray, composite: np.ndarray, influence: np.ndarray, rng: np.random.Generator, *,
                 jpeg_quality: Optional[float] = None, noise: bool = True, blur: bool = True,
                 vignetting: float = 0.0, chromatic: float = 0.0, cx: Optional[float] = None,
                 cy: Optional[float] = None, focal: Optional[float] = None,
                 synthetic: Optional[np.ndarray] = None, ids: Optional[np.ndarray] = None,
                 albedo: Optional[np.ndarray] = None, normal: Optional[np.ndarray] = None,
                 denoise: bool = True) -> Tuple[np.ndarray, Dict[str, Any]]:
    """Applies to the pixels the inserted objects changed (``influence``, H x W bool) what the
    photo's camera did: lens effects (optional), the photo's blur, its noise (in sRGB space,
    only the variance the pixel lacks), then re-encodes the whole frame as the photo's JPEG was.
    ``synthetic``: H x W coverage of the inserted objects (where the render's own, not the
    photo's, values are); with ``ids`` (and the albedo / normal labels as guides), the objects'
    Monte Carlo noise is filtered first (:func:`denoise_objects`). Returns (image, parameters
    for the metadata)."""
    h, w = influence.shape
    cx = w / 2 if cx is None else cx
    cy = h / 2 if cy is None else cy
    focal = max(w, h) if focal is None else focal
    info: Dict[str, Any] = {}
    out = np.array(composite, np.float32)
    grow = influence.copy()
    for _ in range(3):  # the blur and the lens effects spread the objects a little
        g = grow.copy()
        g[1:] |= grow[:-1]
        g[:-1] |= grow[1:]
        g[:, 1:] |= grow[:, :-1]
        g[:, :-1] |= grow[:, 1:]
        grow = g
    if denoise and synthetic is not None and ids is not None and (synthetic > 0.999).any():
        before, _ = noise_sigma(srgb(out), synthetic > 0.999)
        out = denoise_objects(out, synthetic > 0.999, ids, albedo, normal)
        composite = out
        after, _ = noise_sigma(srgb(out), synthetic > 0.999)
        info["denoised"] = {"noise_before": before, "noise_after": after,
                            "filter": "joint bilateral on albedo and normal, 7 x 7"}
    layer = out
    if vignetting > 0:
        layer = vignette(layer, vignetting, cx, cy, focal)
        info["vignetting"] = vignetting
    if chromatic:
        layer = chromatic_aberration(layer, chromatic, cx, cy)
        info["chromatic_aberration_px"] = chromatic
    p_enc = srgb(photo)
    fit = fit_noise(p_enc, ~grow) if noise else {"a": 0.0, "b": 0.0}
    ys_, xs_ = np.nonzero(grow)
    if len(ys_) == 0:
        return out, info
    y0, y1, x0, x1 = ys_.min(), ys_.max() + 1, xs_.min(), xs_.max() + 1
    seed = int(rng.integers(1 << 62))

    def noisy(lin: np.ndarray) -> np.ndarray:
        """sRGB of ``lin`` (a crop) with the noise each pixel lacks added: the photo's model at its
        level, less what it has (the photo's, scaled where the ratio darkened it; the render's
        Monte Carlo noise on the objects). One draw shared by the channels: the fit is of the
        luminance's noise (chroma noise is not modelled)."""
        enc = srgb(lin)
        if not noise:
            return enc
        y = enc.mean(axis=2)
        target_var = fit["a"] * y + fit["b"]
        have = np.zeros(y.shape, np.float32)
        if synthetic is not None:
            syn = synthetic[y0:y1, x0:x1]
            have = np.where(syn > 0.5, var_mc[y0:y1, x0:x1], have)
            py = p_enc[y0:y1, x0:x1].mean(axis=2)
            scale = np.where(py > 1e-4, y / np.maximum(py, 1e-4), 1.0)
            have = np.where(syn > 0.5, have, (scale ** 2) * (fit["a"] * py + fit["b"]))
        add = np.sqrt(np.maximum(target_var - have, 0.0)).astype(np.float32)
        n = np.random.default_rng(seed).standard_normal(y.shape).astype(np.float32) * add
        return np.clip(enc + n[..., None], 0.0, 1.0)

    # The render's own (residual Monte Carlo) noise, per object when the ids are known: a near,
    # well-sampled object and a small far one differ.
    var_mc = np.zeros((h, w), np.float32)
    if noise and synthetic is not None and synthetic.any():
        full = synthetic > 0.99
        enc_c = srgb(composite)
        s_mc, _ = noise_sigma(enc_c, full)
        s_mc = s_mc if math.isfinite(s_mc) else 0.0
        var_mc[:] = s_mc * s_mc
        info["render_noise_sigma"] = s_mc
        if ids is not None:
            per = {}
            for i in np.unique(ids[full]):
                m = full & (ids == i)
                s_i, _ = noise_sigma(enc_c, m)
                if math.isfinite(s_i):
                    var_mc[ids == i] = s_i * s_i
                    per[int(i)] = s_i
            info["render_noise_sigma_per_object"] = per
    if noise:
        info["noise"] = {"a": fit["a"], "b": fit["b"], "model": "sigma^2 = a y + b (sRGB luminance)"}
    crop = layer[y0:y1, x0:x1]
    g = grow[y0:y1, x0:x1]
    sig = 0.0
    if blur:
        # NOTE: sharpness is measured as the camera delivers it, noise included: each candidate
        # blur is measured after the matching noise is added (the same draw for all).
        target = sharpness(p_enc, ~grow)
        info["photo_sharpness"] = target
        prev_s, prev_v = 0.0, sharpness(noisy(crop), g)
        if math.isfinite(target) and math.isfinite(prev_v) and prev_v > target:
            for s in np.round(np.arange(0.1, 3.01, 0.1), 2):
                v = sharpness(noisy(gaussian_blur(crop, float(s))), g)
                if not math.isfinite(v) or v <= target:
                    sig = float(prev_s + (s - prev_s) * (prev_v - target) / max(prev_v - v, 1e-12)) \
                        if math.isfinite(v) else prev_s
                    break
                prev_s, prev_v = float(s), v
            else:
                sig = 3.0
        info["blur_sigma_px"] = sig
    # Blur the whole layer (so the crop's border is right), keep what the objects changed.
    blurred = gaussian_blur(layer[max(0, y0 - 10):y1 + 10, max(0, x0 - 10):x1 + 10], sig)
    crop = blurred[y0 - max(0, y0 - 10):y0 - max(0, y0 - 10) + (y1 - y0), x0 - max(0, x0 - 10):x0 - max(0, x0 - 10) + (x1 - x0)]
    enc = noisy(crop)
    region = out[y0:y1, x0:x1]
    # Only pixels that changed are re-encoded (an sRGB round trip is not exact in float).
    changed = g & (np.any(crop != region, axis=2) | np.any(enc != srgb(crop), axis=2))
    out[y0:y1, x0:x1] = np.where(changed[..., None], linear(enc), region)
    if jpeg_quality is not None:
        out = jpeg_roundtrip(out, jpeg_quality)
        info["jpeg_quality"] = float(jpeg_quality)
    return out, info
