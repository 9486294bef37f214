"""Outputs: what a frame becomes on disk (pure functions: arrays + metadata -> files).

A dataset directory (frame k is ``{k:06d}``)::

    images/000000.png        sRGB 8-bit (rgb)           images/000000.exr  linear float (rgb_exr)
    depth/000000.exr         camera z in metres, float32, +inf on background (depth)
    depth16/000000.png       uint16 millimetres, 0 = no surface or beyond 65.535 m (depth16)
    instance/000000.png      uint16 instance ids (1..N per frame, 0 = background/ground)
    semantic/000000.png      uint16 class ids (1 + index in the scenario's class list)
    normal/000000.exr        shading normals in the camera frame, float32 (normal)
    albedo/000000.exr        albedo of the first hit, linear float32 (albedo)
    labels/000000.txt        YOLO; dataset.yaml names the classes and the split's lists (yolo)
    kitti/000000.txt         KITTI 2D labels (+ 3D fields in the camera frame) (kitti)
    meta/000000.json         seed, every sampled parameter, objects (boxes, occlusion,
                             truncation, pose), the frame's COCO records; written last
    annotations/coco.json    assembled from meta/*.json at the end of a run (coco), and
                             coco_train.json, coco_val.json, coco_test.json: the split
    splits/train.txt, ...    the train / val / test split (:mod:`.split`): image lists and
                             splits.json; frames sharing a photo or a layout stay together

One module per format registers its output kinds (:mod:`.registry`): ``images`` (rgb,
rgb_exr), ``depth`` (depth, depth16), ``masks`` (instance, semantic), ``surface`` (normal,
albedo), ``coco``, ``yolo``, ``kitti``, ``meta``. Adding a format is one module here (found by :func:`discover`) plus its
test. Infrastructure: :mod:`.registry`, :mod:`.files` (atomic writers), :mod:`.render` (the
files of ``synthgen render``), :mod:`.verify` (``synthgen verify``), :mod:`.split` (the split),
:mod:`.read` (:func:`synthgen.read_dataset`: a dataset back as arrays and labels), :mod:`.data`
(:class:`synthgen.FrameData`: one frame as arrays and labels, read back or rendered in memory).
"""
from __future__ import annotations

import importlib
import pkgutil
from typing import List

from .registry import (Frame, OutputKind, default_outputs, finalize_dataset, frame_name, kind,  # noqa: F401
                       kind_names, kinds, register, write_frame)

#: Modules of this package that are not output formats.
INFRASTRUCTURE = ("registry", "files", "render", "verify", "split", "read", "data", "inspect")


def format_modules() -> List[str]:
    """Names of the format modules (every module of the package but the infrastructure)."""
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if m.name not in INFRASTRUCTURE)


def discover() -> None:
    """Imports every format module, which registers its kinds."""
    for name in format_modules():
        importlib.import_module(f"{__name__}.{name}")


discover()
