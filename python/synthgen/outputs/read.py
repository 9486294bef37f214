"""Reading a dataset back: :func:`read_dataset` gives its frames as
:class:`synthgen.FrameData` (numpy arrays + labels), by index or by split, and -- when torch
is importable -- a ``torch.utils.data.Dataset`` in torchvision's detection format::

    ds = synthgen.read_dataset("out/ds")
    len(ds), ds.class_names, ds.splits["val"]
    frame = ds[0]                     # FrameData: rgb, depth, instance_id, objects, boxes_xyxy, ...
    for frame in ds.split("train"): ...
    train = ds.torch("train")         # (image 3xHxW float in [0, 1], {"boxes", "labels", "masks", ...})

Only complete frames are read (their metadata parses and lists existing files). The image is
``images/NNNNNN.exr`` (linear) when the dataset has it, else the PNG decoded to linear.
"""
from __future__ import annotations

import os
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence

import numpy as np

from .._core import SynthgenError
from .data import FrameData
from .meta import frame_status, read_meta
from .registry import frame_name
from .split import SPLITS, read_splits

__all__ = ["Dataset", "read_dataset"]


def _read(path: str, kind: str) -> np.ndarray:
    """Pixels of one file: ids and depth16 as stored (uint), everything else as float32
    (8-bit sRGB images decoded to linear, by the isolated reader)."""
    import OpenImageIO as oiio

    from .._core import read_image

    if kind in ("instance", "semantic", "depth16"):
        buf = oiio.ImageBuf(path)
        if buf.has_error:
            raise SynthgenError(f"{path}: {buf.geterror()}")
        return np.asarray(buf.get_pixels(oiio.UINT16))[..., 0].astype(np.uint32)
    px = np.asarray(read_image(path, "auto", finite=kind not in ("depth", "rgb_exr")), np.float32)
    return px[..., 0] if kind == "depth" else px


class Dataset:
    """The complete frames of a dataset directory (see the module docstring)."""

    def __init__(self, root: str):
        self.root = os.path.abspath(root)
        if not os.path.isdir(os.path.join(self.root, "meta")):
            raise SynthgenError(f"{root}: not a synthgen dataset (no meta/ directory)")
        complete, _ = frame_status(self.root)
        self.frames: List[int] = sorted(complete)
        self._split = read_splits(self.root)
        first = self.meta(self.frames[0]) if self.frames else {}
        #: Class names in order (class id = index + 1).
        self.class_names: List[str] = list(first.get("class_names", []))

    def __len__(self) -> int:
        return len(self.frames)

    @property
    def splits(self) -> Dict[str, List[int]]:
        """Frame indices per split (empty lists when the dataset has no split)."""
        return {s: [k for k in self.frames if self._split.get(k) == s] for s in SPLITS}

    def meta(self, k: int) -> Dict[str, Any]:
        return read_meta(os.path.join(self.root, "meta", frame_name(k) + ".json"))

    def frame(self, k: int) -> FrameData:
        """Frame ``k`` (its index in the dataset, as in its file names)."""
        meta = self.meta(k)
        files = meta["files"]

        def get(*kinds: str) -> Optional[np.ndarray]:
            for kind in kinds:
                if kind in files:
                    a = _read(os.path.join(self.root, files[kind]), kind)
                    if kind == "depth16":  # millimetres, 0 = none -> metres, +inf
                        a = np.where(a > 0, a.astype(np.float32) / 1000.0, np.float32(np.inf)).astype(np.float32)
                    return a
            return None

        return FrameData(index=int(k), rgb=get("rgb_exr", "rgb"), depth=get("depth", "depth16"),
                         instance_id=get("instance"), class_id=get("semantic"), normal=get("normal"),
                         albedo=get("albedo"), meta=meta)

    def __getitem__(self, i: int) -> FrameData:
        """The i-th complete frame (``ds[i]``; ``ds.frame(k)`` takes a frame index)."""
        return self.frame(self.frames[i])

    def __iter__(self) -> Iterator[FrameData]:
        for k in self.frames:
            yield self.frame(k)

    def split(self, name: str) -> Iterator[FrameData]:
        """The frames of a split ("train", "val", "test")."""
        if name not in SPLITS:
            raise SynthgenError(f"unknown split {name!r}; the splits are {', '.join(SPLITS)}")
        for k in self.splits[name]:
            yield self.frame(k)

    def torch(self, split: Optional[str] = None, transform: Optional[Callable[..., Any]] = None) -> Any:
        """A ``torch.utils.data.Dataset`` of the frames (of one split): items are (image,
        target) as torchvision's detection models take them -- image 3 x H x W float32 in
        [0, 1] (sRGB, as a camera's), target {"boxes" N x 4 xyxy float32, "labels" N int64,
        "masks" N x H x W uint8, "image_id", "area", "iscrowd"}; ``transform(image, target)``
        is applied last. torch is not a dependency: SynthgenError when it is missing."""
        try:
            import torch
            from torch.utils.data import Dataset as TorchDataset
        except ImportError:
            raise SynthgenError("Dataset.torch needs PyTorch (import torch failed); the frames themselves "
                                "are numpy: iterate the dataset instead") from None
        frames = self.frames if split is None else self.splits[split] if split in SPLITS else None
        if frames is None:
            raise SynthgenError(f"unknown split {split!r}; the splits are {', '.join(SPLITS)}")
        owner = self

        class _Frames(TorchDataset):  # type: ignore[misc, valid-type]
            def __len__(self) -> int:
                return len(frames)

            def __getitem__(self, i: int) -> Any:
                f = owner.frame(frames[i])
                image = torch.as_tensor(np.ascontiguousarray(f.image.transpose(2, 0, 1)), dtype=torch.float32) / 255.0
                boxes = f.boxes_xyxy
                masks = f.target_masks() if f.instance_id is not None \
                    else np.zeros((len(boxes),) + f.image.shape[:2], bool)
                target = {"boxes": torch.as_tensor(boxes, dtype=torch.float32),
                          "labels": torch.as_tensor(f.labels, dtype=torch.int64),
                          "masks": torch.as_tensor(masks.astype(np.uint8)),
                          "image_id": int(f.index),
                          "area": torch.as_tensor((boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1]),
                                                  dtype=torch.float32),
                          "iscrowd": torch.zeros(len(boxes), dtype=torch.int64)}
                return transform(image, target) if transform is not None else (image, target)

        return _Frames()


def read_dataset(root: str | os.PathLike) -> Dataset:
    """The dataset in directory ``root`` (see the module docstring)."""
    return Dataset(os.fspath(root))
