"""Labels of the real objects a photo already shows, read from the formats users have: labelme
JSON, COCO JSON, YOLO txt and KITTI label txt, plus boxes and polygons written in a calibration.

A real object is a box (pixels of the photo, x0 y0 x1 y1, continuous coordinates), maybe a
polygon, a class name (after the calibration's ``classes`` mapping) and ``ignore``: a region the
detector must not be trained on either way (COCO ``iscrowd``, KITTI ``DontCare``, ``ignore:``
regions). Real labels are written to every output with ``source: real``."""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, Optional, Sequence

import numpy as np

from .._core import SynthgenError
from .formats import MAX_CALIB_BYTES

__all__ = ["RealObject", "read_labels", "LABEL_FORMATS", "polygon_mask", "box_mask", "object_mask", "box_of",
           "points_in_polygons", "PolygonSet"]

LABEL_FORMATS = ("labelme", "coco", "yolo", "kitti")
_MAX_LABEL_BYTES = 64 * MAX_CALIB_BYTES


@dataclass
class RealObject:
    cls: str                              #: class name (mapped to the scenario's)
    box: Sequence[float]                  #: x0, y0, x1, y1 in photo pixels
    polygon: Optional[np.ndarray] = None  #: N x 2 photo pixels, or None (the box)
    ignore: bool = False                  #: an ignore region (crowd, DontCare)
    source: str = ""                      #: file (and line / index) it came from

    def meta(self) -> Dict[str, Any]:
        d = {"class": self.cls, "box": [float(v) for v in self.box], "ignore": self.ignore, "source": self.source}
        if self.polygon is not None:
            d["polygon"] = np.asarray(self.polygon, float).round(2).tolist()
        return d


def box_of(points: np.ndarray) -> List[float]:
    p = np.asarray(points, np.float64)
    return [float(p[:, 0].min()), float(p[:, 1].min()), float(p[:, 0].max()), float(p[:, 1].max())]


def _read(path: str, what: str) -> str:
    if not os.path.isfile(path):
        raise SynthgenError(f"{path}: {what} not found")
    if os.path.getsize(path) > _MAX_LABEL_BYTES:
        raise SynthgenError(f"{path}: a {what} larger than {_MAX_LABEL_BYTES} bytes")
    try:
        with open(path, "r", encoding="utf-8") as f:
            return f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise SynthgenError(f"{path}: cannot read the {what} ({e})") from None


def _json(path: str, what: str) -> Any:
    try:
        return json.loads(_read(path, what))
    except json.JSONDecodeError as e:
        raise SynthgenError(f"{path}:{e.lineno}: not JSON ({e.msg})") from None


def _finite_points(pts: Any, where: str) -> np.ndarray:
    try:
        p = np.asarray(pts, np.float64)
    except (TypeError, ValueError):
        raise SynthgenError(f"{where}: points must be [[x, y], ...] numbers") from None
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 1 or not np.all(np.isfinite(p)):
        raise SynthgenError(f"{where}: points must be [[x, y], ...] finite numbers")
    return p


def _labelme(path: str, photo: str, size) -> List[RealObject]:
    d = _json(path, "labelme file")
    if not isinstance(d, dict) or not isinstance(d.get("shapes"), list):
        raise SynthgenError(f"{path}: not a labelme file (no 'shapes' list)")
    _check_size(path, d.get("imageWidth"), d.get("imageHeight"), size)
    out = []
    for i, s in enumerate(d["shapes"]):
        where = f"{path}: shapes[{i}]"
        if not isinstance(s, dict) or not isinstance(s.get("label"), str):
            raise SynthgenError(f"{where}: a shape needs a 'label' and 'points'")
        p = _finite_points(s.get("points"), where)
        kind = s.get("shape_type") or "polygon"
        if kind == "rectangle" and len(p) == 2:
            box, poly = box_of(p), None
        elif kind == "circle" and len(p) == 2:
            r = float(np.hypot(*(p[1] - p[0])))
            box, poly = [p[0, 0] - r, p[0, 1] - r, p[0, 0] + r, p[0, 1] + r], None
        elif kind in ("polygon", "linestrip") and len(p) >= 3:
            box, poly = box_of(p), p
        else:
            continue  # points and lines mark no object
        out.append(RealObject(s["label"], box, poly, False, where))
    return out


