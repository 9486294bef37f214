"""The registry of dataset output kinds, and the writing of one frame.

An output kind is a name users list under a scenario's ``outputs:`` (``rgb``, ``depth``,
``coco``, ...), the per-frame file it writes (``DIR/<directory>/<frame><extension>``, or
none), a pure writer ``write(path, frame) -> path`` and an optional dataset-level
``finalize(out_dir, class_names, frames)`` run at the end of a run (``annotations/coco.json``,
``dataset.yaml``). Each format module of :mod:`synthgen.outputs` registers its kinds with
:func:`register`; :func:`write_frame` writes a frame's selected kinds in their ``order`` and
the metadata (kind ``meta``, always written) last, so a frame with metadata is complete.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence

import numpy as np

from .._core import SynthgenError

__all__ = ["Frame", "OutputKind", "register", "kinds", "kind", "kind_names", "default_outputs", "write_frame",
           "finalize_dataset", "frame_name", "frame_path"]


def frame_name(k: int) -> str:
    """File stem of frame ``k``: six digits."""
    return f"{int(k):06d}"


@dataclass(frozen=True)
class Frame:
    """What a writer sees of one frame: its index, the render's arrays (``rgb``, ``depth``,
    ``instance_id``, ``class_id``) and its metadata (image size, objects with boxes, ...)."""

    index: int
    arrays: Mapping[str, np.ndarray]
    meta: Mapping[str, Any]
    outputs: Sequence[str] = ()            #: the kinds selected for the frame
    files: Mapping[str, str] = field(default_factory=dict)  #: {kind: path relative to the dataset} so far

    @property
    def size(self) -> tuple:
        """(width, height) in pixels."""
        w, h = self.meta["image_size"]
        return int(w), int(h)

    def visible_objects(self) -> List[Mapping[str, Any]]:
        """Objects that were kept and have visible pixels, in frame order."""
        return [o for o in self.meta["objects"] if not o.get("dropped") and o.get("visible_pixels")]

    def parts(self) -> List[Mapping[str, Any]]:
        """Labelled parts of the frame's objects with visible pixels (plate-only boxes:
        ``plates: {class: ...}``), each with its own class, box, mask and 3D box."""
        return [p for p in self.meta.get("parts", []) if p.get("visible_pixels")]

    def real_objects(self) -> List[Mapping[str, Any]]:
        """Labelled real objects of a photo frame (``background``), in the photo's order."""
        return [o for o in self.meta.get("real_objects", []) if not o["ignore"]]

    def ignore_regions(self) -> List[Mapping[str, Any]]:
        """A photo frame's ignore regions: crowds, DontCare, real objects mostly hidden."""
        return [o for o in self.meta.get("real_objects", []) if o["ignore"]]


@dataclass(frozen=True)
class OutputKind:
    """One kind of output (see the module docstring)."""

    name: str
    doc: str
    order: int
    directory: Optional[str] = None
    extension: str = ""
    write: Optional[Callable[[str, Frame], str]] = None
    finalize: Optional[Callable[[str, Sequence[str], Sequence[int]], Optional[str]]] = None
    default: bool = True   #: in a scenario's default ``outputs``
    always: bool = False   #: written for every frame (not listed under ``outputs``)
    module: str = field(default="", compare=False)


_KINDS: Dict[str, OutputKind] = {}


def register(kind: OutputKind) -> OutputKind:
    """Adds an output kind (called by the format modules at import)."""
    if kind.name in _KINDS:
        raise SynthgenError(f"output kind '{kind.name}' is registered twice")
    if (kind.write is None) != (kind.directory is None):
        raise SynthgenError(f"output kind '{kind.name}': a per-frame writer needs a directory and vice versa")
    _KINDS[kind.name] = kind
    return kind


def kinds(include_always: bool = False) -> List[OutputKind]:
    """The registered kinds in writing order (without ``meta`` unless asked)."""
    return sorted((k for k in _KINDS.values() if include_always or not k.always), key=lambda k: k.order)


def kind(name: str) -> OutputKind:
    return _KINDS[name]


def kind_names() -> List[str]:
    """Names users may list under ``outputs:``, in writing order."""
    return [k.name for k in kinds()]


def default_outputs() -> List[str]:
    return [k.name for k in kinds() if k.default]


def frame_path(out_dir: str, k: OutputKind, frame: int) -> str:
    return os.path.join(out_dir, k.directory, frame_name(frame) + k.extension)


def write_frame(out_dir: str, frame: int, arrays: Mapping[str, np.ndarray], meta: Mapping[str, Any],
                outputs: Sequence[str]) -> Dict[str, str]:
    """Writes one frame's files: the ``outputs`` kinds in order, then the metadata (always,
    last; it records the other files). Returns {kind: path}."""
    selected = [k for k in kinds() if k.name in outputs]
    final = kinds(include_always=True)
    last = [k for k in final if k.always]
    for k in selected + last:
        if k.directory:
            os.makedirs(os.path.join(out_dir, k.directory), exist_ok=True)
    files: Dict[str, str] = {}
    for k in selected + last:
        if k.write is not None:
            rel = {n: os.path.relpath(p, out_dir) for n, p in files.items()}
            files[k.name] = k.write(frame_path(out_dir, k, frame), Frame(int(frame), arrays, meta, tuple(outputs), rel))
    return files


def finalize_dataset(out_dir: str, outputs: Sequence[str], class_names: Sequence[str],
                     frames: Sequence[int]) -> List[str]:
    """Runs the dataset-level step of every selected kind; returns the files written."""
    out = []
    for k in kinds():
        if k.name in outputs and k.finalize is not None:
            p = k.finalize(out_dir, class_names, frames)
            if p:
                out.append(p)
    return out
