"""Output kinds ``normal`` (surface normals in the camera frame, float32 EXR) and ``albedo``
(surface albedo, linear float32 EXR): the first hit's geometry and reflectance, for normal
estimation, intrinsic decomposition and denoiser training.

``normal/NNNNNN.exr``: the shading normal of the first hit, as a unit vector in the OpenCV
camera frame of the frame's metadata (x right, y down, z forward: a surface facing the camera
has z < 0), 0 on background. ``albedo/NNNNNN.exr``: the albedo of the first hit (linear; 0 on
background). Neither is touched by post-processing steps.
"""
from __future__ import annotations

import numpy as np

from .files import write_exr
from .registry import Frame, OutputKind, register

__all__ = ["camera_normals"]


def camera_normals(world_normals: np.ndarray, world_from_camera: np.ndarray) -> np.ndarray:
    """World-space normals (H x W x 3) in the camera frame (the rotation part of
    world_from_camera, inverted; background zeros stay zero)."""
    r = np.asarray(world_from_camera, np.float64)[:3, :3]
    n = np.asarray(world_normals, np.float64) @ r  # (R^T n) for each pixel, as rows
    return n.astype(np.float32)


def write_normal(path: str, frame: Frame) -> str:
    n = camera_normals(frame.arrays["normal"], np.asarray(frame.meta["camera"]["world_from_camera"]))
    return write_exr(path, n, channel_names=("X", "Y", "Z"))


def write_albedo(path: str, frame: Frame) -> str:
    return write_exr(path, np.asarray(frame.arrays["albedo"], np.float32))


register(OutputKind("normal", "shading normals of the first hit in the camera frame (OpenCV axes), float32 EXR",
                    order=45, directory="normal", extension=".exr", write=write_normal, default=False,
                    module=__name__))
register(OutputKind("albedo", "albedo of the first hit, linear float32 EXR", order=46, directory="albedo",
                    extension=".exr", write=write_albedo, default=False, module=__name__))