def _coco(path: str, photo: str, size) -> List[RealObject]:
    d = _json(path, "COCO file")
    if not isinstance(d, dict) or not all(isinstance(d.get(k), list) for k in ("images", "annotations", "categories")):
        raise SynthgenError(f"{path}: not a COCO file (needs images, annotations and categories lists)")
    name = os.path.basename(photo)
    image = next((im for im in d["images"] if isinstance(im, dict)
                  and os.path.basename(str(im.get("file_name", ""))) == name), None)
    if image is None:
        raise SynthgenError(f"{path}: no image with file_name '{name}'")
    _check_size(path, image.get("width"), image.get("height"), size)
    cats = {c.get("id"): str(c.get("name")) for c in d["categories"] if isinstance(c, dict)}
    out = []
    for i, a in enumerate(d["annotations"]):
        if not isinstance(a, dict) or a.get("image_id") != image.get("id"):
            continue
        where = f"{path}: annotations[{i}]"
        bb = a.get("bbox")
        if (not isinstance(bb, list) or len(bb) != 4 or
                not all(isinstance(v, (int, float)) and math.isfinite(v) for v in bb)):
            raise SynthgenError(f"{where}: bbox must be [x, y, width, height]")
        if a.get("category_id") not in cats:
            raise SynthgenError(f"{where}: category_id {a.get('category_id')!r} is not in categories")
        poly = None
        seg = a.get("segmentation")
        if isinstance(seg, list) and seg and isinstance(seg[0], list) and len(seg[0]) >= 6:
            poly = _finite_points(np.asarray(seg[0], float).reshape(-1, 2), where)
        x, y, w, h = (float(v) for v in bb)
        out.append(RealObject(cats[a["category_id"]], [x, y, x + w, y + h], poly, bool(a.get("iscrowd", 0)), where))
    return out


def _yolo(path: str, photo: str, size, names: Optional[Sequence[str]]) -> List[RealObject]:
    if not names:
        raise SynthgenError(f"{path}: YOLO labels need the class names ('names' in the labels entry, in the "
                            "order of the class indices)")
    w, h = size
    out = []
    for n, line in enumerate(_read(path, "YOLO label file").splitlines(), 1):
        if not line.strip():
            continue
        parts = line.split()
        try:
            c = int(parts[0])
            v = [float(x) for x in parts[1:5]]
        except (ValueError, IndexError):
            raise SynthgenError(f"{path}:{n}: expected 'class cx cy w h', got '{line.strip()[:60]}'") from None
        if len(v) != 4 or not all(math.isfinite(x) for x in v) or not 0 <= c < len(names):
            raise SynthgenError(f"{path}:{n}: expected 'class cx cy w h' with class in 0..{len(names) - 1}")
        cx, cy, bw, bh = v
        out.append(RealObject(str(names[c]), [(cx - bw / 2) * w, (cy - bh / 2) * h, (cx + bw / 2) * w,
                                              (cy + bh / 2) * h], None, False, f"{path}:{n}"))
    return out


