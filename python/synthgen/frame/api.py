"""Frames in memory: :class:`Scenario` renders a scenario's frames as arrays and labels,
without writing files -- for training loops that generate on the fly, notebooks and tests::

    import synthgen
    sc = synthgen.Scenario("scenarios/default.yaml", overrides=[("render.spp", 16)])
    for frame in sc.frames(0, 8):
        frame.rgb, frame.depth, frame.instance_id, frame.objects, frame.boxes_xyxy, frame.labels

Frame k is the same as frame k of ``synthgen run`` on the same scenario (same seeds, same
arrays; the files hold their 8-bit / 16-bit encodings).
"""
from __future__ import annotations

import os
from typing import Any, Iterator, List, Optional, Sequence, Tuple

import numpy as np

from ..outputs.data import FrameData

__all__ = ["Scenario"]


class Scenario:
    """A validated scenario file whose frames render in memory (one scene kept across
    frames, as a worker of ``synthgen run`` does). ``overrides``: (key path, value) pairs set
    before validation, as ``synthgen run --set``; ``threads``: render threads (0: all);
    ``allow_extensions``: consent to compile and run the scenario's C extensions (which it must
    allow itself too: docs/extensions.md)."""

    def __init__(self, path: str | os.PathLike, overrides: Sequence[Tuple[str, Any]] = (), threads: int = 0,
                 check_inputs: bool = True, allow_extensions: bool = False):
        from ..scenario import check_inputs as check, load_scenario

        self.spec = load_scenario(path, overrides, allow_extensions)
        if check_inputs:
            check(self.spec)
        self._threads = int(threads)
        self._renderer: Any = None

    @property
    def class_names(self) -> List[str]:
        """Class names in order: class id = index + 1."""
        return list(self.spec.class_names)

    @property
    def count(self) -> int:
        return self.spec.count

    @property
    def resolution(self) -> Tuple[int, int]:
        return self.spec.resolution

    def frame(self, k: int) -> FrameData:
        """Frame ``k``: its arrays (copies, yours to keep) and metadata."""
        from ..outputs.surface import camera_normals
        from .renderer import FrameRenderer

        if self._renderer is None:
            self._renderer = FrameRenderer(self.spec, self._threads)
        arrays, meta, _ = self._renderer.render(int(k))
        wfc = np.asarray(meta["camera"]["world_from_camera"])
        return FrameData(index=int(k), rgb=np.array(arrays["rgb"], np.float32),
                         depth=np.array(arrays["depth"], np.float32),
                         instance_id=np.array(arrays["instance_id"], np.uint32),
                         class_id=np.array(arrays["class_id"], np.uint32),
                         normal=camera_normals(arrays["normal"], wfc),
                         albedo=np.array(arrays["albedo"], np.float32), meta=meta)

    def frames(self, start: int = 0, stop: Optional[int] = None) -> Iterator[FrameData]:
        """Frames ``start`` .. ``stop - 1`` (default: to the scenario's count), in order."""
        for k in range(int(start), int(self.count if stop is None else stop)):
            yield self.frame(k)

    def __repr__(self) -> str:
        w, h = self.resolution
        return f"synthgen.Scenario({self.spec.source!r}: {self.count} frames, {w}x{h}, classes {self.class_names})"
