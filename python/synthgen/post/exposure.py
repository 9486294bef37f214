"""Exposure: the post-processing step ``exposure`` (the linear image x 2^ev, photographic
stops: to vary brightness across a dataset, ``ev: {uniform: [-1, 1]}``), and the metering of a
camera's auto-exposure (:func:`meter`, :func:`auto_factor`), which the frame pipeline applies
for a scenario's ``camera.exposure`` (synthgen.frame.exposure; docs/scenarios.md). Labels are
untouched.

The metering is a pure function of a linear image (float64, numpy reductions in a fixed order,
no threads): the same image gives the same factor, bit for bit."""
from __future__ import annotations

import math
from typing import Any, Dict, Mapping

import numpy as np

from ..schema.fields import Number, Record
from . import Arrays, PostStep, register

__all__ = ["metering_pass", "KEY", "LUMINANCE", "HIGHLIGHT_PERCENTILE", "CLIP_PERCENTILE", "DYNAMIC_RANGE_STOPS", "MAX_STOPS",
           "luminance", "metering_weights", "meter", "auto_factor"]

SCHEMA = Record({"ev": Number(0.0, min=-20.0, max=20.0, doc="exposure change in stops (the image x 2^ev)")},
                doc="exposure")

#: NOTE: the key of auto-exposure, the mid-grey a scene's log-average luminance is mapped to:
#: 0.18 (18% reflectance grey), E. Reinhard et al., "Photographic Tone Reproduction for Digital
#: Images", SIGGRAPH 2002, sec. 3.1 ("key value"; 0.18 their "normal-key" value), as a
#: reflected-light meter puts an average scene near mid-grey (ISO 2720's calibration, K = 12.5).
KEY = 0.18
#: NOTE: Rec. 709 / sRGB luminance weights of linear RGB (ITU-R BT.709-6, item 3.2).
LUMINANCE = (0.2126, 0.7152, 0.0722)
#: Luminances above this percentile of the frame (the sun's disc, specular highlights, lamps)
#: count as this percentile in the log-average: a few very bright pixels do not darken the frame.
CLIP_PERCENTILE = 99.0
#: Highlight protection: the exposure is lowered until at most (100 - this)% of the frame is
#: past white (1.0) -- a camera's highlight-weighted metering: a bright sky filling a quarter
#: of the frame keeps its colour instead of clipping.
HIGHLIGHT_PERCENTILE = 97.0
#: Luminances below the clipped maximum / 2^this count as that (a sensor's dynamic range, about
#: 12 stops): black pixels (an empty background) do not drag the exposure up without bound.
DYNAMIC_RANGE_STOPS = 12.0
#: The factor is kept within 2^-40 .. 2^40 (no float32 overflow; the night condition's range).
MAX_STOPS = 40.0


def apply(arrays: Mapping[str, np.ndarray], params: Mapping[str, Any]) -> Arrays:
    out = dict(arrays)
    out["rgb"] = (np.asarray(arrays["rgb"], np.float32) * np.float32(2.0 ** float(params["ev"]))).astype(np.float32)
    return out


