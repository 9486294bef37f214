"""Output kind ``coco``: COCO instance annotations with exact RLE masks.

Per frame, the metadata holds the frame's COCO image record and annotations (written with
it, so a resumed run never mixes frames); at the end of a run they are assembled into
``annotations/coco.json`` (:func:`assemble_coco`). Pure functions: masks in, JSON-ready
dicts out.

* Masks are boolean H x W arrays taken from synthgen's instance label (the first camera-ray
  hit of each pixel centre), never filtered.
* COCO run-length encoding is column-major (Fortran order), starts with the number of 0s
  (possibly 0) and alternates: ``[[0, 1], [1, 1], [0, 0]]`` -> ``counts`` ``[1, 1, 1, 2, 1]``.
  :func:`rle_encode` gives the counts as a list ("uncompressed RLE");
  :func:`rle_to_string` / :func:`rle_from_string` convert to and from the compact string form
  that pycocotools writes (its ``rleToString``: first differences of the counts from the third
  on, 5-bit groups with a continuation bit, offset by 48). Both forms are valid COCO.
* ``bbox`` = ``[x, y, w, h]`` of the tight box around the mask's pixels, pixel-edge
  coordinates (a single pixel at column 3, row 5 is ``[3, 5, 1, 1]``), as pycocotools' toBbox.
"""
from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from typing import Any, Dict, Iterable, List, Optional

import numpy as np

from .files import write_json
from .registry import Frame, OutputKind, frame_name, register

__all__ = ["rle_encode", "rle_decode", "rle_to_string", "rle_from_string", "rle_area", "mask_bbox",
           "coco_annotation", "coco_dataset", "frame_annotations", "frame_record", "assemble_coco"]


# ---------------------------------------------------------------------------------------
# COCO run-length encoding


def rle_encode(mask: np.ndarray) -> Dict[str, Any]:
    """COCO RLE of a boolean H x W mask: ``{"size": [H, W], "counts": [...]}`` (column-major
    runs, the first one counting 0s)."""
    m = np.asarray(mask)
    if m.ndim != 2:
        raise ValueError(f"rle_encode: mask must be 2-D, got shape {m.shape}")
    h, w = m.shape
    flat = m.astype(bool).ravel(order="F")
    if flat.size == 0:
        return {"size": [int(h), int(w)], "counts": []}
    # Positions where the value changes, plus both ends.
    change = np.flatnonzero(flat[1:] != flat[:-1]) + 1
    edges = np.concatenate(([0], change, [flat.size]))
    runs = np.diff(edges).tolist()
    if flat[0]:
        runs = [0] + runs
    return {"size": [int(h), int(w)], "counts": [int(r) for r in runs]}


def _counts(rle: Mapping[str, Any]) -> List[int]:
    c = rle["counts"]
    return rle_from_string(c) if isinstance(c, (str, bytes)) else [int(x) for x in c]


def rle_decode(rle: Mapping[str, Any]) -> np.ndarray:
    """The boolean H x W mask of a COCO RLE (counts as a list or a compact string)."""
    h, w = (int(x) for x in rle["size"])
    counts = _counts(rle)
    if sum(counts) != h * w:
        raise ValueError(f"rle_decode: counts sum to {sum(counts)}, expected {h} x {w} = {h * w}")
    values = np.zeros(len(counts), dtype=bool)
    values[1::2] = True
    flat = np.repeat(values, counts)
    return flat.reshape((w, h)).T.copy() if h * w else np.zeros((h, w), dtype=bool)


def rle_area(rle: Mapping[str, Any]) -> int:
    """Number of mask pixels of an RLE (the sum of its odd runs)."""
    return int(sum(_counts(rle)[1::2]))


def rle_to_string(counts: Sequence[int]) -> str:
    """The compact COCO string of RLE counts (pycocotools ``rleToString``)."""
    out = []
    for i, c in enumerate(counts):
        x = int(c)
        if i > 2:
            x -= int(counts[i - 2])
        more = True
        while more:
            ch = x & 0x1F
            x >>= 5  # arithmetic shift: Python ints keep the sign
            more = (x != -1) if (ch & 0x10) else (x != 0)
            if more:
                ch |= 0x20
            out.append(chr(ch + 48))
    return "".join(out)


