"""Labels of the real objects a photo already shows: the objects of its label files
(:mod:`.label_files`: labelme, COCO, YOLO, KITTI, CSV, Pascal VOC) under its calibration's
``classes`` mapping, plus boxes and polygons written in a calibration; and the masks of real
objects.

A real object is a box (pixels of the photo, x0 y0 x1 y1, continuous coordinates), maybe a
polygon, a class name (after the calibration's ``classes`` mapping) and ``ignore``: a region the
detector must not be trained on either way (COCO ``iscrowd``, KITTI ``DontCare``, VOC
``difficult``, ``ignore:`` regions). Real labels are written to every output with ``source: real``.

Real labels must not vanish on the way: :func:`load_labels` refuses a mapping that does not list
every class of the file's objects, and :func:`check_classes` classes the scenario does not have;
each error names the labels file, the classes found in it and the mapping."""
from __future__ import annotations

import math
import os
from collections import Counter, OrderedDict
from dataclasses import dataclass, field
from typing import Dict, List, Mapping, Optional, Sequence

import numpy as np

from .._core import SynthgenError
from .label_files import LABEL_FORMATS, RealObject, box_of, read_label_file

__all__ = ["RealObject", "LabelFile", "load_labels", "read_labels", "check_classes", "LABEL_FORMATS",
           "polygon_mask", "box_mask", "object_mask", "box_of", "points_in_polygons", "PolygonSet"]


def _show_mapping(classes: Optional[Mapping[str, Optional[str]]]) -> str:
    if classes is None:
        return "no classes mapping: the file's names are taken as the scenario's"
    return "classes: {" + ", ".join(f"{k}: {'null' if v is None else v}" for k, v in classes.items()) + "}"


def _case_hints(names: Sequence[str], known: Sequence[str]) -> str:
    """'; 'Car' is not 'car': class names are case-sensitive' for each name known in another case."""
    hints = [f"'{c}' is not '{k}'" for c in names for k in known if k != c and k.lower() == c.lower()][:3]
    return f"; {', '.join(hints)}: class names are case-sensitive" if hints else ""


@dataclass
class LabelFile:
    """One label file read for one photo: its classes and the objects they map to."""

    path: str
    format: str
    classes: Optional[Mapping[str, Optional[str]]]   #: the calibration's mapping (None: the file's names)
    found: Dict[str, int] = field(default_factory=dict)   #: the file's classes for the photo -> objects
    objects: List[RealObject] = field(default_factory=list)   #: after the mapping

    def describe(self) -> str:
        found = ", ".join(f"{c} ({n})" for c, n in self.found.items()) or "none"
        return f"classes found in it: {found}; {_show_mapping(self.classes)}"


def load_labels(path: str, fmt: str, photo: str, size, classes: Optional[Mapping[str, Optional[str]]] = None,
                names: Optional[Sequence[str]] = None, default_class: Optional[str] = None) -> LabelFile:
    """The real objects of ``photo`` in a calibration's labels entry: :func:`read_label_file`,
    then ``classes`` (the file's class names -> the scenario's; a name mapped to None is dropped
    deliberately). Every class of the file's objects must be a key of ``classes`` when one is
    given, or the file is refused (a name not listed, ``car`` for KITTI's ``Car``, would drop
    real objects silently); ignore regions (DontCare, crowd, difficult) not listed stay ignore
    regions."""
    if fmt == "yolo" and not names:
        raise SynthgenError(f"{path}: YOLO labels need the class names ('names' in the labels entry, in the "
                            "order of the class indices)")
    objs = read_label_file(path, fmt, photo, size, names, default_class)
    lf = LabelFile(path, fmt, None if classes is None else dict(classes), dict(Counter(o.cls for o in objs)))
    if classes is None:
        lf.objects = objs
        return lf
    unlisted = list(OrderedDict.fromkeys(o.cls for o in objs if not o.ignore and o.cls not in classes))
    if unlisted:
        raise SynthgenError(
            f"{path}: {os.path.basename(photo)}: the class{'es' if len(unlisted) > 1 else ''} "
            f"{', '.join(repr(c) for c in unlisted)} of its objects {'are' if len(unlisted) > 1 else 'is'} not in the "
            f"labels' classes mapping ({lf.describe()}){_case_hints(unlisted, list(classes))}. Map every class "
            "the file has to a scenario class, or to null to drop its objects deliberately")
    for o in objs:
        if o.cls not in classes:  # an ignore region the mapping does not name
            lf.objects.append(o)
        elif classes[o.cls] is not None:
            lf.objects.append(RealObject(str(classes[o.cls]), o.box, o.polygon, o.ignore, o.source))
    return lf


def read_labels(path: str, fmt: str, photo: str, size, classes: Optional[Mapping[str, Optional[str]]] = None,
                names: Optional[Sequence[str]] = None, default_class: Optional[str] = None) -> List[RealObject]:
    """The objects of :func:`load_labels`."""
    return load_labels(path, fmt, photo, size, classes, names, default_class).objects


def check_classes(files: Sequence[LabelFile], objects: Sequence[RealObject], class_names: Sequence[str],
                  photo: str) -> None:
    """Refuses real objects of a class the scenario does not have (they would be left out of
    every output): a label file's mapping to such a class, or its objects' classes with no
    mapping, and the calibration's own ``objects``. Ignore regions are free text."""
    names = list(class_names)
    for lf in files:
        bad = list(OrderedDict.fromkeys([v for v in (lf.classes or {}).values() if v is not None and v not in names]
                                        + [o.cls for o in lf.objects if not o.ignore and o.cls not in names]))
        if bad:
            raise SynthgenError(
                f"{lf.path}: {os.path.basename(photo)}: {', '.join(repr(c) for c in bad)} "
                f"{'are' if len(bad) > 1 else 'is'} not a class of the scenario ({', '.join(names)}): its real objects "
                f"would be left out of the labels ({lf.describe()}){_case_hints(bad, names)}. Map the file's classes "
                "to the scenario's, or to null to drop their objects deliberately")
    from_files = {id(o) for lf in files for o in lf.objects}
    for o in objects:
        if not o.ignore and o.cls not in names and id(o) not in from_files:
            raise SynthgenError(f"{photo}: the calibration's {o.source}: class '{o.cls}' is not a class of the "
                                f"scenario ({', '.join(names)}): the real object would be left out of the labels")


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