def _kitti(path: str, photo: str, size) -> List[RealObject]:
    out = []
    for n, line in enumerate(_read(path, "KITTI label file").splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        try:
            box = [float(x) for x in parts[4:8]]
        except ValueError:
            box = []
        if len(box) != 4 or not all(math.isfinite(x) for x in box):
            raise SynthgenError(f"{path}:{n}: expected a KITTI label line (type truncated occluded alpha "
                                f"x0 y0 x1 y1 ...), got '{line.strip()[:60]}'")
        out.append(RealObject(parts[0], box, None, parts[0] == "DontCare", f"{path}:{n}"))
    return out


def _check_size(path: str, w: Any, h: Any, size) -> None:
    if isinstance(w, int) and isinstance(h, int) and size is not None and (w, h) != tuple(size):
        raise SynthgenError(f"{path}: its labels are for a {w} x {h} image, the photo is {size[0]} x {size[1]}")


def read_labels(path: str, fmt: str, photo: str, size, classes: Optional[Mapping[str, Optional[str]]] = None,
                names: Optional[Sequence[str]] = None) -> List[RealObject]:
    """The real objects of ``photo`` (its ``size`` = (width, height)) in label file ``path`` of
    format ``fmt``. ``classes`` maps the file's class names to the scenario's (a name mapped
    to None, or a name absent when ``classes`` is given, is dropped; KITTI's DontCare stays as
    an ignore region)."""
    if fmt not in LABEL_FORMATS:
        raise SynthgenError(f"{path}: label format '{fmt}' is not one of {', '.join(LABEL_FORMATS)}")
    if fmt == "labelme":
        objs = _labelme(path, photo, size)
    elif fmt == "coco":
        objs = _coco(path, photo, size)
    elif fmt == "yolo":
        objs = _yolo(path, photo, size, names)
    else:
        objs = _kitti(path, photo, size)
    if classes is None:
        return objs
    out = []
    for o in objs:
        if o.ignore and o.cls not in classes:
            out.append(o)
            continue
        mapped = classes.get(o.cls)
        if mapped is not None:
            o.cls = str(mapped)
            out.append(o)
    return out


class PolygonSet:
    """Polygons prepared for many point-in-polygon queries (their edges extracted once)."""

    def __init__(self, polygons):
        self.edges = []  # per polygon: arrays ax, ay, bx, by of its non-horizontal edges
        for p in polygons:
            p = np.asarray(p, np.float64)
            q = np.roll(p, -1, axis=0)
            keep = p[:, 1] != q[:, 1]  # horizontal edges cross no horizontal ray
            self.edges.append((p[keep, 0], p[keep, 1], q[keep, 0], q[keep, 1]))
        self.edge_lists = [list(zip(*(a.tolist() for a in e))) for e in self.edges]

    def contains(self, pts) -> np.ndarray:
        """Whether each point (N x 2) lies inside one of the polygons (even-odd rule)."""
        pts = np.asarray(pts, np.float64).reshape(-1, 2)
        out = np.zeros(len(pts), bool)
        for (ax, ay, bx, by), edges in zip(self.edges, self.edge_lists):
            if not edges:
                continue
            # NOTE: the same IEEE double arithmetic per (point, edge) either way, so the same
            # answer: a few points against a few edges (placement tests a few points per
            # candidate spot, thousands of times a frame) in plain Python, whose floats beat
            # NumPy's per-call overhead there; else all edges at once (points x edges) with the
            # crossings' parity per point, the points in chunks of at most ~2^20 (point, edge) pairs.
            if len(pts) * len(edges) <= 256:
                for i, (x, y) in enumerate(pts.tolist()):
                    odd = False
                    for eax, eay, ebx, eby in edges:
                        if (eay > y) != (eby > y) and x < eax + (y - eay) * (ebx - eax) / (eby - eay):
                            odd = not odd
                    out[i] |= odd
                continue
            step = max(1, (1 << 20) // len(edges))
            for i in range(0, len(pts), step):
                x, y = pts[i:i + step, 0:1], pts[i:i + step, 1:2]
                cross = ((ay > y) != (by > y)) & (x < ax + (y - ay) * (bx - ax) / (by - ay))
                out[i:i + step] |= (np.count_nonzero(cross, axis=1) & 1).astype(bool)
        return out


def points_in_polygons(polygons, pts: np.ndarray) -> np.ndarray:
    """Whether each point (N x 2) lies inside one of the polygons (even-odd rule)."""
    return PolygonSet(polygons).contains(pts)


def polygon_mask(polygon: np.ndarray, width: int, height: int) -> np.ndarray:
    """H x W bool: pixel centres inside the polygon (even-odd rule)."""
    p = np.asarray(polygon, np.float64)
    x0, y0 = max(int(math.floor(p[:, 0].min())), 0), max(int(math.floor(p[:, 1].min())), 0)
    x1, y1 = min(int(math.ceil(p[:, 0].max())) + 1, width), min(int(math.ceil(p[:, 1].max())) + 1, height)
    mask = np.zeros((height, width), bool)
    if x1 <= x0 or y1 <= y0:
        return mask
    ys, xs = np.mgrid[y0:y1, x0:x1]
    centres = np.stack([xs.ravel() + 0.5, ys.ravel() + 0.5], 1)
    mask[y0:y1, x0:x1] = points_in_polygons([p], centres).reshape(xs.shape)
    return mask


def box_mask(box, width: int, height: int) -> np.ndarray:
    """H x W bool: pixel centres inside the box [x0, y0, x1, y1]."""
    x0, y0, x1, y1 = (int(math.floor(float(v) + 0.5)) for v in box)
    mask = np.zeros((height, width), bool)
    mask[max(y0, 0):max(y1, 0), max(x0, 0):max(x1, 0)] = True
    return mask


def object_mask(polygon, box, width: int, height: int) -> np.ndarray:
    """A real object's pixels: its polygon's when it has one, else its box's."""
    return polygon_mask(polygon, width, height) if polygon is not None else box_mask(box, width, height)