def rle_from_string(s: str | bytes) -> List[int]:
    """RLE counts from the compact COCO string (pycocotools ``rleFrString``)."""
    if isinstance(s, bytes):
        s = s.decode("ascii")
    counts: List[int] = []
    p = 0
    while p < len(s):
        x, k, more = 0, 0, True
        while more:
            if p >= len(s):
                raise ValueError("rle_from_string: truncated RLE string")
            c = ord(s[p]) - 48
            if not 0 <= c < 64:
                raise ValueError(f"rle_from_string: invalid character {s[p]!r} at {p}")
            x |= (c & 0x1F) << (5 * k)
            more = bool(c & 0x20)
            p += 1
            k += 1
            if not more and (c & 0x10):
                x |= -1 << (5 * k)
        if len(counts) > 2:
            x += counts[-2]
        counts.append(x)
    return counts


def mask_bbox(mask: np.ndarray) -> Optional[List[int]]:
    """``[x, y, w, h]`` of the tight pixel box around a boolean mask; None when empty."""
    m = np.asarray(mask, dtype=bool)
    rows = np.flatnonzero(m.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(m.any(axis=0))
    x0, x1, y0, y1 = int(cols[0]), int(cols[-1]), int(rows[0]), int(rows[-1])
    return [x0, y0, x1 - x0 + 1, y1 - y0 + 1]


# ---------------------------------------------------------------------------------------
# COCO


def coco_annotation(ann_id: int, image_id: int, category_id: int, mask: np.ndarray,
                    extra: Optional[Mapping[str, Any]] = None, compact: bool = True) -> Optional[Dict[str, Any]]:
    """One COCO annotation of a visible mask (None when the mask is empty: nothing is labelled
    that is not visible). ``segmentation`` is RLE (compact string when ``compact``), ``bbox``
    the tight mask box, ``area`` the mask's pixel count, ``iscrowd`` 0; ``extra`` keys (e.g.
    ``occlusion``, ``truncation``, ``instance_id``) are added."""
    if ann_id < 1 or image_id < 0 or category_id < 1:
        raise ValueError(f"coco_annotation: ids must be >= 1 (got ann {ann_id}, category {category_id})")
    box = mask_bbox(mask)
    if box is None:
        return None
    rle = rle_encode(mask)
    if compact:
        rle = {"size": rle["size"], "counts": rle_to_string(rle["counts"])}
    ann = {"id": int(ann_id), "image_id": int(image_id), "category_id": int(category_id),
           "segmentation": rle, "area": int(np.count_nonzero(mask)), "bbox": [float(v) for v in box],
           "iscrowd": 0}
    if extra:
        ann.update(extra)
    return ann


def coco_dataset(images: Sequence[Mapping[str, Any]], annotations: Sequence[Mapping[str, Any]],
                 class_names: Sequence[str], info: Optional[Mapping[str, Any]] = None) -> Dict[str, Any]:
    """A COCO detection/segmentation dataset dict. Category ids are 1 + the index in
    ``class_names``; annotation ids are renumbered 1..N in the given order."""
    anns = []
    for i, a in enumerate(annotations):
        b = dict(a)
        b["id"] = i + 1
        anns.append(b)
    return {
        "info": dict(info or {}),
        "licenses": [],
        "images": [dict(im) for im in images],
        "annotations": anns,
        "categories": [{"id": i + 1, "name": str(n), "supercategory": "object"} for i, n in enumerate(class_names)],
    }


# ---------------------------------------------------------------------------------------
# Datasets


def xyxy_to_xywh(box: Sequence[float]) -> List[float]:
    x0, y0, x1, y1 = (float(v) for v in box)
    return [x0, y0, x1 - x0, y1 - y0]


def real_annotations(meta: Mapping[str, Any], n_classes: int) -> List[Dict[str, Any]]:
    """COCO annotations of a photo frame's real objects (``source: real``): its labelled
    objects, and its ignore regions as ``iscrowd: 1`` (for every category when they have none:
    COCO's evaluation ignores a crowd region for its own category only)."""
    anns = []
    for o in meta.get("real_objects", []):
        bbox = xyxy_to_xywh(o["bbox"])
        if o.get("polygon"):
            seg = [[float(v) for p in o["polygon"] for v in p]]
            pts = np.asarray(o["polygon"], float)
            area = float(0.5 * abs(np.dot(pts[:, 0], np.roll(pts[:, 1], 1)) - np.dot(pts[:, 1], np.roll(pts[:, 0], 1))))
        else:
            x, y, w, h = bbox
            seg = [[x, y, x + w, y, x + w, y + h, x, y + h]]
            area = w * h
        cats = [int(o["class_id"])] if o["class_id"] else list(range(1, n_classes + 1))
        for c in cats:
            anns.append({"id": 1, "image_id": int(meta["frame"]), "category_id": c, "segmentation": seg,
                         "area": area, "bbox": bbox, "iscrowd": int(bool(o["ignore"])), "source": "real",
                         "visible_fraction": float(o["visible_fraction"]), "truncation": float(o["truncation"])})
    return anns


def frame_annotations(meta: Mapping[str, Any], instance_id: np.ndarray) -> List[Dict[str, Any]]:
    """COCO annotations (image_id = frame, ids assigned later) of a frame's visible objects
    (``source: synthetic``) and, in a photo frame, its real objects and ignore regions
    (:func:`real_annotations`)."""
    anns = []
    for o in meta["objects"]:
        if o.get("dropped") or not o.get("visible_pixels"):
            continue
        extra = {"instance_id": o["instance_id"], "occlusion": o["occlusion"], "truncation": o["truncation"],
                 "source": "synthetic"}
        if "weather" in o:  # fog or haze: how much of the object it lets through (docs/weather.md)
            extra.update({"transmittance": o["weather"]["transmittance"], "contrast": o["weather"]["contrast"]})
        a = coco_annotation(1, int(meta["frame"]), int(o["class_id"]), instance_id == o["instance_id"], extra=extra)
        if a is not None:
            anns.append(a)
    for p in meta.get("parts", []):  # plate-only labels: their exact visible masks
        m = rle_decode(p["mask"])
        a = coco_annotation(1, int(meta["frame"]), int(p["class_id"]), m,
                            extra={"parent_instance_id": p["parent_instance_id"], "occlusion": 1.0 - p["visible_fraction"],
                                   "truncation": p["truncation"], "source": "synthetic"})
        if a is not None:
            anns.append(a)
    return anns + real_annotations(meta, len(meta.get("class_names", [])))


def frame_record(frame: Frame) -> Dict[str, Any]:
    """The frame's COCO image record and (when ``coco`` is selected) its annotations, kept in
    the frame's metadata until :func:`assemble_coco`."""
    w, h = frame.size
    ids = np.asarray(frame.arrays["instance_id"])
    return {"image": {"id": frame.index, "file_name": f"images/{frame_name(frame.index)}.png", "width": w,
                      "height": h},
            "annotations": frame_annotations(frame.meta, ids) if "coco" in frame.outputs else []}


def assemble_coco(out_dir: str, class_names: Sequence[str], frames: Iterable[int]) -> str:
    """annotations/coco.json from the per-frame records in meta/*.json, and one file per
    split (coco_train.json, coco_val.json, coco_test.json when not empty; synthgen.outputs.split)."""
    from .split import SPLITS, read_splits

    records = {}
    for k in sorted(frames):
        with open(os.path.join(out_dir, "meta", frame_name(k) + ".json"), encoding="utf-8") as f:
            records[k] = json.load(f)["coco"]
    info = {"description": "synthgen dataset", "version": "1"}

    def write(name: str, keys: Sequence[int]) -> str:
        images = [records[k]["image"] for k in keys]
        anns = [a for k in keys for a in records[k]["annotations"]]
        path = os.path.join(out_dir, "annotations", name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        return write_json(path, coco_dataset(images, anns, class_names, info=info))

    splits = read_splits(out_dir)
    for s in SPLITS:
        keys = [k for k in records if splits.get(k) == s]
        if keys:
            write(f"coco_{s}.json", keys)
    return write("coco.json", list(records))


register(OutputKind("coco", "COCO instance annotations (RLE masks, occlusion, truncation): annotations/coco.json",
                    order=70, finalize=assemble_coco, module=__name__))
