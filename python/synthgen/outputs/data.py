"""One frame as arrays and labels: what :meth:`synthgen.Scenario.frames` yields (rendered in
memory) and :func:`synthgen.read_dataset` reads back from a dataset directory.

Arrays are numpy, H x W (x C): ``rgb`` float32 linear radiance (``image`` is its 8-bit
sRGB encoding), ``depth`` float32 camera z in metres (+inf: background), ``instance_id`` and
``class_id`` uint32 (0: background, ground and unlabelled objects), ``normal`` float32 unit
normals in the OpenCV camera frame, ``albedo`` float32 linear. An array a dataset did not
write is None. ``objects`` are the frame's labelled, visible objects (as the annotation
files have them); in a frame inserted into a photo, ``real_objects`` are the labelled objects the
photo shows and ``ignore_regions`` its regions to ignore; ``boxes_xyxy``, ``labels`` and
``target_masks()`` hold both kinds, inserted first (the order of COCO, YOLO and KITTI);
``meta`` is the frame's whole metadata.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

import numpy as np

__all__ = ["FrameData"]


@dataclass
class FrameData:
    """A frame's arrays and labels (see the module docstring)."""

    index: int
    rgb: Optional[np.ndarray]
    depth: Optional[np.ndarray] = None
    instance_id: Optional[np.ndarray] = None
    class_id: Optional[np.ndarray] = None
    normal: Optional[np.ndarray] = None
    albedo: Optional[np.ndarray] = None
    meta: Dict[str, Any] = field(default_factory=dict)

    @property
    def image(self) -> np.ndarray:
        """H x W x 3 uint8 sRGB encoding of ``rgb`` (what images/NNNNNN.png holds)."""
        from .files import to_srgb8

        if self.rgb is None:
            raise ValueError(f"frame {self.index} has no image")
        return to_srgb8(self.rgb)

    @property
    def class_names(self) -> List[str]:
        return list(self.meta.get("class_names", []))

    @property
    def objects(self) -> List[Dict[str, Any]]:
        """The labelled objects with visible pixels: class, class_id (1-based), instance_id,
        bbox [x, y, w, h] in pixels, occlusion, truncation, and the 3D fields (dimensions_hwl,
        location_camera, rotation_y) -- what COCO, YOLO and KITTI get."""
        return [o for o in self.meta.get("objects", [])
                if o.get("label", True) and not o.get("dropped") and o.get("visible_pixels")]

    def mask(self, instance_id: int) -> np.ndarray:
        """H x W bool visible mask of an object (from ``instance_id``, exact)."""
        if self.instance_id is None:
            raise ValueError(f"frame {self.index} has no instance mask (output 'instance')")
        return np.asarray(self.instance_id) == int(instance_id)

    @property
    def real_objects(self) -> List[Dict[str, Any]]:
        """A photo's labelled real objects: class, class_id, bbox [x0, y0, x1, y1], polygon (if
        known), visible_fraction (what inserted objects leave of it), truncation."""
        return [o for o in self.meta.get("real_objects", []) if not o["ignore"]]

    @property
    def ignore_regions(self) -> List[Dict[str, Any]]:
        """A photo's regions to ignore (crowds, DontCare, real objects mostly hidden), bbox [x0, y0, x1, y1]."""
        return [o for o in self.meta.get("real_objects", []) if o["ignore"]]

    @property
    def boxes_xyxy(self) -> np.ndarray:
        """N x 4 float32 boxes [x0, y0, x1, y1] (pixel edges) of :attr:`objects`, then of
        :attr:`real_objects`."""
        b = np.array([o["bbox"] for o in self.objects], np.float32).reshape(-1, 4)
        b[:, 2:] += b[:, :2]
        r = np.array([o["bbox"] for o in self.real_objects], np.float32).reshape(-1, 4)
        return np.concatenate([b, r])

    @property
    def labels(self) -> np.ndarray:
        """N int64 class ids (1-based, COCO category ids) of :attr:`objects`, then of :attr:`real_objects`."""
        return np.array([o["class_id"] for o in self.objects] + [o["class_id"] for o in self.real_objects], np.int64)

    def target_masks(self) -> np.ndarray:
        """N x H x W bool masks of :attr:`boxes_xyxy`'s objects: inserted ones exact (from
        ``instance_id``), real ones from their polygon (or box)."""
        from ..background.labels import object_mask

        h, w = (self.rgb if self.rgb is not None else self.instance_id).shape[:2]
        out = [self.mask(o["instance_id"]) for o in self.objects]
        out += [object_mask(None if not o.get("polygon") else np.asarray(o["polygon"], float), o["bbox"], w, h)
                for o in self.real_objects]
        return np.stack(out) if out else np.zeros((0, h, w), bool)
