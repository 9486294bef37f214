"""Output kinds ``rgb`` (8-bit sRGB PNG) and ``rgb_exr`` (linear float32 EXR) of the image."""
from __future__ import annotations

from .files import write_exr, write_srgb_png
from .registry import Frame, OutputKind, register


def write_rgb(path: str, frame: Frame) -> str:
    return write_srgb_png(path, frame.arrays["rgb"])


def write_rgb_exr(path: str, frame: Frame) -> str:
    return write_exr(path, frame.arrays["rgb"])


register(OutputKind("rgb", "the image, sRGB 8-bit PNG", order=10, directory="images", extension=".png",
                    write=write_rgb, module=__name__))
register(OutputKind("rgb_exr", "the image, linear float32 EXR (lossless)", order=20, directory="images",
                    extension=".exr", write=write_rgb_exr, default=False, module=__name__))
