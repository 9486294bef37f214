"""Calibration files users already have: KITTI ``calib/*.txt`` (projection matrices P0..P3) and
Cityscapes ``camera/*.json`` (intrinsic + extrinsic), and the EXIF focal length as the
intrinsics of last resort. Each reader returns plain numbers and raises SynthgenError naming
the file, the line or key and the reason."""
from __future__ import annotations

import json
import math
import os
from typing import Dict, Optional, Tuple

from .._core import SynthgenError

__all__ = ["read_kitti_calib", "read_cityscapes_camera", "focal_from_exif", "MAX_CALIB_BYTES"]

#: Calibration files are small; anything larger is refused before it is read.
MAX_CALIB_BYTES = 1 << 20


def _read_text(path: str, what: str) -> str:
    if not os.path.isfile(path):
        raise SynthgenError(f"{path}: {what} not found")
    if os.path.getsize(path) > MAX_CALIB_BYTES:
        raise SynthgenError(f"{path}: a {what} of {os.path.getsize(path)} bytes is larger than the "
                            f"{MAX_CALIB_BYTES} bytes one can be")
    try:
        with open(path, "r", encoding="utf-8") as f:
            return f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise SynthgenError(f"{path}: cannot read the {what} ({e})") from None


def read_kitti_calib(path: str, camera: str = "P2") -> Dict[str, float]:
    """fx, fy, cx, cy of projection matrix ``camera`` (P0..P3) of a KITTI calibration file
    (lines ``P2: 12 numbers``, row-major 3 x 4). KITTI's rectified cameras have no distortion;
    the camera height is not in the file (KITTI's is 1.65 m; give it in the calibration)."""
    text = _read_text(path, "KITTI calibration file")
    for n, line in enumerate(text.splitlines(), 1):
        key, _, rest = line.partition(":")
        if key.strip() != camera:
            continue
        try:
            v = [float(x) for x in rest.split()]
        except ValueError:
            raise SynthgenError(f"{path}:{n}: {camera}: expected 12 numbers, got '{rest.strip()[:60]}'") from None
        if len(v) != 12 or not all(math.isfinite(x) for x in v):
            raise SynthgenError(f"{path}:{n}: {camera}: expected 12 finite numbers (a 3 x 4 matrix), got {len(v)}")
        fx, cx, fy, cy = v[0], v[2], v[5], v[6]
        if not (fx > 0 and fy > 0) or v[1] != 0.0 or v[4] != 0.0 or (v[8], v[9], v[10]) != (0.0, 0.0, 1.0):
            raise SynthgenError(f"{path}:{n}: {camera}: not a rectified pinhole projection "
                                f"[fx 0 cx tx; 0 fy cy ty; 0 0 1 tz]")
        return {"fx": fx, "fy": fy, "cx": cx, "cy": cy}
    raise SynthgenError(f"{path}: no line '{camera}:' (a KITTI calibration file has P0..P3)")


def read_cityscapes_camera(path: str) -> Dict[str, float]:
    """Intrinsics and the ground pose of a Cityscapes ``camera.json``: fx, fy, cx (u0), cy (v0);
    camera_height (extrinsic z, metres above the road); pitch and roll (radians there, degrees
    here; Cityscapes' vehicle axes: x forward, y left, z up, so a positive pitch looks down and a
    positive roll lifts the camera's left side: synthgen's conventions); road_direction: the
    vehicle's forward seen from the camera (its yaw), degrees to the right."""
    text = _read_text(path, "Cityscapes camera file")
    try:
        d = json.loads(text)
    except json.JSONDecodeError as e:
        raise SynthgenError(f"{path}:{e.lineno}: not JSON ({e.msg})") from None

    def num(section: str, key: str) -> float:
        try:
            v = d[section][key]
        except (KeyError, TypeError):
            raise SynthgenError(f"{path}: {section}.{key}: missing (a Cityscapes camera file has intrinsic "
                                f"fx, fy, u0, v0 and extrinsic x, y, z, pitch, roll, yaw)") from None
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise SynthgenError(f"{path}: {section}.{key}: expected a finite number, got {v!r}")
        return float(v)

    out = {"fx": num("intrinsic", "fx"), "fy": num("intrinsic", "fy"), "cx": num("intrinsic", "u0"),
           "cy": num("intrinsic", "v0"), "camera_height": num("extrinsic", "z"),
           "pitch": math.degrees(num("extrinsic", "pitch")), "roll": math.degrees(num("extrinsic", "roll")),
           "road_direction": math.degrees(num("extrinsic", "yaw"))}
    if not (out["fx"] > 0 and out["fy"] > 0):
        raise SynthgenError(f"{path}: intrinsic fx, fy must be positive")
    if not out["camera_height"] > 0:
        raise SynthgenError(f"{path}: extrinsic.z (the camera's height above the road) must be positive")
    return out


def focal_from_exif(width: int, height: int, focal_35mm: float = 0.0, focal_mm: float = 0.0,
                    sensor_width_mm: Optional[float] = None) -> Optional[Tuple[float, str]]:
    """(focal length in pixels, how) from EXIF: the 35 mm-equivalent focal length (CIPA DC-008:
    equivalence by the diagonal of the 36 x 24 mm frame, 43.27 mm), or the focal length and a
    sensor width given by the user; None when neither is known."""
    if focal_35mm > 0:
        diag = math.hypot(width, height)
        return focal_35mm * diag / math.hypot(36.0, 24.0), f"EXIF FocalLengthIn35mmFilm {focal_35mm:g} mm"
    if focal_mm > 0 and sensor_width_mm:
        return focal_mm * width / float(sensor_width_mm), \
            f"EXIF FocalLength {focal_mm:g} mm on a {sensor_width_mm:g} mm wide sensor"
    return None
