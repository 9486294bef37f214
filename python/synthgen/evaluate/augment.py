"""Training-time augmentation of the reference detector: a random scale, a crop (or padding) to
the training size, a horizontal flip and a photometric jitter, each an option, applied to one
image and its boxes at a time. Numpy, with Pillow's resampling (:func:`resize`).

:class:`Augment` holds the options (``Augment()`` = the defaults below, ``Augment.none()`` = no
augmentation: the image placed at the top left of the training size, cut or padded, as
``Detector.detect`` pads). :func:`apply` takes an image (``H x W x 3`` uint8 RGB), its boxes
(``N x 4`` x0 y0 x1 y1 px) and a numpy ``Generator`` and returns the augmented image of exactly
``size`` (rows, columns), the boxes moved with it, and per box the fraction of its area left
inside the crop. The caller turns a box mostly cut away into an ignore region
(:data:`MIN_KEPT`): a car cut to its rear bumper is neither a car to learn nor background.

The order: scale (the image and boxes by ``s``, log-uniform in ``scale``), then a crop of
``size`` at a uniform offset (where the scaled image is smaller than ``size`` along a side, it
is placed at a uniform offset in the padding, which is black, as ``Detector.detect`` pads),
then the flip (probability ``flip``), then brightness, contrast and saturation factors, each
uniform in ``[1 - j, 1 + j]`` for ``j`` = ``brightness`` etc. (torchvision's ``ColorJitter``
definitions on values 0..1, in random order), rounded back to uint8. Every random number comes
from the given generator, so a sample's augmentation depends on its generator's seed alone (the
trainer seeds one per batch slot: the same whatever the number of data workers).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional, Tuple

import numpy as np

from .._core import SynthgenError

__all__ = ["Augment", "MIN_KEPT", "apply", "resize", "place"]

#: A box that keeps less of its area than this inside the crop becomes an ignore region.
MIN_KEPT = 0.5


@dataclass(frozen=True)
class Augment:
    """Augmentation options (see the module docstring)."""
    scale: Tuple[float, float] = (0.75, 1.33)   #: the scale's range (log-uniform); (1, 1): none
    crop: bool = True                           #: a random crop offset (else the top left)
    flip: float = 0.5                           #: probability of a horizontal flip
    brightness: float = 0.25                    #: brightness factor in [1 - b, 1 + b]
    contrast: float = 0.25                      #: contrast factor in [1 - c, 1 + c]
    saturation: float = 0.25                    #: saturation factor in [1 - s, 1 + s]

    def __post_init__(self) -> None:
        lo, hi = (float(v) for v in self.scale)
        if not (0 < lo <= hi < 16):
            raise SynthgenError(f"augment: scale range {tuple(self.scale)} must be 0 < low <= high < 16")
        if not 0 <= self.flip <= 1:
            raise SynthgenError(f"augment: flip probability {self.flip} outside [0, 1]")
        for name in ("brightness", "contrast", "saturation"):
            v = getattr(self, name)
            if not 0 <= v < 1:
                raise SynthgenError(f"augment: {name} {v} outside [0, 1)")

    @classmethod
    def none(cls) -> "Augment":
        """No augmentation: the image at the top left, cut or padded to the training size."""
        return cls(scale=(1.0, 1.0), crop=False, flip=0.0, brightness=0.0, contrast=0.0, saturation=0.0)

    def describe(self) -> dict:
        return {"scale": list(self.scale), "crop": self.crop, "flip": self.flip, "brightness": self.brightness,
                "contrast": self.contrast, "saturation": self.saturation}


def resize(image: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """``image`` (H x W x 3 uint8) resampled to ``rows`` x ``cols``: bilinear, antialiased when
    shrinking (Pillow's ``BILINEAR``, whose filter widens with the reduction; within 1 of
    PyTorch's ``interpolate(antialias=True)`` and 1.6-2.3 times faster on a 676 x 380 frame
    scaled by 0.8-1.25, which matters: the data workers, not the GPU, bound training on the
    accelerator)."""
    if image.shape[:2] == (rows, cols):
        return image
    from PIL import Image  # lazily, as the package's other Pillow users (a module lookup per call)

    return np.asarray(Image.fromarray(np.ascontiguousarray(image)).resize((cols, rows), Image.BILINEAR))


def place(image: np.ndarray, size: Tuple[int, int], top: int, left: int) -> np.ndarray:
    """The ``size`` (rows, columns) window of ``image`` whose top-left corner is at image row
    ``top``, column ``left`` (negative: the image starts inside the window); outside the image
    the window is black."""
    rows, cols = size
    out = np.zeros((rows, cols, 3), np.uint8)
    H, W = image.shape[:2]
    y0, x0 = max(top, 0), max(left, 0)
    y1, x1 = min(top + rows, H), min(left + cols, W)
    if y1 > y0 and x1 > x0:
        out[y0 - top:y1 - top, x0 - left:x1 - left] = image[y0:y1, x0:x1]
    return out


def _offset(extent: int, window: int, rng: Optional[np.random.Generator]) -> int:
    """Top/left of the window in image coordinates: inside the image when it is larger, else
    negative (the image inside the window)."""
    slack = extent - window
    if rng is None or slack == 0:
        return 0
    return int(rng.integers(0, slack + 1)) if slack > 0 else -int(rng.integers(0, -slack + 1))


def _jitter(img: np.ndarray, aug: Augment, rng: np.random.Generator) -> np.ndarray:
    """Brightness, contrast, saturation (torchvision ColorJitter's formulas), random order."""
    steps = [(name, getattr(aug, name)) for name in ("brightness", "contrast", "saturation")]
    if not any(v > 0 for _, v in steps):
        return img
    x = img.astype(np.float32)
    x *= np.float32(1 / 255.0)
    order = rng.permutation(len(steps))
    factors = [float(rng.uniform(1 - v, 1 + v)) if v > 0 else 1.0 for _, v in steps]
    luma = np.array([0.299, 0.587, 0.114], np.float32)
    # in place, float32 (a third faster than fresh arrays: this runs per training sample)
    for i in order:
        name, f = steps[i][0], factors[i]
        if f == 1.0:
            continue
        # NOTE: torchvision.transforms.functional: grayscale = 0.299 R + 0.587 G + 0.114 B;
        # contrast blends with the image's mean grey, saturation with each pixel's grey.
        if name == "brightness":
            x *= np.float32(f)
        elif name == "contrast":
            mean = np.float32((x @ luma).mean())
            x *= np.float32(f)
            x += mean * np.float32(1 - f)
        else:
            grey = x @ luma
            grey *= np.float32(1 - f)
            x *= np.float32(f)
            x += grey[..., None]
        np.maximum(x, 0.0, out=x)
        np.minimum(x, 1.0, out=x)
    x *= np.float32(255.0)
    return np.rint(x, out=x).astype(np.uint8)


def apply(image: np.ndarray, boxes: Any, size: Tuple[int, int], aug: Augment,
          rng: Optional[np.random.Generator]) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(image, boxes, kept)``: ``image`` augmented to exactly ``size`` (rows, columns), the
    boxes (N x 4 px, clipped to the window) and the fraction of each box's area inside the
    window (0 for a box entirely outside). ``rng`` None: no augmentation (as
    :meth:`Augment.none`)."""
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 3 or a.dtype != np.uint8:
        raise SynthgenError(f"augment: expected an H x W x 3 uint8 RGB image, got {a.shape} of {a.dtype}")
    b = np.asarray(boxes, np.float64).reshape(-1, 4).copy()
    rows, cols = int(size[0]), int(size[1])
    if rng is None:
        aug = Augment.none()
    lo, hi = aug.scale
    s = 1.0 if lo == hi or rng is None else float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
    H, W = a.shape[:2]
    if s != 1.0:
        nh, nw = max(1, int(round(H * s))), max(1, int(round(W * s)))
        a = resize(a, nh, nw)
        b *= [nw / W, nh / H, nw / W, nh / H]
        H, W = nh, nw
    top = _offset(H, rows, rng if aug.crop else None)
    left = _offset(W, cols, rng if aug.crop else None)
    a = place(a, (rows, cols), top, left)
    b -= [left, top, left, top]
    area = np.maximum(b[:, 2] - b[:, 0], 0) * np.maximum(b[:, 3] - b[:, 1], 0)
    b = np.clip(b, 0, [cols, rows, cols, rows])
    inside = np.maximum(b[:, 2] - b[:, 0], 0) * np.maximum(b[:, 3] - b[:, 1], 0)
    kept = np.where(area > 0, inside / np.where(area > 0, area, 1), 0.0)
    if rng is not None and aug.flip > 0 and rng.random() < aug.flip:
        a = np.ascontiguousarray(a[:, ::-1])
        b = np.stack((cols - b[:, 2], b[:, 1], cols - b[:, 0], b[:, 3]), 1) if len(b) else b
    if rng is not None:
        a = _jitter(a, aug, rng)
    return a, b, kept
