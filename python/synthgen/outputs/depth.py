"""Output kinds ``depth`` (camera z in metres, float32 EXR, +inf on background) and
``depth16`` (uint16 millimetres PNG, 0 = no surface or beyond 65.535 m)."""
from __future__ import annotations

import numpy as np

from .files import write_exr, write_id_png
from .registry import Frame, OutputKind, register


def write_depth(path: str, frame: Frame) -> str:
    return write_exr(path, np.asarray(frame.arrays["depth"], np.float32))


def depth_mm16(depth: np.ndarray) -> np.ndarray:
    """Depth in whole millimetres as uint16; 0 where there is no surface or it lies beyond
    65.535 m."""
    depth = np.asarray(depth, np.float32)
    mm = np.where(np.isfinite(depth), np.round(depth * 1000.0), 0.0)
    return np.where(mm > 65535, 0, mm).astype(np.uint16)


def write_depth16(path: str, frame: Frame) -> str:
    return write_id_png(path, depth_mm16(frame.arrays["depth"]))


register(OutputKind("depth", "camera-space z in metres, float32 EXR, +inf on background", order=30,
                    directory="depth", extension=".exr", write=write_depth, module=__name__))
register(OutputKind("depth16", "depth in millimetres, uint16 PNG, 0 = no surface or beyond 65.535 m", order=40,
                    directory="depth16", extension=".png", write=write_depth16, default=False, module=__name__))
