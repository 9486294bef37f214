"""Levels of detail of library models: how far each strays from the finest, and which one a
frame needs (docs/geometry_lod.md).

A library entry may list coarser versions of its model under ``lods`` (the TORCS cars ship
several), each with ``error``: the largest distance between its surface and the finest level's
(a symmetric Hausdorff distance, in mesh units), measured once by :func:`geometric_error` and
written into the manifest by ``tools/lod_errors.py``. Per frame, an object uses the coarsest
level whose error, projected into the image at the object's nearest point, stays under
``render.geometry_lod`` pixels (0.5 by default: no silhouette moves by half a pixel, so masks
hardly change; 0 keeps the finest level).
"""
from __future__ import annotations

import math
from typing import Sequence, Tuple

import numpy as np

from .._core import surface_distances

__all__ = ["surface_samples", "directed_error", "geometric_error", "projected_error_px", "choose_level"]


def surface_samples(positions: np.ndarray, indices: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Points of a triangle mesh's surface: its vertices, its edges' midpoints and ``n`` points
    drawn uniformly by area (float32, m x 3)."""
    pos = np.asarray(positions, np.float64)
    tri = np.asarray(indices, np.int64).reshape(-1, 3)
    a, b, c = pos[tri[:, 0]], pos[tri[:, 1]], pos[tri[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    if not area.sum() > 0:
        raise ValueError("surface_samples: the mesh has no area")
    pick = rng.choice(len(tri), size=n, p=area / area.sum())
    # NOTE: uniform point in a triangle by the square-root warp (Osada et al. 2002, "Shape
    # distributions", eq. 1): p = (1 - sqrt(r1)) a + sqrt(r1) (1 - r2) b + sqrt(r1) r2 c.
    r1, r2 = np.sqrt(rng.random(n))[:, None], rng.random(n)[:, None]
    inside = (1 - r1) * a[pick] + r1 * (1 - r2) * b[pick] + r1 * r2 * c[pick]
    mids = np.concatenate([0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)])
    return np.concatenate([pos, mids, inside]).astype(np.float32)


def directed_error(a: Tuple[np.ndarray, np.ndarray], b: Tuple[np.ndarray, np.ndarray], n: int,
                   rng: np.random.Generator) -> float:
    """The largest distance from a point of mesh ``a`` (positions, indices) to the surface of
    mesh ``b``, over ``a``'s vertices, edge midpoints and ``n`` area-uniform points (the exact
    distance to ``b``'s closest triangle each: Embree point queries)."""
    pts = surface_samples(a[0], a[1], n, rng)
    d = surface_distances(np.asarray(b[0], np.float32), np.asarray(b[1], np.int64).reshape(-1, 3), pts)
    return float(d.max())


def geometric_error(finest: Tuple[np.ndarray, np.ndarray], coarse: Tuple[np.ndarray, np.ndarray],
                    n: int = 200_000, seed: int = 0) -> float:
    """Symmetric Hausdorff distance between two meshes (positions, indices), in their units:
    the larger of the two directed errors. Sampled, so a lower bound of the true distance that
    approaches it as ``n`` grows; the largest distances sit at vertices (both meshes' are
    included), where a coarse level cuts a corner or a fine one has a feature the coarse lacks."""
    rng = np.random.default_rng(seed)
    return max(directed_error(finest, coarse, n, rng), directed_error(coarse, finest, n, rng))


def _camera_scale(camera) -> Tuple[float, float]:
    """(pixels per unit of tan(angle) at the image centre, the image's largest 1 + tan^2 of the
    angle off the optical axis) of a pinhole camera."""
    fx, fy = float(camera.fx), float(camera.fy)
    w, h, cx, cy = float(camera.width), float(camera.height), float(camera.cx), float(camera.cy)
    tx, ty = max(cx, w - cx) / fx, max(cy, h - cy) / fy
    return max(fx, fy), 1.0 + tx * tx + ty * ty


def projected_error_px(error: float, world_from_mesh: np.ndarray, lo: np.ndarray, hi: np.ndarray, camera) -> float:
    """An upper bound of how far, in pixels, a displacement of ``error`` mesh units of a model
    (bounds ``lo``..``hi``, placed by ``world_from_mesh``, 4 x 4) moves in the image of a
    pinhole ``camera``; inf when the model reaches the camera's plane.

    NOTE: projection x = f X / Z; a displacement e moves it by at most f e sqrt(1 + tan^2 t) / Z
    (t: the angle off the axis, bounded by the image's corner); Z is bounded below by the
    depth of the model's bounding sphere's nearest point, e (world) by e times the transform's
    largest singular value."""
    if error <= 0:
        return 0.0
    m = np.asarray(world_from_mesh, np.float64)
    stretch = float(np.linalg.norm(m[:3, :3], 2))
    centre = m[:3, :3] @ (0.5 * (np.asarray(lo) + np.asarray(hi))) + m[:3, 3]
    radius = 0.5 * float(np.linalg.norm(np.asarray(hi, np.float64) - np.asarray(lo, np.float64))) * stretch
    wfc = np.asarray(camera.world_from_camera, np.float64)
    z = float((wfc[:3, :3].T @ (centre - wfc[:3, 3]))[2]) - radius
    if z <= 1e-6:
        return math.inf
    f, corner = _camera_scale(camera)
    return f * error * stretch * math.sqrt(corner) / z


def choose_level(errors: Sequence[float], world_from_mesh: np.ndarray, lo: np.ndarray, hi: np.ndarray, camera,
                 max_px: float) -> int:
    """The coarsest level (index into ``errors``, finest first) whose projected error stays under
    ``max_px`` pixels; 0 (the finest) when none does or ``max_px`` is 0."""
    best = 0
    if max_px <= 0:
        return 0
    for k, e in enumerate(errors):
        if not k:
            continue
        if projected_error_px(e, world_from_mesh, lo, hi, camera) < max_px:
            best = k
    return best
