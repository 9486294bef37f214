"""Feature-guided denoising of a render from its two half-sample images, a reduced NFOR.

NFOR: Bitterli and colleagues 2016, "Nonlinearly Weighted First-Order Regression for Denoising
Monte Carlo Renderings"; docs/denoise.md gives the algorithm, its settings and its measured
quality.

    res = scene.render(spp=16, max_depth=6, seed=1)
    img = denoise(res.rgb_even, res.rgb_odd, res.albedo, res.normal, res.depth)

Each feature is one array (the render's pixel-centre feature, used for both halves) or a pair
(even, odd) of sample-averaged half buffers, which are then prefiltered."""
from __future__ import annotations

from typing import Any, Optional, Sequence, Tuple, Union

import numpy as np

from ..._core import denoise as _denoise

__all__ = ["denoise", "SETTINGS"]

#: The settings denoise() accepts, with their defaults (cpp/film/denoise.h DenoiseSettings).
SETTINGS = {
    "radius": 4,
    "patch_radius": 1,
    "k": 1.0,
    "feature_radius": 5,
    "selection_radius": 2,
    "albedo_floor": 0.01,
    "ridge": 1e-3,
    "firefly_ratio": 2.0,
    "second_pass": False,
    "distance_floor": 1e-3,
    "normal_weight": 5.0,
}

Feature = Union[np.ndarray, Sequence[np.ndarray]]


def _image(a: Any, name: str, shape: Tuple[int, ...]) -> np.ndarray:
    arr = np.asarray(a)
    if arr.dtype.kind not in "fiu":
        raise ValueError(f"denoise: {name} must be a numeric array, got dtype {arr.dtype}")
    if arr.shape != shape:
        raise ValueError(f"denoise: {name} has shape {arr.shape}, expected {shape}")
    return np.ascontiguousarray(arr, np.float32)


def _halves(f: Feature, name: str, shape: Tuple[int, ...]) -> Tuple[np.ndarray, np.ndarray]:
    if isinstance(f, (tuple, list)):
        if len(f) != 2:
            raise ValueError(f"denoise: {name} must be one array or a pair (even, odd), got {len(f)} arrays")
        return _image(f[0], f"{name}[0]", shape), _image(f[1], f"{name}[1]", shape)
    one = _image(f, name, shape)
    return one, one


def denoise(rgb_even: np.ndarray, rgb_odd: np.ndarray, albedo: Feature, normal: Feature, depth: Feature,
            variance: Optional[np.ndarray] = None, **settings: Any) -> np.ndarray:
    """The denoised H x W x 3 float32 linear image of a render from its half-sample images
    ``rgb_even`` / ``rgb_odd`` (H x W x 3) and its features: ``albedo`` and ``normal``
    (H x W x 3) and ``depth`` (H x W, +inf on background), each one array or a pair
    (even, odd). ``variance`` (optional, H x W x 3): the variance of the mean
    (``RenderResult.variance``); without it the noise is estimated from the halves.
    ``settings``: see :data:`SETTINGS` (radius, patch_radius, k, feature_radius,
    selection_radius, albedo_floor, ridge, firefly_ratio, second_pass, distance_floor,
    normal_weight). Raises ValueError on bad shapes or settings."""
    unknown = sorted(set(settings) - set(SETTINGS))
    if unknown:
        raise ValueError(f"denoise: unknown setting(s) {unknown}; known: {sorted(SETTINGS)}")
    even = np.asarray(rgb_even)
    if even.ndim != 3 or even.shape[2] != 3 or even.shape[0] == 0 or even.shape[1] == 0:
        raise ValueError(f"denoise: rgb_even must be a non-empty H x W x 3 array, got shape {even.shape}")
    h, w = even.shape[:2]
    rgb3, rgb1 = (h, w, 3), (h, w)
    a = _image(rgb_even, "rgb_even", rgb3)
    b = _image(rgb_odd, "rgb_odd", rgb3)
    al = _halves(albedo, "albedo", rgb3)
    no = _halves(normal, "normal", rgb3)
    de = _halves(depth, "depth", rgb1)
    var = None if variance is None else _image(variance, "variance", rgb3)
    opts = dict(SETTINGS)
    opts.update(settings)
    return _denoise(a, b, al[0], al[1], no[0], no[1], de[0], de[1], var, **opts)
