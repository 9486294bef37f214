"""Output kind ``meta`` (always written, last): ``meta/NNNNNN.json``, everything known about
a frame -- seeds, every sampled parameter, the camera, lights, objects (boxes, occlusion,
truncation, pose), the frame's COCO records and the files written. Its presence marks the
frame complete (:func:`completed_frames`; ``--resume`` renders the frames without it)."""
from __future__ import annotations

import glob
import os
from typing import List

from .coco import frame_record
from .files import write_json
from .registry import Frame, OutputKind, register

__all__ = ["write_meta", "completed_frames"]


def write_meta(path: str, frame: Frame) -> str:
    meta = dict(frame.meta)
    meta["coco"] = frame_record(frame)
    meta["files"] = dict(frame.files)
    return write_json(path, meta)


def completed_frames(out_dir: str) -> List[int]:
    """Frames whose metadata exists (the last file written for a frame)."""
    out = []
    for p in glob.glob(os.path.join(out_dir, "meta", "[0-9]" * 6 + ".json")):
        out.append(int(os.path.basename(p)[:6]))
    return sorted(out)


register(OutputKind("meta", "frame metadata (always written, last: marks the frame complete)", order=1000,
                    directory="meta", extension=".json", write=write_meta, always=True, module=__name__))
