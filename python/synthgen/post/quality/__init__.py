"""Image quality, one definition everywhere: PSNR of linear RGB clamped to [0, 1] after the
scene's exposure (peak 1), and relMSE, against a converged image of the same renderer -- and
their estimates from a render alone, from its two half-sample images.

A render keeps, per pixel, the mean of its even-numbered and of its odd-numbered samples
(``RenderResult.rgb_even`` / ``rgb_odd``): two independent estimates of the pixel with half
the samples each. Their difference measures the noise of the full mean.

NOTE: with n_e and n_o samples in the halves (n = n_e + n_o) and a per-sample variance s^2,
E[(a - b)^2] = s^2 (1/n_e + 1/n_o) while the full mean's variance is s^2 / n, so
MSE(mean) = E[(a - b)^2] / (n (1/n_e + 1/n_o)) -- a quarter of it for equal halves
(Rousselle, Knaus & Zwicker 2012, sec. 4: the dual-buffer estimate). The estimate sees noise
only, not bias (a converged reference's bias is reported apart where it is measured).
Clamping to [0, 1] is applied to each half before the difference, as it is to the image and
its reference in the true PSNR."""
from __future__ import annotations

import math
from typing import Any, Dict, Mapping, Optional, Sequence

import numpy as np

__all__ = ["psnr", "relmse", "estimate_noise", "exposure_scale", "RELMSE_EPS"]

#: relMSE's denominator offset (the reference squared + this), as in the denoising literature
#: (Rousselle et al. 2012; Bitterli et al. 2016 use 1e-2).
RELMSE_EPS = 1e-2


def _prep(img: np.ndarray, scale: float) -> np.ndarray:
    return np.clip(np.asarray(img, np.float64)[..., :3] * float(scale), 0.0, 1.0)


def psnr(img: np.ndarray, ref: np.ndarray, scale: float = 1.0, mask: Optional[np.ndarray] = None) -> float:
    """PSNR (dB) of ``img`` against ``ref``: both linear RGB times ``scale`` (the exposure),
    clamped to [0, 1], peak 1, mean over ``mask``'s pixels (all by default) and channels."""
    d = (_prep(img, scale) - _prep(ref, scale)) ** 2
    mse = float(d[mask].mean() if mask is not None else d.mean())
    return math.inf if mse <= 0.0 else -10.0 * math.log10(mse)


def relmse(img: np.ndarray, ref: np.ndarray, scale: float = 1.0, mask: Optional[np.ndarray] = None) -> float:
    """Mean of (img - ref)^2 / (ref^2 + 1e-2) over pixels and channels (linear, times ``scale``,
    not clamped)."""
    a = np.asarray(img, np.float64)[..., :3] * scale
    r = np.asarray(ref, np.float64)[..., :3] * scale
    d = (a - r) ** 2 / (r * r + RELMSE_EPS)
    return float(d[mask].mean() if mask is not None else d.mean())


def estimate_noise(even: np.ndarray, odd: np.ndarray, spp: Any, scale: float = 1.0,
                   mask: Optional[np.ndarray] = None) -> Optional[Dict[str, float]]:
    """The estimated error of a render of ``spp`` samples per pixel (a number, or an H x W
    array of each pixel's count: ``RenderResult.sample_count`` of adaptive sampling) from its
    half-sample images (``rgb_even``, ``rgb_odd``): ``{"psnr_db", "relmse", "mse"}`` against the
    converged image (clamped after ``scale``, see :func:`psnr`; relMSE unclamped), or None
    where a pixel has fewer than 2 samples."""
    n = np.asarray(spp, np.int64)
    if n.ndim == 2:
        n = n[..., None]
    if (n < 2).any():
        return None
    n_e, n_o = (n + 1) // 2, n // 2
    factor = 1.0 / (n * (1.0 / n_e + 1.0 / n_o))
    ua = np.asarray(even, np.float64)[..., :3] * scale
    ub = np.asarray(odd, np.float64)[..., :3] * scale
    a, b = np.clip(ua, 0.0, 1.0), np.clip(ub, 0.0, 1.0)
    # NOTE: where one half saturates and the other does not (the edge of a bright emitter: a
    # sliver met by some samples of one half only), clamping hides part of the spread, and the
    # mean's clamped error is poorly seen from one pair of halves. There the clamped estimate
    # is doubled: measured on the Cornell box (its 18.4-radiance light's edges hold most of
    # the clamped error), over 6 renders at 4 / 16 / 64 spp the estimate's mean is then within
    # -0.03 / +0.42 / +0.47 dB of the true PSNR (undoubled: +1.18 / +2.14 / +0.47; the
    # unclamped difference capped at 1: -1.67 / -1.12 / +0.46).
    one = (ua > 1.0) != (ub > 1.0)
    d = (a - b) ** 2 * np.where(one, 2.0 * factor, factor)
    mse = float((d[mask] if mask is not None else d).mean())
    m = (ua * n_e + ub * n_o) / n
    r = (ua - ub) ** 2 * factor / (m * m + RELMSE_EPS)
    rel = float((r[mask] if mask is not None else r).mean())
    return {"psnr_db": math.inf if mse <= 0.0 else -10.0 * math.log10(mse), "relmse": rel, "mse": mse}


def exposure_scale(post: Sequence[Any]) -> float:
    """The factor the scene's ``exposure`` post steps apply to radiance (2^ev each); steps given
    as objects with ``type`` / ``params`` or as {"type", "params"} mappings."""
    s = 1.0
    for p in post or ():
        kind = p["type"] if isinstance(p, Mapping) else p.type
        params = p.get("params", {}) if isinstance(p, Mapping) else p.params
        if kind == "exposure":
            s *= 2.0 ** float(params.get("ev", 0.0))
    return s
