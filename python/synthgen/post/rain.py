"""Post-processing step ``rain``: falling rain as an image-space step -- motion-blurred streaks
of the drops between the camera and the scene, and the veil of the rain beyond them. Labels
are untouched: rain is not an object (the instance, class and depth images stay the render's).

The drops (:func:`rain_streaks`, a pure function of the image, its depth and a generator):

- sizes from the Marshall-Palmer distribution of a rain ``rate`` R (mm/h): N(D) = 8000
  exp(-4.1 R^-0.21 D) per m^3 per mm of diameter D (Marshall & Palmer 1948), D in
  [0.5, 6] mm; they fall at their terminal velocity v(D) = 9.65 - 10.3 exp(-0.6 D) m/s (Atlas,
  Srivastava & Sekhon 1973), tilted by the ``wind``;
- spread uniformly through the camera's view between ``near`` and ``far`` metres (so their
  number per pixel grows with the square of the distance); each is a straight streak, the
  path its image travels during the ``exposure``, of length f v T / z pixels and width f D / z
  -- near drops long and wide, far ones short and thin;
- each streak is a drop seen for part of the exposure (Garg & Nayar 2004, "Detection and removal
  of rain from videos"; 2006, "Photorealistic rendering of rain streaks"): a pixel it crosses
  gets I = (1 - a) I_background + a E_drop with a the fraction of the exposure the drop covers
  it -- summed over the streak, the drop's image area, spread over its length: a = (pi / 4) D /
  (v T) where the drop is wider than a pixel, less in proportion to its area below that (far
  drops fade); E_drop, the drop's radiance, is the environment a drop refracts towards the
  camera from a cone of about 165 degrees (mostly the bright sky above), estimated as the
  mean of the image's brightest 10% (``brightness`` scales it);
- a streak point nearer than the surface the pixel sees (``depth``, camera z) is drawn, one
  behind it is not: rain falls in front of the scene, never through it;
- beyond ``far`` the drops are too small to see one by one and act as a veil: Koschmieder's
  I = I t + A (1 - t), t = exp(-beta (d - far)) along each pixel's ray (d up to 1 km: rain
  shafts end), beta = (pi / 2) integral D^2 N(D) dD (extinction efficiency 2 of drops much
  larger than the wavelength), about 1.5e-3 per metre at 10 mm/h (visibility 2.5 km); A the
  same environment estimate; ``veil`` scales beta.

The streaks' random positions come from the generator (``seed`` here; a weather condition
passes its own), so the result is deterministic.
"""
from __future__ import annotations

import math
from typing import Any, Dict, Mapping, Optional, Tuple

import numpy as np

from ..schema.fields import Integer, Number, Record
from . import Arrays, PostStep, register
from .photo.fog import koschmieder

__all__ = ["rain_streaks", "drop_density", "rain_extinction", "SCHEMA", "ray_lengths"]

#: Marshall-Palmer: N0 (per m^3 per mm) and the drop diameters drawn (mm).
N0, D_MIN, D_MAX = 8000.0, 0.5, 6.0


def _slope(rate: float) -> float:
    """Marshall-Palmer's Lambda (per mm) of a rain rate (mm/h)."""
    return 4.1 * max(float(rate), 1e-6) ** -0.21


def drop_density(rate: float) -> float:
    """Drops per m^3 with diameters in [D_MIN, D_MAX] mm."""
    lam = _slope(rate)
    return N0 / lam * (math.exp(-lam * D_MIN) - math.exp(-lam * D_MAX)) if rate > 0 else 0.0


def rain_extinction(rate: float) -> float:
    """Extinction coefficient (per metre) of rain of ``rate`` mm/h: (pi / 2) integral D^2 N(D)
    dD over all drops, i.e. (pi / 2) 2 N0 / Lambda^3 mm^2 per m^3."""
    if rate <= 0:
        return 0.0
    return math.pi / 2.0 * 2.0 * N0 / _slope(rate) ** 3 * 1e-6


def terminal_velocity(d_mm: np.ndarray) -> np.ndarray:
    """m/s (Atlas, Srivastava & Sekhon 1973)."""
    return 9.65 - 10.3 * np.exp(-0.6 * np.asarray(d_mm))