def metering_pass(scene: Any, camera: Any, seed: int, threads: int, scale: int = 4, spp: int = 8) -> np.ndarray:
    """A camera's light meter: the scene's linear image through ``camera`` at 1 / ``scale`` of
    its width and height (intrinsics scaled, distortion kept), ``spp`` samples, at most 4
    bounces, render seed ``seed``; the scene's camera is set back afterwards. Used by the
    auto-exposure of ``camera.exposure`` (synthgen.frame.exposure) and by the dusk and night
    conditions' own metering (synthgen.randomize.weather)."""
    from .._core import PinholeCamera

    q = int(scale)
    small = PinholeCamera(camera.fx / q, camera.fy / q, (camera.cx + 0.5) / q - 0.5, (camera.cy + 0.5) / q - 0.5,
                          max(1, camera.width // q), max(1, camera.height // q),
                          np.asarray(camera.world_from_camera, np.float64), distortion=tuple(camera.distortion))
    scene.set_camera(small)
    try:
        pre = scene.render(spp=spp, max_depth=4, seed=int(seed), threads=threads)
    finally:
        scene.set_camera(camera)
    return np.asarray(pre.rgb)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Relative luminance (float64, H x W) of linear RGB (H x W x 3); non-finite pixels are 0."""
    a = np.asarray(rgb, np.float64)[..., :3]
    y = a[..., 0] * LUMINANCE[0] + a[..., 1] * LUMINANCE[1] + a[..., 2] * LUMINANCE[2]
    return np.where(np.isfinite(y), np.maximum(y, 0.0), 0.0)


def metering_weights(height: int, width: int) -> np.ndarray:
    """Centre-weighted average metering: each pixel's weight, 0.25 + exp(-2 (u^2 + v^2)) with u, v
    its centre's position in [-1, 1] across the image (1.25 at the centre, 0.39 at the middle of
    an edge, 0.27 in a corner): the subject, usually near the centre, counts most, the whole frame
    still counts (NOTE: as the 'centre-weighted average' metering mode of cameras, which weighs a
    central circle most; smooth here, so that the factor does not jump as an object crosses an
    edge)."""
    u = (np.arange(width, dtype=np.float64) + 0.5) / max(width, 1) * 2.0 - 1.0
    v = (np.arange(height, dtype=np.float64) + 0.5) / max(height, 1) * 2.0 - 1.0
    return 0.25 + np.exp(-2.0 * (v[:, None] ** 2 + u[None, :] ** 2))


def meter(rgb: np.ndarray) -> Dict[str, float]:
    """What a light meter reads from a linear image (H x W x 3, the render's units):
    ``log_average`` -- the centre-weighted log-average (geometric mean) luminance, each pixel's
    luminance clipped to [high / 2^DYNAMIC_RANGE_STOPS, high] with ``high`` the
    CLIP_PERCENTILE-th percentile (NOTE: the log-average luminance as the scene's key, Reinhard
    et al. 2002, eq. 1) -- and ``highlight``, the HIGHLIGHT_PERCENTILE-th percentile.
    Both 0 for a black image."""
    y = luminance(rgb)
    if y.size == 0:
        return {"log_average": 0.0, "highlight": 0.0}
    high = float(np.percentile(y, CLIP_PERCENTILE))
    highlight = float(np.percentile(y, HIGHLIGHT_PERCENTILE))
    if not high > 0.0:
        return {"log_average": 0.0, "highlight": highlight}
    w = metering_weights(*y.shape)
    logs = np.log(np.clip(y, high * 2.0 ** -DYNAMIC_RANGE_STOPS, high))
    return {"log_average": float(math.exp(float(np.sum(w * logs)) / float(np.sum(w)))), "highlight": highlight}


def auto_factor(rgb: np.ndarray, key: float = KEY, ev: float = 0.0) -> Dict[str, Any]:
    """The factor of an auto-exposure of a linear image: its metered log-average mapped to
    ``key`` (:func:`meter`), lowered where that would put the HIGHLIGHT_PERCENTILE-th percentile
    past white, times 2^``ev`` (exposure compensation, stops), within 2^-MAX_STOPS .. 2^MAX_STOPS.
    ``{"factor", "metered", "highlight", "highlight_limited"}``; a black image: factor 2^ev."""
    m = meter(rgb)
    metered = 1.0
    limited = False
    if m["log_average"] > 0.0:
        metered = float(key) / m["log_average"]
        if m["highlight"] > 0.0 and metered * m["highlight"] > 1.0:
            metered, limited = 1.0 / m["highlight"], True
    stops = min(max(math.log2(metered) + float(ev), -MAX_STOPS), MAX_STOPS)
    return {"factor": float(2.0 ** stops), "metered": m["log_average"], "highlight": m["highlight"],
            "highlight_limited": limited}


register(PostStep("exposure", "scales the linear image by 2^ev (stops)", SCHEMA, apply, module=__name__))
