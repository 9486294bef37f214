"""Output kind ``meta`` (always written, last): ``meta/NNNNNN.json``, everything known about
a frame -- seeds, every sampled parameter, the camera, lights, objects (boxes, occlusion,
truncation, pose), the frame's COCO records and the files written. Its presence marks the
frame complete when every file it lists exists (:func:`frame_status`; ``--resume`` renders
the others again)."""
from __future__ import annotations

import glob
import json
import os
from typing import Any, Dict, List, Tuple

from .._core import SynthgenError
from .coco import frame_record
from .files import write_json
from .registry import Frame, OutputKind, register

__all__ = ["write_meta", "read_meta", "frame_status", "completed_frames"]


def write_meta(path: str, frame: Frame) -> str:
    meta = dict(frame.meta)
    meta["coco"] = frame_record(frame)
    meta["files"] = dict(frame.files)
    return write_json(path, meta)


def read_meta(path: str) -> Dict[str, Any]:
    """A frame's metadata; SynthgenError naming the file when it is unreadable or not a
    frame's metadata."""
    try:
        with open(path, encoding="utf-8") as f:
            meta = json.load(f)
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise SynthgenError(f"{path}: unreadable frame metadata ({type(e).__name__}: {e})") from None
    if not isinstance(meta, dict) or not isinstance(meta.get("files"), dict) or "frame" not in meta:
        raise SynthgenError(f"{path}: not a synthgen frame's metadata (no 'frame' or 'files')")
    return meta


def frame_status(out_dir: str) -> Tuple[List[int], Dict[int, str]]:
    """(complete frames, {incomplete frame: reason}). A frame is complete when its metadata
    (written last) parses and every file it lists exists."""
    done: List[int] = []
    broken: Dict[int, str] = {}
    for p in glob.glob(os.path.join(out_dir, "meta", "[0-9]" * 6 + ".json")):
        k = int(os.path.basename(p)[:6])
        try:
            meta = read_meta(p)
        except SynthgenError as e:
            broken[k] = str(e)
            continue
        missing = [f for f in meta["files"].values() if not os.path.isfile(os.path.join(out_dir, f))]
        if missing:
            broken[k] = f"{p}: lists missing file(s) {', '.join(missing)}"
        else:
            done.append(k)
    return sorted(done), dict(sorted(broken.items()))


def completed_frames(out_dir: str) -> List[int]:
    """Complete frames (see :func:`frame_status`)."""
    return frame_status(out_dir)[0]


register(OutputKind("meta", "frame metadata (always written, last: marks the frame complete)", order=1000,
                    directory="meta", extension=".json", write=write_meta, always=True, module=__name__))
