"""The files of one render (``synthgen render``, ``synthgen demo``): every channel.

:func:`write_outputs` writes one frame into a directory:

============== =========================================================================
``rgb.exr``    linear radiance, float32 RGB (lossless ZIP compression)
``rgb.png``    the same, sRGB-encoded (IEC 61966-2-1 OETF), clipped to [0, 1], 8-bit
``depth.exr``  camera-space z (the OpenCV depth convention), float32, one channel "Y";
               ``+inf`` where the camera ray hits nothing
``normal.exr`` world-space shading normal, float32 RGB = xyz, 0 on the background
``albedo.exr`` surface albedo, float32 RGB
``instance.png`` instance id, 16-bit single-channel PNG (0 = background)
``class.png``  class id, 16-bit single-channel PNG (0 = background)
``meta.json``  settings, seed, stats, camera K and world_from_camera, versions, ...
============== =========================================================================

``meta.json`` is written last. Datasets (``synthgen run``) use the output kinds of
:mod:`synthgen.outputs` instead.
"""
from __future__ import annotations

import os
import platform
import sys
from collections.abc import Mapping
from typing import Any, Dict, Optional, Tuple

import numpy as np
import OpenImageIO as oiio

from .._core import SynthgenError, __version__
from .files import as_hwc, check_ids, write_exr, write_id_png, write_json, write_srgb_png

__all__ = ["OUTPUT_FILES", "camera_meta", "versions", "make_meta", "write_outputs"]

#: Files written by :func:`write_outputs`, in writing order.
OUTPUT_FILES = ("rgb.exr", "rgb.png", "depth.exr", "normal.exr", "albedo.exr", "instance.png", "class.png",
                "meta.json")


def camera_meta(camera: Any) -> Dict[str, Any]:
    """JSON-ready description of a PinholeCamera (or any object with fx, fy, cx, cy,
    width, height, world_from_camera): intrinsics, ``K`` (3x3) and world_from_camera
    (4x4, OpenCV camera axes: x right, y down, z forward)."""
    fx, fy, cx, cy = (float(getattr(camera, k)) for k in ("fx", "fy", "cx", "cy"))
    return {
        "model": "pinhole",
        "convention": "opencv",
        "width": int(camera.width),
        "height": int(camera.height),
        "fx": fx,
        "fy": fy,
        "cx": cx,
        "cy": cy,
        "K": [[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]],
        "world_from_camera": np.asarray(camera.world_from_camera, dtype=np.float64).tolist(),
        **_distortion_meta(camera),
    }


def _distortion_meta(camera: Any) -> Dict[str, Any]:
    """{"distortion": [k1, k2, p1, p2, k3]} (OpenCV's model; the image is rendered through it)
    for a camera with lens distortion, else {}."""
    d = [float(v) for v in (getattr(camera, "distortion", None) or ())]
    return {"distortion": d} if any(v != 0.0 for v in d) else {}