def ray_lengths(shape: Tuple[int, int], fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    """Per pixel, the length of the pixel-centre ray per unit of camera z (distance = z x it)."""
    h, w = shape
    x = (np.arange(w) + 0.5 - cx) / fx
    y = (np.arange(h) + 0.5 - cy) / fy
    return np.sqrt(1.0 + x[None, :] ** 2 + y[:, None] ** 2)


def environment(rgb: np.ndarray) -> np.ndarray:
    """The radiance a drop refracts towards the camera, estimated as the mean colour of the
    image's brightest 10% (by luminance; mostly sky)."""
    a = np.asarray(rgb, np.float64)[..., :3].reshape(-1, 3)
    y = a @ np.array([0.2126, 0.7152, 0.0722])
    k = max(1, len(y) // 10)
    top = np.argpartition(y, len(y) - k)[len(y) - k:]
    return a[top].mean(axis=0)


def rain_streaks(rgb: np.ndarray, depth: np.ndarray, rng: np.random.Generator, *, fx: float, fy: float,
                 cx: float, cy: float, rate: float = 10.0, exposure: float = 0.004, wind: float = 0.0,
                 brightness: float = 1.0, near: float = 0.3, far: float = 8.0, veil: float = 1.0,
                 world_from_camera: Optional[np.ndarray] = None) -> Tuple[np.ndarray, Dict[str, Any]]:
    """The image with rain (see the module docstring): (rgb, info). ``depth``: camera z per
    pixel (+inf: nothing); ``world_from_camera`` (4 x 4) gives the direction of gravity in the
    image (default: a level camera, world up = -y of the image)."""
    img = np.asarray(rgb, np.float32)
    h, w = img.shape[:2]
    z_surf = np.asarray(depth, np.float32)
    env = environment(img)
    e_drop = (env * float(brightness)).astype(np.float32)
    # Gravity and the wind (across the view, to the right) in camera coordinates (x right,
    # y down, z forward).
    if world_from_camera is None:
        down, right = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    else:
        r = np.asarray(world_from_camera, np.float64)[:3, :3]
        down = r.T @ np.array([0.0, -1.0, 0.0])
        xr = r[:, 0].copy()
        xr[1] = 0.0
        n = np.linalg.norm(xr)
        right = r.T @ (xr / n) if n > 1e-9 else np.array([1.0, 0.0, 0.0])
    n_drops = 0
    alpha = np.zeros(h * w, np.float64)
    if rate > 0 and far > near:
        # Positions at mid-exposure: uniform over the view (with a margin for streaks that
        # enter the frame) between near and far, z with density ~ z^2.
        margin = 0.25 * max(w, h)
        area = (w + 2 * margin) * (h + 2 * margin) / (fx * fy)   # m^2 per m^2 of z^2
        volume = area * (far ** 3 - near ** 3) / 3.0
        n_drops = int(rng.poisson(drop_density(rate) * volume))
        u = rng.uniform(-margin, w + margin, n_drops)
        v = rng.uniform(-margin, h + margin, n_drops)
        z = np.cbrt(near ** 3 + rng.random(n_drops) * (far ** 3 - near ** 3))
        lam = _slope(rate)
        c = rng.random(n_drops)  # D from the exponential truncated to [D_MIN, D_MAX]
        e0, e1 = math.exp(-lam * D_MIN), math.exp(-lam * D_MAX)
        d_mm = -np.log(e0 - c * (e0 - e1)) / lam
        speed = terminal_velocity(d_mm)
        p = np.stack([(u - cx) * z / fx, (v - cy) * z / fy, z], axis=1)
        vel = speed[:, None] * down[None, :] + float(wind) * right[None, :]
        half = 0.5 * float(exposure) * vel
        a, b = p - half, p + half
        a[:, 2] = np.maximum(a[:, 2], 1e-3)
        b[:, 2] = np.maximum(b[:, 2], 1e-3)
        ua, va = fx * a[:, 0] / a[:, 2] + cx, fy * a[:, 1] / a[:, 2] + cy
        ub, vb = fx * b[:, 0] / b[:, 2] + cx, fy * b[:, 1] / b[:, 2] + cy
        length = np.hypot(ub - ua, vb - va)
        diam = fx * d_mm * 1e-3 / z                       # the drop's image diameter, pixels
        width = np.maximum(diam, 1.0)
        mass = math.pi / 4.0 * diam ** 2                  # the streak's alpha summed over pixels
        # Samples along each streak (a pixel apart, splatted bilinearly) and across its width.
        n_along = (np.ceil(length) + 1).astype(np.int64)
        n_across = np.maximum(1, np.ceil(width)).astype(np.int64)
        n_s = n_along * n_across
        idx = np.repeat(np.arange(n_drops), n_s)
        start = np.repeat(np.cumsum(n_s) - n_s, n_s)
        k = np.arange(idx.size) - start
        i_along, i_across = k // n_across[idx], k % n_across[idx]
        t = ((i_along + 0.5) / n_along[idx]).astype(np.float32)
        ua, va, ub, vb = (x.astype(np.float32) for x in (ua, va, ub, vb))
        su = ua[idx] + t * (ub - ua)[idx]
        sv = va[idx] + t * (vb - va)[idx]
        # Across: offsets within the width, perpendicular to the streak.
        off = (((i_across + 0.5) / n_across[idx] - 0.5) * width[idx]).astype(np.float32)
        lu, lv = (ub - ua)[idx], (vb - va)[idx]
        ln = np.maximum(np.hypot(lu, lv), 1e-9)
        su, sv = su - off * lv / ln, sv + off * lu / ln
        za, zb = a[:, 2].astype(np.float32), b[:, 2].astype(np.float32)
        sz = za[idx] + t * (zb - za)[idx]
        weight = (mass / n_s).astype(np.float32)[idx]
        # Bilinear splats into the pixels whose surface lies behind the drop.
        fu, fv = su - 0.5, sv - 0.5
        iu, iv = np.floor(fu).astype(np.int64), np.floor(fv).astype(np.int64)
        du, dv = fu - iu, fv - iv
        for ou, ov, wt in ((0, 0, (1 - du) * (1 - dv)), (1, 0, du * (1 - dv)), (0, 1, (1 - du) * dv), (1, 1, du * dv)):
            x, y = iu + ou, iv + ov
            ok = (x >= 0) & (x < w) & (y >= 0) & (y < h)
            pix = y[ok] * w + x[ok]
            front = sz[ok] < z_surf.reshape(-1)[pix]
            alpha += np.bincount(pix[front], (weight[ok] * wt[ok])[front], minlength=h * w)
    a_img = np.minimum(alpha, 1.0).reshape(h, w, 1).astype(np.float32)
    out = img[..., :3] * (1.0 - a_img) + e_drop[None, None, :] * a_img
    beta = rain_extinction(rate) * float(veil)
    if beta > 0:
        dist = np.minimum(np.where(np.isfinite(z_surf), z_surf, np.inf) * ray_lengths((h, w), fx, fy, cx, cy), 1000.0)
        t_veil = np.exp(-beta * np.maximum(dist - float(far), 0.0)).astype(np.float32)
        out = koschmieder(out, t_veil, env)
    if img.shape[2] > 3:
        out = np.concatenate([out, img[..., 3:]], axis=2)
    info = {"drops": n_drops, "drop_radiance": [round(float(x), 6) for x in e_drop],
            "extinction": round(beta, 9), "streak_pixels": int((alpha > 1e-3).sum())}
    return out.astype(np.float32), info


SCHEMA = Record({
    "rate": Number(10.0, min=0.0, max=500.0, doc="rain rate, mm/h (drizzle 1, moderate 5-10, heavy 20-50): "
                                                 "the number and sizes of the drops"),
    "exposure": Number(0.004, min=1e-5, max=1.0, doc="exposure time, s (the streaks' length)"),
    "wind": Number(0.0, min=-50.0, max=50.0, doc="wind across the view, m/s (positive: to the right): tilts "
                                                 "the streaks"),
    "brightness": Number(1.0, min=0.0, max=100.0, doc="drop radiance / the environment's (the mean of the "
                                                      "image's brightest 10%)"),
    "near": Number(0.3, min=0.01, max=100.0, doc="nearest drops drawn, metres"),
    "far": Number(8.0, min=0.01, max=1000.0, doc="farthest drops drawn one by one, metres (beyond: the veil)"),
    "veil": Number(1.0, min=0.0, max=100.0, doc="scales the rain's extinction beyond far (0: no veil)"),
    "fov_y": Number(50.0, min=1.0, max=179.0, doc="the camera's vertical field of view, degrees (a post step "
                                                  "sees only the image; as weather: the frame's camera)"),
    "seed": Integer(0, min=0, max=(1 << 31) - 1, doc="the streaks' random positions (a distribution: new "
                                                     "rain per frame)"),
}, doc="rain")


def apply(arrays: Mapping[str, np.ndarray], params: Mapping[str, Any]) -> Arrays:
    out = dict(arrays)
    rgb = np.asarray(arrays["rgb"], np.float32)
    h, w = rgb.shape[:2]
    f = 0.5 * h / math.tan(math.radians(float(params["fov_y"])) / 2.0)
    depth = arrays.get("depth")
    if depth is None:
        depth = np.full((h, w), np.inf, np.float32)
    out["rgb"], _ = rain_streaks(rgb, depth, np.random.default_rng(int(params["seed"])), fx=f, fy=f,
                                 cx=0.5 * w, cy=0.5 * h,
                                 **{k: float(params[k]) for k in ("rate", "exposure", "wind", "brightness", "near",
                                                                  "far", "veil")})
    return out


register(PostStep("rain", "rain streaks in front of the scene and the rain's veil (labels untouched)", SCHEMA, apply,
                  module=__name__))
