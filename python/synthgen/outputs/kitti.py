"""Output kinds ``kitti``: KITTI object labels, ``kitti/NNNNNN.txt``, and ``kitti_calib``:
their calibration, ``kitti_calib/NNNNNN.txt``.

``type truncated occluded alpha left top right bottom h w l x y z rotation_y``; the box is in
pixel-edge coordinates (right = x + w); 3D fields in the camera frame (x right, y down, z
forward, metres) when known, else KITTI's "unknown" values (-1 for dimensions, -1000 for the
location, -10 for the angles). The 3D fields are in the *level* camera frame: the camera
with its pitch and roll removed (y along the world's vertical), because KITTI's boxes turn
about y only; the calibration's P2 projects that frame into the (tilted) image, so
``P2 @ corner`` lands on the object.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Dict, List, Optional

from .files import write_text
from .registry import Frame, OutputKind, register

__all__ = ["kitti_line", "parse_kitti", "kitti_occlusion_level", "wrap_angle", "calib_text", "parse_calib"]


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


def write_kitti(path: str, frame: Frame) -> str:
    lines = [kitti_line(o["class"], o["bbox"], truncated=o["truncation"],
                        occluded=kitti_occlusion_level(o["visible_fraction"]), alpha=o["alpha"],
                        dimensions=o["dimensions_hwl"], location=o["location_camera"],
                        rotation_y=o["rotation_y"]) for o in list(frame.visible_objects()) + frame.parts()]
    # A photo's real objects (their 3D box unknown: KITTI's -1 / -1000 / -10) and its ignore
    # regions as DontCare.
    for o in frame.real_objects():
        lines.append(kitti_line(o["class"], _xywh(o["bbox"]), truncated=o["truncation"],
                                occluded=kitti_occlusion_level(o["visible_fraction"])))
    for o in frame.ignore_regions():
        lines.append(kitti_line("DontCare", _xywh(o["bbox"]), truncated=-1.0, occluded=-1))
    return write_text(path, "".join(line + "\n" for line in lines))


def _xywh(box: Sequence[float]) -> List[float]:
    x0, y0, x1, y1 = (float(v) for v in box)
    return [x0, y0, x1 - x0, y1 - y0]


def calib_text(P2: Sequence[Sequence[float]], level_from_world: Sequence[Sequence[float]]) -> str:
    """A KITTI calibration file: P0..P3 = P2 (the frame's camera), R0_rect = I, and
    Tr_velo_to_cam = level_from_world (the world playing the velodyne's part)."""
    p = " ".join(f"{v:.12e}" for row in P2 for v in row)
    t = " ".join(f"{v:.12e}" for row in level_from_world for v in row)
    eye = " ".join(f"{v:.12e}" for v in (1, 0, 0, 0, 1, 0, 0, 0, 1))
    ident34 = " ".join(f"{v:.12e}" for v in (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0))
    return (f"P0: {p}\nP1: {p}\nP2: {p}\nP3: {p}\nR0_rect: {eye}\nTr_velo_to_cam: {t}\n"
            f"Tr_imu_to_velo: {ident34}\n")


def write_kitti_calib(path: str, frame: Frame) -> str:
    kf = frame.meta["kitti_frame"]
    return write_text(path, calib_text(kf["P2"], kf["level_from_world"]))


def parse_calib(text: str) -> Dict[str, List[float]]:
    """The matrices of a KITTI calibration file by name (flat lists)."""
    out: Dict[str, List[float]] = {}
    for line in text.splitlines():
        if ":" in line:
            k, v = line.split(":", 1)
            out[k.strip()] = [float(x) for x in v.split()]
    return out


register(OutputKind("kitti", "KITTI labels with 2D boxes and 3D boxes in the camera frame (kitti/NNNNNN.txt)",
                    order=90, directory="kitti", extension=".txt", write=write_kitti, module=__name__))
register(OutputKind("kitti_calib", "KITTI calibration per frame (kitti_calib/NNNNNN.txt): P2 projects the labels' "
                    "level camera frame into the image", order=95, directory="kitti_calib", extension=".txt",
                    write=write_kitti_calib, module=__name__))