def image_points(camera: Any, world_from_object: np.ndarray, points: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Image positions (N x 2, continuous pixel coordinates) and camera-space depths (N: z along
    the optical axis, as the depth output) of object-space points (N x 3) of an object placed by
    ``world_from_object`` (4 x 4), seen by a PinholeCamera: through its lens distortion when it
    has one, as the renderer's rays go (points behind the camera: NaN with a distortion)."""
    p = np.asarray(points, np.float64).reshape(-1, 3)
    cam_from_object = np.linalg.inv(np.asarray(camera.world_from_camera, np.float64)) @ \
        np.asarray(world_from_object, np.float64)
    c = (cam_from_object @ np.c_[p, np.ones(len(p))].T)[:3]
    if any(float(k) != 0.0 for k in (getattr(camera, "distortion", None) or ())):
        # NOTE: K alone would put an off-centre point where an undistorted lens draws it (k1 =
        # -0.3, 676 x 380, fx 338: 44 px off at the image's side): the camera's own projection.
        world = (np.asarray(world_from_object, np.float64) @ np.c_[p, np.ones(len(p))].T)[:3].T
        return np.asarray(camera.project_points(world), np.float64), c[2]
    uv = np.asarray(camera.K, np.float64) @ c
    return (uv[:2] / uv[2]).T, c[2]


def versions() -> Dict[str, str]:
    """Versions of synthgen and the libraries that produced the files."""
    import yaml

    return {
        "synthgen": __version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "OpenImageIO": oiio.VERSION_STRING,
        "PyYAML": getattr(yaml, "__version__", "unknown"),
        "platform": sys.platform,
    }


def make_meta(*, camera: Any, settings: Mapping[str, Any], stats: Optional[Mapping[str, Any]] = None,
              scene: Optional[Mapping[str, Any]] = None, extra: Optional[Mapping[str, Any]] = None) -> Dict[str, Any]:
    """The content of meta.json: ``settings`` (render settings, including ``seed``),
    ``seed``, ``stats``, ``camera`` (:func:`camera_meta`), ``scene`` (e.g. the meta of
    :func:`synthgen.scene.scene_file.load_scene`), ``versions`` and any ``extra`` keys."""
    meta: Dict[str, Any] = {
        "format": "synthgen-frame",
        "format_version": 1,
        "settings": dict(settings),
        "seed": settings.get("seed"),
        "stats": dict(stats or {}),
        "camera": camera if isinstance(camera, Mapping) else camera_meta(camera),
        "outputs": {
            "rgb.exr": "linear RGB radiance, float32",
            "rgb.png": "sRGB-encoded RGB, 8-bit, clipped",
            "depth.exr": "camera-space z (OpenCV), float32 channel Y, +inf on background",
            "normal.exr": "world-space shading normal xyz as RGB, float32, 0 on background",
            "albedo.exr": "surface albedo, float32 RGB",
            "instance.png": "instance id, uint16, 0 = background",
            "class.png": "class id, uint16, 0 = background",
        },
        "versions": versions(),
    }
    if scene is not None:
        meta["scene"] = dict(scene)
    if extra:
        meta.update(extra)
    return meta


# ---------------------------------------------------------------------------------------
# One frame


def _get(result: Any, name: str) -> np.ndarray:
    if isinstance(result, Mapping):
        if name not in result:
            raise SynthgenError(f"write_outputs: missing array '{name}'")
        return np.asarray(result[name])
    return np.asarray(getattr(result, name))


def write_outputs(out_dir: str | os.PathLike, result: Any, meta: Mapping[str, Any]) -> Dict[str, str]:
    """Writes every file of :data:`OUTPUT_FILES` for one frame into ``out_dir``.

    ``result`` is a :class:`synthgen.RenderResult` or a mapping with the arrays ``rgb``
    (H x W x 3), ``depth`` (H x W), ``normal``, ``albedo`` (H x W x 3), ``instance_id``
    and ``class_id`` (H x W integers); ``meta`` is the meta.json content (see
    :func:`make_meta`). All arrays are checked (shapes, id range) before the first file
    is written. Creates ``out_dir``; returns {file name: path} in writing order.
    """
    out_dir = os.fspath(out_dir)
    rgb = as_hwc(_get(result, "rgb"), "rgb", 3)
    h, w = rgb.shape[:2]
    depth = _get(result, "depth")
    normal = as_hwc(_get(result, "normal"), "normal", 3)
    albedo = as_hwc(_get(result, "albedo"), "albedo", 3)
    inst = check_ids(_get(result, "instance_id"), "instance_id")
    cls = check_ids(_get(result, "class_id"), "class_id")
    for name, a in (("depth", depth), ("normal", normal), ("albedo", albedo), ("instance_id", inst),
                    ("class_id", cls)):
        if a.shape[:2] != (h, w):
            raise SynthgenError(f"write_outputs: '{name}' has shape {a.shape}, expected {h} x {w} like rgb")
    if depth.ndim != 2:
        raise SynthgenError(f"write_outputs: 'depth' must be H x W, got shape {depth.shape}")
    os.makedirs(out_dir, exist_ok=True)
    j = lambda name: os.path.join(out_dir, name)  # noqa: E731
    paths = {
        "rgb.exr": write_exr(j("rgb.exr"), rgb),
        "rgb.png": write_srgb_png(j("rgb.png"), rgb),
        "depth.exr": write_exr(j("depth.exr"), depth),
        "normal.exr": write_exr(j("normal.exr"), normal),
        "albedo.exr": write_exr(j("albedo.exr"), albedo),
        "instance.png": write_id_png(j("instance.png"), inst),
        "class.png": write_id_png(j("class.png"), cls),
    }
    meta = dict(meta)
    meta.setdefault("files", list(OUTPUT_FILES))
    meta.setdefault("image_size", [w, h])
    paths["meta.json"] = write_json(j("meta.json"), meta)
    return paths
