"""Reading the images a detector trains on and is scored on: :func:`read_rgb8` returns an image
file as ``H x W x 3`` uint8 RGB, as a viewer shows it (EXIF orientation applied).

Through synthgen's own reader (``synthgen._core.read_image_info``: OpenImageIO, with every
decoder warning that is not a known metadata warning an error, a JPEG walked to its end-of-image
marker; docs/architecture.md, "Untrusted files"), so a truncated photo is an error here as
everywhere in synthgen, never a grey training image. Grey images are repeated into RGB, an
alpha channel dropped; 16-bit and float files are rounded from 0..1 to 8 bits.

Where synthgen's compiled core is not there (the training machine of ``bench/sim2real.py``,
which runs this stage alone), Pillow reads the file with its truncated-image tolerance off
(a file cut short is an error there too).
"""
from __future__ import annotations

import numpy as np

from .._core import SynthgenError

__all__ = ["read_rgb8"]


def _pillow(path: str) -> np.ndarray:
    from PIL import Image, ImageFile, ImageOps

    ImageFile.LOAD_TRUNCATED_IMAGES = False
    try:
        with Image.open(path) as im:
            im.load()
            im = ImageOps.exif_transpose(im).convert("RGB")
            return np.asarray(im, np.uint8).copy()
    except (OSError, ValueError, SyntaxError) as e:
        raise SynthgenError(f"{path}: cannot read the image: {e}") from None


def read_rgb8(path: str) -> np.ndarray:
    """The image file ``path`` as H x W x 3 uint8 RGB (see the module docstring); SynthgenError
    naming the file when it is missing, damaged or not an image."""
    try:
        from .._core import read_image_info
    except ImportError:
        return _pillow(path)
    from ..background.photos import apply_orientation

    pixels, info = read_image_info(path)
    if pixels.shape[2] in (1, 2):
        pixels = np.repeat(pixels[:, :, :1], 3, axis=2)
    pixels = apply_orientation(pixels[:, :, :3], info["orientation"])
    return np.ascontiguousarray(np.clip(np.rint(pixels * 255.0), 0, 255).astype(np.uint8))
