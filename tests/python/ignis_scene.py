"""Builds a synthgen Scene from an Ignis JSON scene (the subset used by ../shared/assets/ignis-cbox).

Supported: ``externals`` (files merged first, the including file overrides), ``technique.max_depth``,
``camera`` (perspective: ``transform`` row-major camera-to-world, ``fov`` in degrees),
``film.size``, ``bsdfs`` of type ``diffuse`` (RGB ``reflectance``), ``shapes`` of type ``obj``
(``filename`` relative to the JSON file, optional ``transform``), ``entities`` (shape + bsdf,
optional ``transform`` applied after the shape's) and ``lights`` of type ``area`` (``entity`` +
RGB ``radiance``). Anything else raises ``NotImplementedError`` so a scene is never silently
rendered differently from what the reference renderer saw.

Ignis cameras look along +z with +y up and +x to the image *left*; synthgen uses the OpenCV
convention (x right, y down, z forward), hence ``world_from_camera = transform @ diag(-1, -1, 1, 1)``.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

import synthgen as sg

# Path of the shared test data: <repo>/../shared (see ../shared/README.md).
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED = os.path.abspath(os.path.join(REPO, "..", "shared"))
CBOX_DIR = os.path.join(SHARED, "assets", "ignis-cbox")

IGNIS_TO_OPENCV = np.diag([-1.0, -1.0, 1.0, 1.0])


@dataclass
class IgnisScene:
    scene: sg.Scene
    camera: sg.PinholeCamera
    max_depth: int
    width: int
    height: int
    json_path: str
    entity_instances: dict = field(default_factory=dict)  # entity name -> instance handle


def _load_json_with_externals(path: str) -> dict:
    with open(path) as f:
        doc = json.load(f)
    merged: dict = {}
    for ext in doc.get("externals", []):
        sub = _load_json_with_externals(os.path.join(os.path.dirname(path), ext["filename"]))
        _merge(merged, sub)
    _merge(merged, {k: v for k, v in doc.items() if k != "externals"})
    return merged


def _merge(dst: dict, src: dict) -> None:
    for k, v in src.items():
        if isinstance(v, list) and isinstance(dst.get(k), list):
            dst[k] = dst[k] + v  # libraries (bsdfs, shapes, ...) accumulate
        elif isinstance(v, dict) and isinstance(dst.get(k), dict):
            _merge(dst[k], v)
        else:
            dst[k] = v


def _transform(value, what: str) -> np.ndarray:
    if value is None:
        return np.eye(4)
    if isinstance(value, list) and all(isinstance(x, (int, float)) for x in value):
        a = np.asarray(value, dtype=np.float64)
        if a.size == 16:
            return a.reshape(4, 4)
        if a.size == 12:
            return np.vstack([a.reshape(3, 4), [0, 0, 0, 1]])
        if a.size == 9:
            m = np.eye(4)
            m[:3, :3] = a.reshape(3, 3)
            return m
    raise NotImplementedError(f"{what}: unsupported transform {value!r} (expected 9, 12 or 16 numbers)")


def _rgb(value, what: str) -> list:
    if isinstance(value, (int, float)):
        return [float(value)] * 3
    if isinstance(value, list) and len(value) == 3 and all(isinstance(x, (int, float)) for x in value):
        return [float(x) for x in value]
    raise NotImplementedError(f"{what}: only constant RGB values are supported, got {value!r}")


def load_ignis_scene(json_path: str) -> IgnisScene:
    json_path = os.path.abspath(json_path)
    base = os.path.dirname(json_path)
    j = _load_json_with_externals(json_path)
    technique = j.get("technique", {})
    if technique.get("type", "path") != "path":
        raise NotImplementedError(f"technique {technique.get('type')!r}")
    max_depth = int(technique.get("max_depth", 64))

    bsdfs = {}
    for b in j.get("bsdfs", []):
        if b.get("type") != "diffuse":
            raise NotImplementedError(f"bsdf {b.get('name')!r} of type {b.get('type')!r}")
        bsdfs[b["name"]] = _rgb(b.get("reflectance", 0.5), f"bsdf {b['name']}")
    shapes = {}
    for s in j.get("shapes", []):
        if s.get("type") != "obj":
            raise NotImplementedError(f"shape {s.get('name')!r} of type {s.get('type')!r}")
        shapes[s["name"]] = s
    area_lights = {}
    for light in j.get("lights", []):
        if light.get("type") != "area":
            raise NotImplementedError(f"light {light.get('name')!r} of type {light.get('type')!r}")
        area_lights[light["entity"]] = _rgb(light.get("radiance", 1.0), f"light {light['name']}")

    scene = sg.Scene()
    mesh_ids = {}  # each shape file is loaded once, instanced per entity
    entity_instances = {}
    for e in j.get("entities", []):
        shape = shapes[e["shape"]]
        if e["shape"] not in mesh_ids:
            mesh_ids[e["shape"]] = scene.load_mesh_file(os.path.join(base, shape["filename"]))["mesh_id"]
        world = _transform(e.get("transform"), f"entity {e['name']}") @ _transform(
            shape.get("transform"), f"shape {shape['name']}")
        albedo = bsdfs[e["bsdf"]]
        if e["name"] in area_lights:
            mat = scene.add_material("emissive", {"radiance": area_lights[e["name"]], "albedo": albedo})
        else:
            mat = scene.add_material("diffuse", {"albedo": albedo})
        entity_instances[e["name"]] = scene.add_instance(mesh_ids[e["shape"]], world.astype(np.float32),
                                                         material_id=mat)
    missing = set(area_lights) - set(entity_instances)
    if missing:
        raise ValueError(f"area lights reference unknown entities {sorted(missing)}")

    cam = j["camera"]
    if cam.get("type", "perspective") != "perspective":
        raise NotImplementedError(f"camera type {cam.get('type')!r}")
    width, height = (int(x) for x in j.get("film", {}).get("size", [800, 600]))
    if width != height:
        # Ignis' fov axis convention only matters for non-square films; the test scenes are square.
        raise NotImplementedError("non-square films: the fov axis convention is not handled")
    world_from_camera = _transform(cam.get("transform"), "camera") @ IGNIS_TO_OPENCV
    camera = sg.PinholeCamera.from_fov(float(cam.get("fov", 60.0)), width, height,
                                       world_from_camera.astype(np.float32))
    scene.set_camera(camera)
    return IgnisScene(scene, camera, max_depth, width, height, json_path, entity_instances)


def read_exr_rgb(path: str) -> np.ndarray:
    """H x W x 3 float32 linear RGB of an EXR (OpenImageIO)."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise OSError(f"{path}: {buf.geterror()}")
    px = buf.get_pixels(oiio.FLOAT)
    return np.ascontiguousarray(px[:, :, :3], dtype=np.float32)
