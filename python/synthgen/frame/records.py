"""The records of a frame: each object as placed (:class:`PlacedObject`), the camera of a
sampled frame, and the metadata written for a frame (boxes, occlusion, truncation, 3D pose
in the camera frame, what the randomizers did)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import PinholeCamera
from ..outputs.coco import mask_bbox
from ..outputs.kitti import wrap_angle
from ..scenario.sample import CameraSpec, ObjectSpec
from .resources import Shape

__all__ = ["PlacedObject", "frame_camera", "object_records"]


@dataclass
class PlacedObject:
    """One object of a frame while it is set up and placed."""

    spec: ObjectSpec
    shape: Shape
    instance: int                  #: its instance id in the scene
    local: np.ndarray              #: object_from_shape: scale and lift onto the ground
    radius: float                  #: footprint radius on the ground
    dims: np.ndarray               #: box size in metres (x, y, z)
    mount_height: Optional[float] = None   #: sign / plate: height of its lower edge (a post below)
    decor: Optional[int] = None    #: index of its post in the decor pool
    world: Optional[np.ndarray] = None     #: world_from_object once placed
    #: What each randomizer did (recorded in the metadata under its key), in sample order.
    info: Dict[str, Any] = field(default_factory=dict)


def frame_camera(cam: CameraSpec, resolution: Tuple[int, int], rng: np.random.Generator) -> PinholeCamera:
    """The PinholeCamera of a sampled camera: an orbit around a (jittered) target or a
    look-at pose, a vertical field of view or intrinsics."""
    w, h = resolution
    pose = cam.pose
    if pose["type"] == "orbit":
        target = np.asarray(pose["target"], np.float64)
        j = float(pose["jitter"])
        if j > 0:
            target = target + rng.uniform(-j, j, 3)
        el, az = math.radians(pose["elevation"]), math.radians(pose["azimuth"])
        d = float(pose["distance"])
        eye = target + d * np.array([math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)])
    else:
        eye, target = np.asarray(pose["eye"], np.float64), np.asarray(pose["target"], np.float64)
    wfc = np.asarray(PinholeCamera.look_at(list(map(float, eye)), list(map(float, target)), [0.0, 1.0, 0.0]),
                     np.float64)
    k = cam.intrinsics
    if "fx" in k:
        fx = k["fx"]
        return PinholeCamera(fx, k.get("fy", fx), k.get("cx", 0.5 * w), k.get("cy", 0.5 * h), w, h, wfc)
    return PinholeCamera.from_fov(cam.fov_y, w, h, wfc)


def object_records(objects: Sequence[PlacedObject], keep: Sequence[bool], dropped: Mapping[int, str],
                   amodal: Mapping[int, Tuple[int, int]], ids: np.ndarray, camera: PinholeCamera,
                   class_names: Sequence[str]) -> List[Dict[str, Any]]:
    """The metadata of each object: labels, what its randomizers did, and for kept objects
    the visible / amodal pixels, occlusion, truncation, box and 3D pose in the camera frame
    (bottom centre, dimensions h, w, l; heading = the object's +x)."""
    cfw = np.linalg.inv(np.asarray(camera.world_from_camera, np.float64))
    out = []
    for k, o in enumerate(objects):
        s = o.spec
        rec: Dict[str, Any] = {"index": k, "instance_id": k + 1, "class": class_names[s.class_index],
                               "class_id": s.class_index + 1, "kind": s.kind}
        rec.update(o.info)
        if not keep[k]:
            rec["dropped"] = dropped.get(k, "no free spot in the placement region")
            out.append(rec)
            continue
        mask = ids == k + 1
        vis = int(mask.sum())
        inside, total = amodal[k]
        rec.update({"visible_pixels": vis, "amodal_pixels": inside,
                    "occlusion": float(1.0 - vis / inside) if inside else 1.0,
                    "visible_fraction": float(vis / inside) if inside else 0.0,
                    "truncation": float(1.0 - inside / total) if total else 1.0,
                    "bbox": mask_bbox(mask)})
        world = o.world
        base = np.array([world[0, 3], 0.0, world[2, 3], 1.0])  # the footprint centre on the ground
        loc_cam = (cfw @ base)[:3]
        heading = cfw[:3, :3] @ (world[:3, :3] @ np.array([1.0, 0.0, 0.0]))
        ry = math.atan2(-heading[2], heading[0])
        dims = o.dims
        rec.update({"world_from_object": world.tolist(), "dimensions_hwl": [float(dims[1]), float(dims[2]),
                                                                             float(dims[0])],
                    "location_camera": [float(v) for v in loc_cam], "rotation_y": float(wrap_angle(ry)),
                    "alpha": float(wrap_angle(ry - math.atan2(loc_cam[0], loc_cam[2])))})
        out.append(rec)
    return out
