"""Dataset annotations from exact label images: COCO (RLE masks), YOLO and KITTI.

Pure functions: masks and per-object records in, JSON-ready dicts or text lines out; the
parsers read the files back (for tests and for users checking a dataset).

Conventions
-----------
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
* YOLO: ``class cx cy w h`` with the box centre and size divided by the image width/height.
* KITTI 2D object labels: ``type truncated occluded alpha left top right bottom h w l x y z
  rotation_y``; the box is in pixel-edge coordinates (right = x + w); 3D fields in the camera
  frame (x right, y down, z forward, metres) when known, else KITTI's "unknown" values
  (-1 for dimensions, -1000 for the location, -10 for the angles).
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

__all__ = [
    "rle_encode",
    "rle_decode",
    "rle_to_string",
    "rle_from_string",
    "rle_area",
    "mask_bbox",
    "coco_annotation",
    "coco_dataset",
    "yolo_line",
    "yolo_lines",
    "parse_yolo",
    "kitti_line",
    "parse_kitti",
    "kitti_occlusion_level",
]


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
# YOLO


def yolo_line(class_index: int, bbox: Sequence[float], width: int, height: int) -> str:
    """``class cx cy w h`` (normalized) of a COCO-style ``[x, y, w, h]`` pixel box."""
    x, y, w, h = (float(v) for v in bbox)
    return (f"{int(class_index)} {(x + w / 2) / width:.6f} {(y + h / 2) / height:.6f} "
            f"{w / width:.6f} {h / height:.6f}")


def yolo_lines(objects: Sequence[Mapping[str, Any]], width: int, height: int) -> List[str]:
    """YOLO lines of records with ``class_index`` (0-based) and ``bbox``."""
    return [yolo_line(o["class_index"], o["bbox"], width, height) for o in objects]


def parse_yolo(text: str, width: int, height: int) -> List[Tuple[int, List[float]]]:
    """(class index, [x, y, w, h] in pixels) per line of a YOLO label file."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        f = line.split()
        if len(f) != 5:
            raise ValueError(f"YOLO line {n}: expected 5 fields, got {len(f)}")
        c, cx, cy, w, h = int(f[0]), *(float(v) for v in f[1:])
        out.append((c, [(cx - w / 2) * width, (cy - h / 2) * height, w * width, h * height]))
    return out


# ---------------------------------------------------------------------------------------
# KITTI


def kitti_occlusion_level(visible_fraction: float) -> int:
    """KITTI's occlusion state from the visible fraction of the object's (in-image) area:
    0 fully visible (>= 0.95), 1 partly occluded (>= 0.5), 2 largely occluded."""
    if visible_fraction >= 0.95:
        return 0
    if visible_fraction >= 0.5:
        return 1
    return 2


def kitti_line(type_name: str, bbox: Sequence[float], truncated: float = 0.0, occluded: int = 3,
               alpha: float = -10.0, dimensions: Optional[Sequence[float]] = None,
               location: Optional[Sequence[float]] = None, rotation_y: float = -10.0) -> str:
    """One KITTI object line. ``bbox`` is COCO-style ``[x, y, w, h]``; ``dimensions`` (h, w, l)
    and ``location`` (x, y, z of the bottom centre, camera frame) default to unknown."""
    x, y, w, h = (float(v) for v in bbox)
    name = str(type_name).replace(" ", "_")
    dims = dimensions if dimensions is not None else (-1.0, -1.0, -1.0)
    loc = location if location is not None else (-1000.0, -1000.0, -1000.0)
    return (f"{name} {float(truncated):.2f} {int(occluded)} {float(alpha):.2f} "
            f"{x:.2f} {y:.2f} {x + w:.2f} {y + h:.2f} "
            f"{dims[0]:.2f} {dims[1]:.2f} {dims[2]:.2f} {loc[0]:.2f} {loc[1]:.2f} {loc[2]:.2f} {float(rotation_y):.2f}")


def parse_kitti(text: str) -> List[Dict[str, Any]]:
    """Records (type, truncated, occluded, alpha, bbox as [x, y, w, h], dimensions, location,
    rotation_y) per line of a KITTI label file."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        f = line.split()
        if len(f) not in (15, 16):
            raise ValueError(f"KITTI line {n}: expected 15 or 16 fields, got {len(f)}")
        v = [float(a) for a in f[1:15]]
        out.append({"type": f[0], "truncated": v[0], "occluded": int(v[1]), "alpha": v[2],
                    "bbox": [v[3], v[4], v[5] - v[3], v[6] - v[4]], "dimensions": v[7:10], "location": v[10:13],
                    "rotation_y": v[13]})
    return out


def wrap_angle(a: float) -> float:
    """An angle in radians wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi
