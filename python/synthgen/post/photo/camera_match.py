"""Camera matching: what a real camera did to the photo, estimated from it and applied to the
inserted render only, so that a detector cannot learn "sharp, clean object = target".

Pure functions (arrays + parameters -> arrays). Photos are gamma-encoded (and often JPEG
compressed): noise and sharpness are measured and matched in the encoded (sRGB) space where
they live; colour and light in linear light.

The measurements (noise fit, sharpness, flat regions, ring statistics) are in
:mod:`synthgen.post.photo.measure` (re-exported here):

* :func:`fit_noise` -- the photo's signal-dependent noise, sigma^2(y) = a y + b (Foi et al. 2008,
  "Practical Poissonian-Gaussian noise modeling and fitting for single-image raw-data": a
  Poisson term a y plus a Gaussian floor b), y the local mean;
* :func:`sharpness` and :func:`match_blur` -- a no-reference sharpness (gradient / contrast at
  step edges) and the Gaussian blur that gives the render the photo's (:func:`match_camera`
  also sharpens, per object, when the photo's camera did);
* :func:`flat_mask` -- where a render is flat (albedo and normal), so what varies is noise;
* :func:`vignette`, :func:`chromatic_aberration` -- optional lens effects;
* :func:`jpeg_roundtrip` -- the frame re-encoded as the photo was (its estimated quality);
* :func:`match_camera` -- all of it on a composite, with the parameters for the metadata (the
  noise loop measured on a test patch per object, through the frame's 8-bit rounding and JPEG);
  what it could not match (an object's noise loop not converged, or its render noisier than
  the photo; a sharpness beyond the largest blur or sharpening) in ``unmatched``, per object,
  never silently.
"""
from __future__ import annotations

import math
import os
import tempfile
from typing import Any, Dict, Optional, Tuple

import numpy as np

from .measure import (_inner, dilate, fit_noise, flat_mask, linear, noise_sigma, ring_statistics,  # noqa: F401
                      sharpness, srgb)

__all__ = ["fit_noise", "noise_sigma", "flat_mask", "sharpness", "gaussian_blur", "match_blur", "vignette",
           "chromatic_aberration", "jpeg_roundtrip", "match_camera", "ring_statistics", "srgb", "linear"]


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


