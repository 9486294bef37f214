"""Train / val / test split of a dataset, by groups of frames that must stay together.

A frame's metadata lists its ``split_keys``: what it shares with other frames -- its scene
layout (``layout:...``) and, for frames composited over photos, the source photo
(``photo:SHA256``). Frames that share any key form one group (union-find over the keys), and
a whole group goes to one split: no photo and no layout is ever in both train and val, so
validation measures generalization, not memory. A group's split is a pure function of the
scenario seed and one of its keys (its photo's, when it has one; a hash compared with the
fractions), so it does not depend on worker count or resume, nor, for a photo's frames, on
which of them exist.

Written at the end of a run: ``splits/train.txt``, ``splits/val.txt``, ``splits/test.txt``
(image paths relative to the dataset, one per line; the lists YOLO's ``dataset.yaml`` and
:func:`synthgen.read_dataset` use) and ``splits/splits.json`` (frame -> split, the groups).
"""
from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Dict, List

from ..schema.fields import Number, Record
from .files import write_json, write_text
from .registry import frame_name

__all__ = ["SCHEMA", "SPLITS", "frame_keys", "groups", "assign", "write_splits", "read_splits"]

#: The splits, in order.
SPLITS = ("train", "val", "test")

SCHEMA = Record({
    "val": Number(0.1, min=0.0, max=1.0, doc="fraction of the groups of frames that go to val"),
    "test": Number(0.0, min=0.0, max=1.0, doc="fraction of the groups of frames that go to test"),
}, default={"val": 0.1, "test": 0.0},
    doc="train / val / test split: frames that share a source photo or a scene layout stay in one split")


def frame_keys(meta: Mapping[str, Any]) -> List[str]:
    """What a frame shares with others (its ``split_keys``; a frame without any is its own
    group)."""
    keys = [str(k) for k in meta.get("split_keys", [])]
    return keys or [f"frame:{int(meta['frame'])}"]


def groups(metas: Iterable[Mapping[str, Any]]) -> List[List[int]]:
    """Frames grouped so that frames sharing a key are in the same group (sorted lists,
    sorted by their first frame)."""
    parent: Dict[str, str] = {}

    def find(x: str) -> str:
        while parent.setdefault(x, x) != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    frames: Dict[int, str] = {}
    for m in metas:
        keys = frame_keys(m)
        frame = int(m["frame"])
        for k in keys[1:]:
            a, b = find(keys[0]), find(k)
            if a != b:
                parent[max(a, b)] = min(a, b)  # the smallest key is the root
        frames[frame] = keys[0]
    by_root: Dict[str, List[int]] = {}
    for frame, key in frames.items():
        by_root.setdefault(find(key), []).append(frame)
    return sorted((sorted(v) for v in by_root.values()), key=lambda g: g[0])


def _representative(keys: Iterable[str]) -> str:
    """The key a group's split is drawn from: its smallest photo key if it has one (the same
    whichever of the photo's frames exist), else its smallest key."""
    return min(keys, key=lambda k: (not k.startswith("photo:"), k))


def _unit(seed: int, key: str) -> float:
    """A uniform number in [0, 1) from the seed and a group's key (SHA-256)."""
    h = hashlib.sha256(f"{int(seed)}\0{key}".encode()).digest()
    return int.from_bytes(h[:8], "big") / 2.0 ** 64


def assign(metas: Sequence[Mapping[str, Any]], seed: int, val: float, test: float) -> Dict[int, str]:
    """frame -> "train" | "val" | "test"; whole groups go to one split."""
    by_frame = {int(m["frame"]): m for m in metas}
    out: Dict[int, str] = {}
    for g in groups(metas):
        key = _representative(k for f in g for k in frame_keys(by_frame[f]))
        u = _unit(seed, key)
        split = "val" if u < val else "test" if u < val + test else "train"
        for f in g:
            out[f] = split
    return out


def write_splits(out_dir: str, metas: Sequence[Mapping[str, Any]], seed: int, val: float, test: float) -> str:
    """splits/{train,val,test}.txt and splits/splits.json of the frames whose metadata is
    given; returns the path of splits.json."""
    assignment = assign(metas, seed, val, test)
    d = os.path.join(out_dir, "splits")
    os.makedirs(d, exist_ok=True)
    for s in SPLITS:
        frames = sorted(f for f, v in assignment.items() if v == s)
        write_text(os.path.join(d, f"{s}.txt"), "".join(f"images/{frame_name(f)}.png\n" for f in frames))
    info = {"seed": int(seed), "fractions": {"val": float(val), "test": float(test)},
            "frames": {str(f): assignment[f] for f in sorted(assignment)},
            "groups": [g for g in groups(metas) if len(g) > 1],
            "counts": {s: sum(1 for v in assignment.values() if v == s) for s in SPLITS}}
    return write_json(os.path.join(d, "splits.json"), info)


def read_splits(out_dir: str) -> Dict[int, str]:
    """frame -> split of a dataset (empty when it has no splits/splits.json)."""
    path = os.path.join(out_dir, "splits", "splits.json")
    if not os.path.exists(path):
        return {}
    with open(path, encoding="utf-8") as f:
        return {int(k): v for k, v in json.load(f)["frames"].items()}
