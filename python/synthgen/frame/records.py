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

__all__ = ["PlacedObject", "frame_camera", "object_records", "weather_labels"]


@dataclass
class PlacedObject:
    """One object of a frame while it is set up and placed."""

    spec: ObjectSpec
    shape: Shape
    instance: int                  #: its instance id in the scene
    local: np.ndarray              #: object_from_shape: scale and lift onto the ground
    radius: float                  #: footprint radius on the ground
    dims: np.ndarray               #: box size in metres (x, y, z)
    post_height: Optional[float] = None    #: sign / plate: the top of the post it stands on
    #: The model's forward direction in its own coordinates (KITTI's heading follows it).
    forward: Tuple[float, float, float] = (1.0, 0.0, 0.0)
    decor: Optional[int] = None    #: index of its post in the decor pool
    world: Optional[np.ndarray] = None     #: world_from_object once placed
    post_world: Optional[np.ndarray] = None  #: world_from_object of its post once placed
    #: What each randomizer did (recorded in the metadata under its key), in sample order.
    info: Dict[str, Any] = field(default_factory=dict)
    #: The material it renders with (-1: a model with materials of its own, ``materials``).
    material: int = -1
    #: A model's own materials: mesh material id -> the material it renders with (after the
    #: randomizers; weather wraps each of them).
    materials: Dict[int, int] = field(default_factory=dict)


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
        return PinholeCamera(fx, k.get("fy", fx), k.get("cx", 0.5 * w), k.get("cy", 0.5 * h), w, h, wfc,
                             distortion=tuple(cam.distortion))
    c = PinholeCamera.from_fov(cam.fov_y, w, h, wfc)
    if any(cam.distortion):
        c = PinholeCamera(c.fx, c.fy, c.cx, c.cy, w, h, wfc, distortion=tuple(cam.distortion))
    return c


def level_frame(camera: PinholeCamera) -> Dict[str, Any]:
    """The frame of KITTI's 3D labels: the camera's position and heading with its pitch and
    roll removed (x right, y down along the world's vertical, z forward, level), so boxes
    that stand on the ground turn about its y axis only, as KITTI assumes. ``level_from_world``
    (3 x 4) maps world points into it, ``P2`` (3 x 4) projects its points into the image (the
    real, tilted camera): KITTI's calibration with R0_rect = I and the world as its velodyne
    frame."""
    wfc = np.asarray(camera.world_from_camera, np.float64)
    R_wc, c = wfc[:3, :3], wfc[:3, 3]
    fwd = R_wc @ np.array([0.0, 0.0, 1.0])
    flat = np.array([fwd[0], 0.0, fwd[2]])
    if np.linalg.norm(flat) < 1e-6:  # looking straight down or up: the image's up is forward
        up_img = R_wc @ np.array([0.0, -1.0, 0.0])
        flat = np.array([up_img[0], 0.0, up_img[2]]) * (1.0 if fwd[1] < 0 else -1.0)
    z = flat / np.linalg.norm(flat)
    y = np.array([0.0, -1.0, 0.0])
    x = np.cross(y, z)
    L = np.stack([x, y, z])                       # level_from_world rotation
    level_from_world = np.concatenate([L, (-L @ c)[:, None]], axis=1)
    cam_from_level = R_wc.T @ L.T
    K = np.asarray(camera.K, np.float64)
    P2 = K @ np.concatenate([cam_from_level, np.zeros((3, 1))], axis=1)
    return {"level_from_world": level_from_world.tolist(), "P2": P2.tolist()}


def object_records(objects: Sequence[PlacedObject], keep: Sequence[bool], dropped: Mapping[int, str],
                   amodal: Mapping[int, Tuple[int, int]], ids: np.ndarray, camera: PinholeCamera,
                   class_names: Sequence[str]) -> List[Dict[str, Any]]:
    """The metadata of each object: labels, what its randomizers did, and for kept objects
    the visible / amodal pixels, occlusion, truncation, box and 3D pose in KITTI's level
    camera frame (:func:`level_frame`)
    (bottom centre; dimensions h, w, l along the model's up, lateral and forward axes;
    heading = the direction its forward axis points)."""
    lfw = np.asarray(level_frame(camera)["level_from_world"], np.float64)  # KITTI's 3D frame
    out = []
    for k, o in enumerate(objects):
        s = o.spec
        if not s.labelled:  # label: false: where it is, nothing else
            rec = {"index": k, "label": False, "instance_id": 0, "class": None, "class_id": 0, "kind": s.kind}
            rec.update(o.info)
            if keep[k]:
                rec["world_from_object"] = o.world.tolist()
            else:
                rec["dropped"] = dropped.get(k, "no free spot in the placement region")
            out.append(rec)
            continue
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
        loc_cam = lfw @ base
        heading = lfw[:, :3] @ (world[:3, :3] @ np.asarray(o.forward, np.float64))
        ry = math.atan2(-heading[2], heading[0])
        dims = o.dims
        rec.update({"world_from_object": world.tolist(), "dimensions_hwl": [float(dims[1]), float(dims[2]),
                                                                             float(dims[0])],
                    "location_camera": [float(v) for v in loc_cam], "rotation_y": float(wrap_angle(ry)),
                    "alpha": float(wrap_angle(ry - math.atan2(loc_cam[0], loc_cam[2])))})
        out.append(rec)
    return out


def weather_labels(records: List[Dict[str, Any]], transmittance: np.ndarray, rgb: np.ndarray,
                   instance_id: np.ndarray) -> None:
    """Per visible object of a foggy frame, ``weather``: ``transmittance``, the mean over its
    pixels of the medium's transmittance along the camera ray to it (the share of its own light
    that reaches the camera: Koschmieder's factor), and ``contrast``, its visible contrast in
    the rendered image, |Y_object - Y_surround| / Y_surround (luminance; the surround: the
    unlabelled pixels within 3 pixels of it), so that objects fog has made invisible can be
    filtered."""
    from ..post.photo.measure import dilate

    y = np.asarray(rgb, np.float64)[..., :3] @ np.array([0.2126, 0.7152, 0.0722])
    for rec in records:
        if rec.get("dropped") or not rec.get("visible_pixels"):
            continue
        mask = instance_id == rec["instance_id"]
        if not mask.any():
            continue
        ring = dilate(mask, 3) & (instance_id == 0)
        y_obj = float(y[mask].mean())
        y_ring = float(y[ring].mean()) if ring.any() else float("nan")
        contrast = abs(y_obj - y_ring) / y_ring if ring.any() and y_ring > 1e-6 else float("nan")
        rec["weather"] = {"transmittance": round(float(np.asarray(transmittance)[mask].mean()), 6),
                          "contrast": round(contrast, 6) if np.isfinite(contrast) else None}