def _channel_noise(enc: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """A 3 x 3 matrix L whose L L^T is the covariance of ``enc``'s noise between its channels over
    ``mask`` (the robust estimate per channel and per pair's mean: var((c + d) / 2) =
    (var c + var d + 2 cov) / 4), made positive semi-definite; zeros where it cannot be measured.
    A render's residual Monte Carlo noise is neither one draw shared by the channels nor three
    independent ones, and the JPEG keeps the part the channels share (luminance) far more than
    the rest (chroma: subsampled, coarser quantization)."""
    def var(z: np.ndarray) -> float:
        s, _ = noise_sigma(z, mask)
        return s * s if math.isfinite(s) else 0.0

    c = np.zeros((3, 3))
    for i in range(3):
        c[i, i] = var(enc[..., i])
    for i, j in ((0, 1), (0, 2), (1, 2)):
        c[i, j] = c[j, i] = 2.0 * var(0.5 * (enc[..., i] + enc[..., j])) - 0.5 * (c[i, i] + c[j, j])
    ev, vec = np.linalg.eigh(c)
    return (vec * np.sqrt(np.maximum(ev, 0.0))).astype(np.float32)


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
    for the metadata; ``unmatched``: {object id or "frame": [{"check": "noise_loop" |
    "blur_clamp", achieved and target numbers}]} when something could not be matched)."""
    h, w = influence.shape
    cx = w / 2 if cx is None else cx
    cy = h / 2 if cy is None else cy
    focal = max(w, h) if focal is None else focal
    info: Dict[str, Any] = {}
    out = np.array(composite, np.float32)
    grow = dilate(influence, 3)  # the blur and the lens effects spread the objects a little
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
    # NOTE: the photo's noise is fitted over the whole photo: the insertion changed none of its
    # pixels, and leaving out what the objects and their shadows cover (often most of the road,
    # the flattest part of a street photo) left foliage and sky edges, whose texture the fit
    # took for noise 15 times the photo's (0.0307 against 0.0021, sRGB, on one dusk road photo:
    # a speckled car on a clean road).
    fit = fit_noise(p_enc) if noise else {"a": 0.0, "b": 0.0}
    ys_, xs_ = np.nonzero(grow)
    if len(ys_) == 0:
        return out, info
    y0, y1, x0, x1 = ys_.min(), ys_.max() + 1, xs_.min(), xs_.max() + 1
    seed = int(rng.integers(1 << 62))

    # The inserted objects in the crop: the pixels each covers, the pixels its noise is measured
    # on (flat albedo and normal, two pixels from any edge: noise, not texture nor the JPEG's
    # ringing at edges; the pixels :func:`ring_statistics` measures) and its box (crop
    # coordinates, grown by 3 pixels: its edges and the shadow under it).
    ch, cw = y1 - y0, x1 - x0
    g = grow[y0:y1, x0:x1]
    objects = []
    if synthetic is not None and ids is not None:
        syn_c, ids_c = synthetic[y0:y1, x0:x1], ids[y0:y1, x0:x1]
        alb_c = None if albedo is None else albedo[y0:y1, x0:x1]
        nrm_c = None if normal is None else normal[y0:y1, x0:x1]
        for i in np.unique(ids_c[syn_c > 0.99]):
            whole = (ids_c == i) & (syn_c > 0.99)
            flat = _inner(flat_mask(whole, alb_c, nrm_c))
            cover = (ids_c == i) & (syn_c > 0.5)
            oy, ox = np.nonzero(cover)
            box = (max(0, oy.min() - 3), min(ch, oy.max() + 4), max(0, ox.min() - 3), min(cw, ox.max() + 4))
            objects.append({"id": int(i), "cover": cover, "flat": flat if flat.sum() >= 20 else whole, "box": box,
                            "gain": 1.0})
    # Who owns each influenced pixel for the blur: an object its own pixels, then the pixels of its
    # box (first come); what is left (a long shadow) the frame's.
    owner = np.full((ch, cw), -1, np.int32)
    for k, o in enumerate(objects):
        by0, by1, bx0, bx1 = o["box"]
        sub = owner[by0:by1, bx0:bx1]
        sub[(sub < 0) & g[by0:by1, bx0:bx1]] = k
    for k, o in enumerate(objects):
        owner[o["cover"]] = k

    def noisy(lin: np.ndarray, oy: int = 0, ox: int = 0) -> np.ndarray:
        """sRGB of ``lin`` (the crop, or a window of it at (oy, ox)) with the noise each pixel
        lacks added: the photo's model at its level, less what it has (the photo's, scaled where
        the ratio darkened it; each object's own residual Monte Carlo noise, measured on ``lin``
        itself, so after the blur), times the object's gain (see below). One draw shared by the
        channels: the fit is of the luminance's noise (chroma noise is not modelled)."""
        enc = srgb(lin)
        if not noise:
            return enc
        hh, ww = lin.shape[:2]
        win = (slice(oy, oy + hh), slice(ox, ox + ww))
        y = enc.mean(axis=2)
        target_var = fit["a"] * y + fit["b"]
        have = np.zeros(y.shape, np.float32)
        if synthetic is not None:
            syn = synthetic[y0:y1, x0:x1][win]
            py = p_enc[y0:y1, x0:x1][win].mean(axis=2)
            scale = np.where(py > 1e-4, y / np.maximum(py, 1e-4), 1.0)
            have = np.where(syn > 0.5, 0.0, (scale ** 2) * (fit["a"] * py + fit["b"]))
            for o in objects:
                cover = o["cover"][win]
                if not cover.any():
                    continue
                s_i, _ = noise_sigma(enc, o["flat"][win])
                s_i = s_i if math.isfinite(s_i) else 0.0
                have = np.where(cover, s_i * s_i, have)
                target_var = np.where(cover, o["gain"] * target_var, target_var)
        add = np.sqrt(np.maximum(target_var - have, 0.0)).astype(np.float32)
        draw = np.random.default_rng(seed).standard_normal((ch, cw)).astype(np.float32)[win]
        return np.clip(enc + (draw * add)[..., None], 0.0, 1.0)

    # NOTE: in-camera sharpening is an unsharp mask in the encoded space with a threshold
    # ("coring"): details under a few noise sigmas are left alone, so noise is not amplified
    # (the threshold ramps in over 3..6 sigma of the photo's noise at mid grey).
    core = 3.0 * math.sqrt(max(fit["a"] * 0.5 + fit["b"], 0.0)) if noise else 0.0

    # Sharpening acts on the objects' edges (their silhouettes and where their albedo or normal
    # changes), not on their flat insides nor on the photo (already the camera's).
    edges = np.zeros((h, w), bool)
    if synthetic is not None:
        syn_any = synthetic > 0.01
        edges = syn_any.copy()
        edges[1:] |= syn_any[:-1]
        edges[:-1] |= syn_any[1:]
        edges[:, 1:] |= syn_any[:, :-1]
        edges[:, :-1] |= syn_any[:, 1:]
        edges &= ~flat_mask(synthetic > 0.99, albedo, normal, min_pixels=0)

    def soften(a: np.ndarray, amount: float, where: np.ndarray) -> np.ndarray:
        """``amount`` > 0: a Gaussian blur of that sigma; < 0: an unsharp mask of that strength
        (radius 1 pixel, sRGB, cored), as in-camera sharpening does, on ``where``."""
        if amount > 0:
            return gaussian_blur(a, amount)
        if amount < 0:
            enc = srgb(a)
            d = enc - gaussian_blur(enc, 1.0)
            if core > 0:
                d = d * np.clip(np.abs(d) / core - 1.0, 0.0, 1.0)
            return linear(enc + (-amount) * d * where[..., None])
        return a

    M = 10  # margin: the blur's reach (3 sigma) and the sharpness measure's (6 pixels)

    def window(wy0: int, wy1: int, wx0: int, wx1: int, amount: float) -> np.ndarray:
        """The layer over crop rows wy0:wy1, columns wx0:wx1, softened by ``amount`` (computed
        with a margin, so the window's border is right)."""
        ey0, ex0 = max(0, y0 + wy0 - M), max(0, x0 + wx0 - M)
        a = soften(layer[ey0:y0 + wy1 + M, ex0:x0 + wx1 + M], amount, edges[ey0:y0 + wy1 + M, ex0:x0 + wx1 + M])
        return a[y0 + wy0 - ey0:y0 + wy1 - ey0, x0 + wx0 - ex0:x0 + wx1 - ex0]

    def match_sharpness(target: float, wy0: int, wy1: int, wx0: int, wx1: int, mask: np.ndarray,
                        who: Any = None) -> float:
        """The blur (> 0) or sharpening (< 0) that gives the window's ``mask`` the photo's
        sharpness, measured as the camera delivers it (the matching noise added: the same draw
        for all candidates). When the largest amount tried (blur 3, sharpening 2) falls short,
        that amount, and ``who``'s "blur_clamp" is recorded in ``unmatched``."""
        def measure(amount: float) -> float:
            return sharpness(noisy(window(wy0, wy1, wx0, wx1, amount), wy0, wx0), mask)

        v0 = measure(0.0)
        if not (math.isfinite(target) and math.isfinite(v0)) or abs(v0 - target) <= 0.02 * target:
            return 0.0
        sign = 1.0 if v0 > target else -1.0  # too sharp: blur; too soft: sharpen
        # NOTE: sharpness falls monotonically with the amount: bracket the target, then regula
        # falsi (a handful of measurements instead of a scan).
        lo_a, lo_v = 0.0, v0
        hi_a = hi_v = None
        for a in ((0.5, 1.0, 2.0, 3.0) if sign > 0 else (-0.5, -1.0, -2.0)):
            v = measure(a)
            if not math.isfinite(v):
                return lo_a
            if sign * (v - target) <= 0:
                hi_a, hi_v = a, v
                break
            lo_a, lo_v = a, v
        if hi_a is None:
            if abs(lo_v - target) > 0.02 * target:
                unmatched.setdefault(who, []).append({"check": "blur_clamp", "amount": float(lo_a), "sharpness": lo_v,
                                                      "target": target})
            return lo_a
        for _ in range(3):
            a = lo_a + (hi_a - lo_a) * (lo_v - target) / (lo_v - hi_v) if lo_v != hi_v else hi_a
            v = measure(a)
            if not math.isfinite(v) or abs(v - target) <= 0.02 * target:
                return float(a)
            if sign * (v - target) > 0:
                lo_a, lo_v = a, v
            else:
                hi_a, hi_v = a, v
        return float(lo_a + (hi_a - lo_a) * (lo_v - target) / (lo_v - hi_v)) if lo_v != hi_v else float(hi_a)

    if noise:
        info["noise"] = {"a": fit["a"], "b": fit["b"], "model": "sigma^2 = a y + b (sRGB luminance)"}
    # What could not be matched, per object id ("frame": the influence no object's box holds):
    # a list of {"check", achieved and target numbers}.
    unmatched: Dict[Any, list] = {}
    frame_amount = 0.0
    if blur:
        # NOTE: per object (a near object and a far one, rendered at one resolution, are not
        # equally soft; the photo's camera made both as sharp as the photo), the frame's amount
        # for influence no object's box holds.
        target = sharpness(p_enc, ~grow)
        info["photo_sharpness"] = target
        frame_amount = match_sharpness(target, 0, ch, 0, cw, g, "frame") if (owner < 0).any() or not objects else 0.0
        for k, o in enumerate(objects):
            by0, by1, bx0, bx1 = o["box"]
            wy0, wy1, wx0, wx1 = max(0, by0 - M), min(ch, by1 + M), max(0, bx0 - M), min(cw, bx1 + M)
            mask = np.zeros((wy1 - wy0, wx1 - wx0), bool)
            mask[by0 - wy0:by1 - wy0, bx0 - wx0:bx1 - wx0] = (owner[by0:by1, bx0:bx1] == k)
            o["amount"] = match_sharpness(target, wy0, wy1, wx0, wx1, mask, o["id"])
        info["blur_sigma_px"] = frame_amount if not objects else float(np.median([o["amount"] for o in objects]))
        info["blur_per_object"] = {o["id"]: o["amount"] for o in objects}
    # The softened crop: each pixel as its owner's amount made it.
    crop = window(0, ch, 0, cw, frame_amount)
    for k, o in enumerate(objects):
        if o.get("amount", 0.0) != frame_amount:
            crop = np.where((owner == k)[..., None], window(0, ch, 0, cw, o["amount"]), crop)
    region = out[y0:y1, x0:x1]
    if objects:
        info["render_noise_sigma_per_object"] = {o["id"]: noise_sigma(srgb(crop), o["flat"])[0] for o in objects}

    def finished(enc: np.ndarray) -> np.ndarray:
        """The frame with the crop's noisy pixels in (only pixels that changed are re-encoded:
        an sRGB round trip is not exact in float)."""
        changed = g & (np.any(crop != region, axis=2) | np.any(enc != srgb(crop), axis=2))
        f = out.copy()
        f[y0:y1, x0:x1] = np.where(changed[..., None], linear(enc), region)
        return f

    # NOTE: closed loop per object. What the camera chain does after the noise is added (the
    # JPEG re-encode smooths it, nonlinearly; the 8-bit file adds (1/255)^2 / 12 of quantization,
    # a variance comparable to these photos' own) is measured, not modelled: the noise is added,
    # re-encoded as it will be written, measured as the photo's was, and each object's gain on
    # the target variance corrected; at most 6 rounds, to within 3 %.
    # It is measured on a test patch per object, not on the object in the frame: 128 x 128 of the
    # object's colour (its flat pixels' mean) with the noise its flat pixels get (the render's
    # residual, per channel as measured, and the shared draw noisy() adds at the object's gain;
    # draws of its own, the same every round), 8-bit, through the frame's JPEG. The photo's
    # noise model is fitted where the photo is flat, mostly far from edges; an object's flat
    # pixels in these photos are all within a JPEG block of its edges (a car 30 - 60 pixels
    # tall), where the JPEG's ringing at those edges (stronger where they were sharpened) is
    # 1 - 3 times the photo's noise and changes with every draw that flips a coefficient's
    # rounding: measured there, the loop read the ringing as noise and turned the gain down to
    # 0, or stepped on a function that is not monotonic, and scattered (last errors 0.44 - 1.96
    # on three highway frames). The ringing is the JPEG's, as the photo's own edges have it; the
    # noise under it is the patch's. A patch whose noise the JPEG removes entirely (measured 0)
    # has far too little, never "done"; one noisier than the photo with nothing added is the
    # render's own noise (gain 0, reported).
    if noise and objects:
        P = 128  # the probe's side: 8 x 8 blocks of 16 x 16 (4:2:0), 126 x 126 second differences
        pdraw = np.random.default_rng([seed, 1]).standard_normal((P, P * len(objects))).astype(np.float32)
        rdraw = np.random.default_rng([seed, 2]).standard_normal((P, P * len(objects), 3)).astype(np.float32)
        # A gentle plane (3 code values across: no second differences), so that the 8-bit rounding
        # is not the same at every pixel, as on the photo's and the objects' shaded surfaces (on one
        # constant value the estimate jumps as the noise crosses the lattice's steps).
        yy, xx = np.mgrid[0:P, 0:P].astype(np.float32) / P
        plane = (2.0 * xx + 0.75 * yy - 1.375) / 255.0
        crop_enc = srgb(crop)
        for o in objects:
            o["colour"] = srgb(crop[o["flat"]].mean(axis=0))
            s_i, _ = noise_sigma(crop_enc, o["flat"])
            o["have"] = s_i * s_i if math.isfinite(s_i) else 0.0
            o["residual"] = _channel_noise(crop_enc, o["flat"])
            o["target"] = fit["a"] * float(o["colour"].mean()) + fit["b"]
            o["tries"] = []  # (gain, log of written / photo's noise, error, noise, photo's noise)
        # NOTE: the written noise rises with the gain, but not smoothly: the JPEG's dead zone drops
        # noise under a coefficient's quantization step and keeps it above (here about 0.5 of the
        # photo's at gain 1, 1.5 at gain 4, with steps of 5 - 10 % where many coefficients cross).
        # So: bracket the target, then regula falsi on log(ratio) against log(gain) (about a power
        # law; Illinois: the end kept twice has its value halved), from g <- g / r^2 (no JPEG:
        # variance ~ g); an object within 3 % keeps its gain; one that is not after 6 rounds gets
        # its best try, reported with that try's numbers.
        rounds = []
        for _ in range(6):
            todo = [k for k, o in enumerate(objects) if "done" not in o]
            # The render's own residual noise (per channel, correlated as measured), and the shared
            # draw noisy() adds on top of it: what the object's flat pixels get.
            probe = np.concatenate([np.clip(
                o["colour"] + (plane + pdraw[:, k * P:(k + 1) * P] * math.sqrt(
                    max(o["gain"] * o["target"] - o["have"], 0.0)))[..., None] + rdraw[:, k * P:(k + 1) * P] @ o[
                        "residual"].T, 0.0, 1.0) for k, o in enumerate(objects) if k in todo], axis=1)
            f = linear(probe)
            if jpeg_quality is not None:
                f = jpeg_roundtrip(f, jpeg_quality)
            written = np.round(srgb(f) * 255.0) / 255.0
            for j, k in enumerate(todo):
                o = objects[k]
                s_i, level = noise_sigma(written[:, j * P:(j + 1) * P], np.ones((P, P), bool))
                e_i = math.sqrt(max(fit["a"] * level + fit["b"], 0.0)) if math.isfinite(level) else 0.0
                if not e_i > 0:
                    o["done"] = True  # nothing to match (no noise model at this level)
                    continue
                # No noise left after the 8-bit rounding and the JPEG (or a measure that failed):
                # far too little noise, so more gain (at most 4 x a round), never "done".
                s_i = s_i if math.isfinite(s_i) else 0.0
                gn, lr = o["gain"], math.log(max(s_i / e_i, 1e-3))
                err = abs(s_i / e_i - 1.0)
                o["tries"].append((gn, lr, err, s_i, e_i))
                if err < 0.03:
                    o["done"] = True
                    continue
                if lr > 0 and gn * o["target"] <= o["have"]:
                    # Noisier than the photo with nothing added: the render's own noise, which no
                    # gain takes away. None is added (gain 0), and the object is reported.
                    o["gain"], o["tries"][-1] = 0.0, (0.0, lr, err, s_i, e_i)
                    o["done"] = "noisier"
                    continue
                below = [t for t in o["tries"] if t[1] < 0]
                above = [t for t in o["tries"] if t[1] > 0]
                if below and above and gn > 0:
                    lo = max(below, key=lambda t: t[0])  # the bracket's ends: the nearest tries
                    hi = min((t for t in above if t[0] > lo[0]), key=lambda t: t[0], default=None)
                else:
                    lo = hi = None
                if hi is not None and lo[0] > 0:
                    flo, fhi = lo[1], hi[1]
                    side = "hi" if lr > 0 else "lo"
                    if o.get("side") == side:  # Illinois: the other end, kept twice, counts half
                        if side == "hi":
                            flo *= 0.5 ** o.get("kept", 1)
                        else:
                            fhi *= 0.5 ** o.get("kept", 1)
                        o["kept"] = o.get("kept", 1) + 1
                    else:
                        o["kept"] = 1
                    o["side"] = side
                    xlo, xhi = math.log(lo[0]), math.log(hi[0])
                    g_new = math.exp(xlo - flo * (xhi - xlo) / (fhi - flo)) if fhi != flo else math.sqrt(lo[0] * hi[0])
                else:
                    # g / r^2, from the gain that starts adding noise where the render's own residual
                    # is all the probe has (the variance is max(g T, residual)).
                    base = max(gn, o["have"] / o["target"]) if lr < 0 and o["target"] > 0 else gn
                    g_new = min(max(base * math.exp(-2.0 * lr), base / 4.0), 4.0 * base)
                o["gain"] = float(min(max(g_new, 1e-4), 64.0))
            # The round's worst over all objects (each one's latest measurement: those done keep
            # theirs), so that the last entry is the loop's outcome.
            rounds.append(round(max([o["tries"][-1][2] for o in objects if o["tries"]] + [0.0]), 4))
            if all("done" in o for o in objects):
                break
        errors = {}
        for o in objects:
            if o["tries"] and o.get("done") is True:
                errors[o["id"]] = o["tries"][-1][2]
            elif o["tries"]:
                # The best try (the latest of equals), or nothing added to a render already noisier.
                best = o["tries"][-1] if o.get("done") == "noisier" else min(reversed(o["tries"]), key=lambda t: t[2])
                o["gain"], errors[o["id"]] = best[0], best[2]
                unmatched.setdefault(o["id"], []).append(
                    {"check": "noise_loop", "error": best[2], "max_error": 0.03, "noise": best[3],
                     "photo_noise": best[4], "gain": o["gain"], "rounds": len(rounds)})
        info["noise_gain_per_object"] = {o["id"]: o["gain"] for o in objects}
        info["noise_loop_worst_error"] = rounds
        info["noise_loop_error_per_object"] = errors  # the gain kept's (what is written)
    if unmatched:
        info["unmatched"] = unmatched
    out = finished(noisy(crop))
    if jpeg_quality is not None:
        out = jpeg_roundtrip(out, jpeg_quality)
        info["jpeg_quality"] = float(jpeg_quality)
    return out, info
