"""Fog on a photo with inserted objects, in image space (weather fog and haze over photo
backgrounds, docs/weather.md): Koschmieder's law over the composite,

    I = J t + A (1 - t),   t = exp(-beta s),

J the composite without fog, beta = 3.912 / visibility (the medium's extinction), s the length
of each pixel's camera ray inside the fog layer up to what the pixel sees -- the photo's depth
map where the pixel is the photo, the render's depth where an inserted object is, so photo and
objects are fogged alike -- and A the airlight: the colour of the fog at an infinite distance,
estimated from the photo by the dark channel prior (He, Sun & Tang 2009, "Single image haze
removal using dark channel prior", sec. 4.4): the mean colour of the photo's pixels at the
brightest 0.1% of its dark channel (the per-pixel minimum over R, G, B and a 15 x 15 window),
which in a photo with sky is the sky near the horizon and without one its brightest white. The
mean of those pixels rather than the brightest one keeps a specular glint from deciding it.
Single scattering of a homogeneous layer in a uniformly lit atmosphere; the render's fog
(the ``homogeneous`` medium, path traced) is not used here, for the photo has none.
"""
from __future__ import annotations

from typing import Any, Optional, Tuple

import numpy as np

__all__ = ["dark_channel", "airlight", "ray_directions", "layer_path", "koschmieder"]


def dark_channel(rgb: np.ndarray, window: int = 15) -> np.ndarray:
    """min over R, G, B and a window x window neighbourhood (He et al. 2009, eq. 5)."""
    from scipy.ndimage import minimum_filter

    return minimum_filter(np.asarray(rgb, np.float32)[..., :3].min(axis=2), size=int(window), mode="nearest")


def airlight(photo: np.ndarray, share: float = 0.001, window: int = 15) -> np.ndarray:
    """The airlight A (linear RGB) of a photo: the mean colour of its pixels at the brightest
    ``share`` of its dark channel."""
    px = np.asarray(photo, np.float32)[..., :3]
    dc = dark_channel(px, window).reshape(-1)
    k = max(1, int(round(share * dc.size)))
    top = np.argpartition(dc, dc.size - k)[dc.size - k:]
    return px.reshape(-1, 3)[top].astype(np.float64).mean(axis=0)


def ray_directions(camera: Any, shape: Tuple[int, int]) -> Tuple[np.ndarray, np.ndarray]:
    """(world unit directions H x W x 3, length per unit of camera z H x W) of the pixel-centre
    rays of a PinholeCamera (through its lens distortion when it has one)."""
    h, w = shape
    x = (np.arange(w) + 0.5 - camera.cx) / camera.fx
    y = (np.arange(h) + 0.5 - camera.cy) / camera.fy
    xs, ys = np.meshgrid(x, y)
    if any(float(k) != 0.0 for k in camera.distortion):
        und = np.array([camera.undistort(float(a), float(b)) or (float(a), float(b))
                        for a, b in zip(xs.ravel(), ys.ravel())], np.float64)
        xs, ys = und[:, 0].reshape(h, w), und[:, 1].reshape(h, w)
    d = np.stack([xs, ys, np.ones_like(xs)], axis=-1)
    per_z = np.linalg.norm(d, axis=-1)
    m = np.asarray(camera.world_from_camera, np.float64)
    world = (d / per_z[..., None]) @ m[:3, :3].T
    return world, per_z


def layer_path(origin_y: float, dir_y: np.ndarray, distance: np.ndarray, top: float,
               bottom: Optional[float] = None) -> np.ndarray:
    """Length of each ray's first ``distance`` metres inside the layer bottom <= y <= top
    (bottom None: all the way down), as the medium counts it (cpp/medium/homogeneous.cpp)."""
    dist = np.asarray(distance, np.float64)
    dy = np.asarray(dir_y, np.float64)
    lo = -np.inf if bottom is None else float(bottom)
    with np.errstate(divide="ignore", invalid="ignore"):
        ta = np.where(dy != 0, (lo - origin_y) / dy, np.where(origin_y >= lo, -np.inf, np.inf))
        tb = np.where(dy != 0, (float(top) - origin_y) / dy, np.where(origin_y <= top, np.inf, -np.inf))
        t0 = np.maximum(np.minimum(ta, tb), 0.0)
        t1 = np.minimum(np.maximum(ta, tb), dist)
        # Rays parallel to the layer's planes: all or nothing.
        flat = dy == 0
        inside = (origin_y >= lo) & (origin_y <= top)
        t0 = np.where(flat, 0.0, t0)
        t1 = np.where(flat, np.where(inside, dist, 0.0), t1)
        length = np.maximum(t1 - t0, 0.0)
    return np.where(np.isnan(length), 0.0, length)


def koschmieder(rgb: np.ndarray, transmittance: np.ndarray, airlight_rgb: np.ndarray) -> np.ndarray:
    """I = J t + A (1 - t) per pixel."""
    t = np.asarray(transmittance, np.float32)[..., None]
    a = np.asarray(airlight_rgb, np.float32)[None, None, :]
    j = np.asarray(rgb, np.float32)
    out = j[..., :3] * t + a * (1.0 - t)
    if j.shape[2] > 3:
        out = np.concatenate([out, j[..., 3:]], axis=2)
    return out.astype(np.float32)
