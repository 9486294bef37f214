"""Output kind ``yolo``: YOLO labels, ``labels/NNNNNN.txt`` (``class cx cy w h``, the box
centre and size divided by the image width / height) and ``dataset.yaml`` naming the
classes."""
from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any, List, Tuple

from .coco import xyxy_to_xywh
from .files import write_text
from .registry import Frame, OutputKind, register

__all__ = ["yolo_line", "yolo_lines", "parse_yolo", "write_yolo_dataset_yaml"]


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


def write_yolo(path: str, frame: Frame) -> str:
    w, h = frame.size
    lines = [yolo_line(o["class_id"] - 1, o["bbox"], w, h) for o in list(frame.visible_objects()) + frame.parts()]
    # A photo's real objects follow (YOLO has no ignore regions: they are in COCO, KITTI, meta).
    lines += [yolo_line(o["class_id"] - 1, xyxy_to_xywh(o["bbox"]), w, h) for o in frame.real_objects()]
    return write_text(path, "".join(line + "\n" for line in lines))


def write_yolo_dataset_yaml(out_dir: str, class_names: Sequence[str], frames: Sequence[int] = ()) -> str:
    """dataset.yaml: the image lists of the split (splits/*.txt, :mod:`synthgen.outputs.split`)
    and the class names; without a split (a dataset of an older run), every image for both."""
    import yaml

    lists = {s: f"splits/{s}.txt" for s in ("train", "val", "test")
             if os.path.exists(os.path.join(out_dir, "splits", f"{s}.txt"))}
    doc: dict = {"path": os.path.abspath(out_dir)}
    if lists:
        doc.update({"train": lists["train"], "val": lists["val"]})
        if os.path.getsize(os.path.join(out_dir, lists["test"])) > 0:
            doc["test"] = lists["test"]
    else:
        doc.update({"train": "images", "val": "images"})
    doc["names"] = {i: n for i, n in enumerate(class_names)}
    text = yaml.safe_dump(doc, sort_keys=False)
    return write_text(os.path.join(out_dir, "dataset.yaml"), text)


register(OutputKind("yolo", "YOLO labels (labels/NNNNNN.txt) and dataset.yaml", order=80, directory="labels",
                    extension=".txt", write=write_yolo, finalize=write_yolo_dataset_yaml, module=__name__))
