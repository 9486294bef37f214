"""The camera's exposure of a synthetic frame (scenario ``camera.exposure``,
docs/scenarios.md#exposure): the factor the rendered linear image is multiplied by, after the
weather's image-space steps and before the scenario's ``post`` steps; labels never change.

- ``auto`` (the default of format version 2): metered like a camera's auto-exposure, before
  the exposure, from a pre-pass at a quarter of the resolution (:data:`PRE_PASS_SPP` samples,
  the frame's scene and render seed): its centre-weighted log-average luminance mapped to
  ``key``, highlights protected (:func:`synthgen.post.exposure.auto_factor`), times 2^ev;
- ``fixed`` (version 1's default, factor 1: the image as rendered): ``factor`` x 2^ev;
- a time of day that exposes the frame itself (``dusk``, ``night``: its own metering, whose
  lower key keeps night dark) is the frame's metering: ``auto`` adds only its ev;
- photo backgrounds: none (the render is matched to the photo's own exposure,
  synthgen.frame.photo; meta ``background.exposure``).

The factor is known before the frame's render, so the render's own exposure (adaptive
sampling, ``clamp_indirect``, the noise estimate) includes it and the scene's journal records
it (``synthgen replay`` applies it). The pre-pass changes nothing of the frame's render: the
image is the render times the factor, bit for bit.
"""
from __future__ import annotations

import math
from typing import Any, Dict, Mapping, Tuple

import numpy as np

from ..post.exposure import auto_factor, metering_pass
from ..randomize import weather

__all__ = ["frame_exposure", "apply_exposure", "PRE_PASS_SCALE", "PRE_PASS_SPP"]

#: The metering pre-pass: 1 / this of the width and height, this many samples per pixel and
#: at most 4 bounces (night's metering pre-pass does the same): 1/128 of the samples of a 64-spp frame.
PRE_PASS_SCALE = 4
PRE_PASS_SPP = 8


def frame_exposure(renderer: Any, exposure: Mapping[str, Any], photo: bool, weather_ctx: Mapping[str, Any],
                   camera: Any, seed: int) -> Tuple[float, Dict[str, Any]]:
    """(factor, what meta ``exposure`` records) of a frame's sampled ``camera.exposure``
    (:class:`synthgen.scenario.sample.CameraSpec`); ``photo``: a photo background;
    ``weather_ctx``: the frame's conditions {key: context} (a condition that ``exposes`` meters)."""
    mode = str(exposure["mode"])
    ev = float(exposure.get("ev") or 0.0)
    if photo:
        return 1.0, {"mode": "photo", "factor": 1.0,
                     "note": "the render is matched to the photo's exposure (background.exposure)"}
    if mode == "fixed":
        factor = float(exposure["factor"]) if exposure.get("factor") is not None else 1.0
        if ev != 0.0:
            factor *= 2.0 ** ev
        return factor, {"mode": "fixed", "factor": factor, "ev": ev}
    by = next((key for key in weather_ctx if weather.condition(key).exposes), None)
    if by is not None:
        factor = 2.0 ** ev
        return factor, {"mode": "auto", "factor": factor, "ev": ev, "metered_by": f"weather.{by}"}
    pre = metering_pass(renderer.scene, camera, seed, renderer.threads, PRE_PASS_SCALE, PRE_PASS_SPP)
    a = auto_factor(pre, float(exposure["key"]), ev)
    return a["factor"], {"mode": "auto", "factor": a["factor"], "ev": ev, "key": float(exposure["key"]),
                         "metered": a["metered"], "highlight": a["highlight"],
                         "highlight_limited": a["highlight_limited"],
                         "stops": round(math.log2(a["factor"]), 6),
                         "pre_pass": {"scale": PRE_PASS_SCALE, "spp": PRE_PASS_SPP}}


def apply_exposure(arrays: Dict[str, np.ndarray], factor: float) -> Dict[str, np.ndarray]:
    """The arrays with rgb times ``factor`` (float32); the same arrays where it is 1."""
    if factor == 1.0:
        return arrays
    out = dict(arrays)
    out["rgb"] = (np.asarray(arrays["rgb"], np.float32) * np.float32(factor)).astype(np.float32)
    return out
