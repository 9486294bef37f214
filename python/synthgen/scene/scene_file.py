"""Static scene files: a thin, validated YAML layer over :class:`synthgen.Scene`.

A scene file is a YAML mapping::

    version: 1                     # optional, the format version (only 1 exists)
    description: "..."             # optional free text
    camera:
      width: 640                   # pixels
      height: 480
      fov_y: 40                    # vertical field of view in degrees ...
      # fx: 500, fy: 500, cx: 320, cy: 240   # ... or OpenCV intrinsics
      look_at: {eye: [0, 2, -6], target: [0, 0.5, 0], up: [0, 1, 0]}
      # world_from_camera: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]  # or a 4x4 pose
    textures:                      # named; referenced by name from materials and textures
      wood: {type: image, file: textures/wood.png, colorspace: srgb, wrap: repeat}
      rust: {type: noise, pattern: turbulence, scale: 4}
    materials:                     # named; referenced by name from objects
      red: {type: diffuse, albedo: [0.8, 0.1, 0.1]}
      floor: {type: diffuse, albedo: {texture: wood}}
    objects:                       # at least one
      - name: ball                 # optional, reported in meta.json
        primitive: sphere          # sphere {radius, segments, rings} | box {size} |
        radius: 0.5                #   plane {size} | ground {radius} (to the horizon)
        class_id: 1                # 0..65535 (0 is also the background's label)
        material: red              # optional; default: the mesh file's materials / grey
        translate: [0, 0.5, 0]     # world_from_object = T * R * S ...
        rotate: {axis: [0, 1, 0], angle: 30}
      - mesh: {file: meshes/bunny.obj}           # OBJ / PLY / glTF / GLB
        class_id: 2
      - shape: {type: torus, major_radius: 1}    # a shape of an extension (below)
    allow_extensions: true         # with --allow-extensions: compile and run ...
    extensions: [shapes.c]         # ... these C files (docs/extensions.md)
    lights:
      - {type: sun, direction: [0.3, 1, 0.2], irradiance: 3}
    render: {spp: 64, max_depth: 8}

The vocabulary of ``camera``, ``textures``, ``materials``, ``lights`` and ``render`` is the
plugins' own: every key, type, default and range comes from the plugin's C++ declaration
(:mod:`synthgen.schema.plugins`); ``synthgen schema`` prints it. Relative file paths are
resolved against the directory of the YAML file. Every problem raises
:class:`~synthgen.schema.SceneFileError` (``FILE:LINE:COLUMN: key.path: reason``), errors of
the native core included (re-raised at the YAML entry that caused them).
"""
from __future__ import annotations

import hashlib
import math
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import PinholeCamera, Scene, TextureRef
from ..schema import limits
from ..schema.errors import Loc, ValidationContext, suggest
from ..schema.fields import (EMPTY, Bool, Choice, FilePath, Integer, ListOf, MapOf, MaterialName, Matrix4, Number,
                             Record, String, TextureName, Validated, Vector)
from ..schema.plugins import given_params, plugin_record, settings_record
from ..schema.reference import format_schema as _format_schema
from ..schema.yaml_io import read_yaml
from . import primitives

__all__ = ["load_scene", "build_scene", "build_validated", "validate_scene", "validate_render_settings",
           "format_schema", "world_from_object", "SCENE_SCHEMA", "CAMERA", "TEXTURE", "MATERIAL", "LIGHT", "RENDER",
           "OBJECT"]

_ID_MAX = 65535


def _check_look_at(rec: Validated, ctx: ValidationContext) -> None:
    eye, target = rec["eye"], rec["target"]
    if all(isinstance(v, float) for v in eye + target) and eye == target:
        ctx.error(rec.locs["target"], "'eye' and 'target' coincide")


LOOK_AT = Record({
    "eye": Vector(3, doc="camera position"),
    "target": Vector(3, doc="point the camera looks at (image centre)"),
    "up": Vector(3, (0.0, 1.0, 0.0), doc="world up vector; image y points along -up"),
}, doc="camera pose from eye / target / up", check=_check_look_at)

#: The camera plugin's parameters, posed by ``look_at`` or ``world_from_camera``.
CAMERA = settings_record("camera", "pinhole").extend(
    {"look_at": LOOK_AT}, one_of=[("look_at", "world_from_camera")])
TEXTURE = plugin_record("texture", doc="texture")
MATERIAL = plugin_record("material", doc="material")
LIGHT = plugin_record("light", fields={"name": String(None, doc="free name, reported in meta.json")},
                      doc="light (area lights come from emissive materials)")
MEDIUM = plugin_record("medium", default=None, doc="the participating medium filling the scene (fog, haze; "
                                                    "docs/weather.md)")
SHAPE = plugin_record("shape", default=None,
                      doc="a shape of a loaded extension (its name and parameters; docs/extensions.md)")
RENDER = settings_record("render", "path_tracer", default=EMPTY, doc="render settings (keyword arguments of "
                                                                    "Scene.render)")


def _check_rotate(rec: Validated, ctx: ValidationContext) -> None:
    axis = rec.get("axis")
    if axis is not None and all(isinstance(v, float) for v in axis) and not any(axis):
        ctx.error(rec.locs["axis"], "rotation axis must be a non-zero vector")


ROTATE = Record({
    "axis": Vector(3, doc="rotation axis (normalised)"),
    "angle": Number(None, doc="rotation angle in degrees (right-handed about axis; with axis)"),
    "euler": Vector(3, doc="rotation angles in degrees about the world x, y, z axes"),
    "order": Choice(["xyz", "xzy", "yxz", "yzx", "zxy", "zyx"], "xyz",
                    doc="order in which the euler rotations are applied (xyz: R = Rz Ry Rx)"),
}, doc="rotation: {axis, angle} or {euler, order}",
    one_of=[("axis", "euler")], exclusive=[(("axis", "angle"), ("euler", "order"))],
    requires={"axis": ("angle",), "angle": ("axis",)}, check=_check_rotate)

MESH_FILE = Record({
    "file": FilePath(doc="OBJ (+MTL), PLY, glTF or GLB file (relative to the scene file)"),
}, doc="mesh loaded from a file")

OBJECT = Record({
    "name": String(None, doc="free name, reported in meta.json"),
    "mesh": MESH_FILE,
    "shape": SHAPE,
    "primitive": Choice(["sphere", "box", "cylinder", "cone", "plane", "ground"], doc="built-in procedural mesh"),
    "class_id": Integer(min=0, max=_ID_MAX, doc="semantic class label (0 is also the background)"),
    "instance_id": Integer(None, min=1, max=_ID_MAX, doc="instance label (default: instance handle + 1)"),
    "material": String(None, doc="name of a material under 'materials' (default: the mesh's own)"),
    "translate": Vector(3, (0.0, 0.0, 0.0), doc="translation"),
    "rotate": ROTATE.extend(default=None, doc="rotation {axis, angle} or {euler, order}, in degrees"),
    "scale": Vector(3, (1.0, 1.0, 1.0), min=0, min_open=True, broadcast=True,
                    doc="scale factors (positive; use world_from_object to mirror)"),
    "world_from_object": Matrix4(None, doc="object-to-world matrix instead of translate/rotate/scale"),
}, tag="primitive", variants={
    "sphere": {
        "radius": Number(1.0, min=0, min_open=True, doc="sphere radius"),
        "segments": Integer(64, min=3, max=4096, doc="subdivisions around the y axis"),
        "rings": Integer(32, min=2, max=4096, doc="subdivisions from pole to pole"),
    },
    "box": {
        "size": Vector(3, (1.0, 1.0, 1.0), min=0, min_open=True, broadcast=True,
                       doc="edge lengths along x, y, z (centred at the origin)"),
    },
    "cylinder": {
        "radius": Number(0.5, min=0, min_open=True, doc="radius"),
        "height": Number(1.0, min=0, min_open=True, doc="height along y (centred at the origin)"),
        "segments": Integer(64, min=3, max=4096, doc="subdivisions around the y axis"),
    },
    "cone": {
        "radius": Number(0.5, min=0, min_open=True, doc="radius of the base"),
        "height": Number(1.0, min=0, min_open=True, doc="height along y: base at -height/2, apex at +height/2"),
        "segments": Integer(64, min=3, max=4096, doc="subdivisions around the y axis"),
    },
    "plane": {
        "size": Vector(2, (1.0, 1.0), min=0, min_open=True, broadcast=True,
                       doc="edge lengths along x and z (the y = 0 plane, normal +y)"),
    },
    "ground": {
        "radius": Number(1.0e5, min=0, min_open=True,
                         doc="the y = 0 plane out to this distance in metres (the default reaches the horizon); "
                             "uv = (x, z) in metres"),
    },
}, doc="an instance of a mesh file, primitive or extension shape",
    one_of=[("mesh", "primitive", "shape")],
    exclusive=[(("translate", "rotate", "scale"), ("world_from_object",))])

SCENE_SCHEMA = Record({
    "version": Integer(1, min=1, max=1, doc="scene file format version"),
    "description": String(None, doc="free text"),
    "allow_extensions": Bool(False, doc="this file may compile and run the C files under 'extensions' (with "
                                           "--allow-extensions on the command line too: extensions run with your "
                                           "rights)"),
    "extensions": ListOf(FilePath(doc="a C file"), [], doc="user extensions (C files, synthgen_ext.h) whose textures "
                                                           "and shapes the file uses; docs/extensions.md"),
    "camera": CAMERA,
    "textures": MapOf(TEXTURE, {}, doc="named textures"),
    "materials": MapOf(MATERIAL, {}, doc="named materials"),
    "objects": ListOf(OBJECT, min_items=1, doc="instances of meshes and primitives"),
    "lights": ListOf(LIGHT, [], doc="lights"),
    "medium": MEDIUM,
    "render": RENDER,
}, doc="a synthgen scene")


def format_schema(field: Any = SCENE_SCHEMA, indent: int = 0) -> str:
    """Every key of a schema (default: the scene file's) with type, default and doc."""
    return _format_schema(field, indent)


# ---------------------------------------------------------------------------------------
# Building


def _rotation_matrix(axis: Sequence[float], degrees: float) -> np.ndarray:
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    th = math.radians(degrees)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def world_from_object(obj: Mapping[str, Any]) -> np.ndarray:
    """The 4x4 (float64) object-to-world matrix of a validated object: its
    ``world_from_object``, or T * R * S from ``translate``, ``rotate``, ``scale``."""
    if obj.get("world_from_object") is not None:
        return np.array(obj["world_from_object"], dtype=np.float64)
    m = np.eye(4)
    R = np.eye(3)
    rot = obj.get("rotate")
    if rot:
        if rot.get("axis") is not None:
            R = _rotation_matrix(rot["axis"], rot["angle"])
        else:
            for ax, ang in zip(rot["order"], [rot["euler"]["xyz".index(c)] for c in rot["order"]]):
                R = _rotation_matrix(_AXES[ax], ang) @ R
    m[:3, :3] = R @ np.diag(np.asarray(obj["scale"], dtype=np.float64))
    m[:3, 3] = obj["translate"]
    return m


def _dependency_order(items: Mapping[str, Validated], ref: type, what: str, section: str,
                      ctx: ValidationContext) -> List[str]:
    """Names ordered so that every entry comes after the entries of the same section it
    refers to (``ref`` values: a mix's materials, a blend's textures); a reference cycle is
    an error at its entry, an unknown name an error with the names defined."""
    order: List[str] = []
    state: Dict[str, int] = {}  # 1: visiting, 2: done

    def visit(name: str, via: Optional[Loc]) -> None:
        if state.get(name) == 2:
            return
        if state.get(name) == 1:
            ctx.error(via or items[name].loc, f"{what} '{name}' refers to itself through a reference cycle")
        state[name] = 1
        for v in items[name].values():
            if isinstance(v, ref) and str(v) in items:
                visit(str(v), v.loc)
        state[name] = 2
        order.append(name)

    for n, item in items.items():  # unknown names first, with the full list
        for v in item.values():
            if isinstance(v, ref) and str(v) not in items:
                _lookup(ctx, {k: 0 for k in items}, str(v), v.loc, what, section)
    for n in items:
        visit(n, None)
    return order


def _lookup(ctx: ValidationContext, table: Mapping[str, int], name: str, loc: Loc, what: str, section: str) -> int:
    if name not in table:
        defined = ", ".join(sorted(table)) if table else "none"
        ctx.error(loc, f"unknown {what} '{name}'{suggest(name, table)}; {section} defined: {defined}")
    return table[name]


def _core_params(rec: Validated, textures: Mapping[str, int], materials: Mapping[str, int],
                 ctx: ValidationContext) -> Dict[str, Any]:
    """A plugin's given parameters with names of textures / materials resolved to ids."""
    params = given_params(rec)
    for k, v in params.items():
        if isinstance(v, TextureName):
            params[k] = TextureRef(_lookup(ctx, textures, str(v), v.loc, "texture", "textures"))
        elif isinstance(v, MaterialName):
            params[k] = _lookup(ctx, materials, str(v), v.loc, "material", "materials")
    return params


def _primitive_mesh(obj: Validated) -> Tuple[tuple, Dict[str, np.ndarray], np.ndarray]:
    """(cache key, unit mesh arrays, object_from_unit scale) of a primitive object: one
    unit mesh per kind (and tessellation) is shared by every instance, sized by scaling."""
    kind = obj["primitive"]
    if kind == "sphere":
        return ((kind, obj["segments"], obj["rings"]), primitives.uv_sphere(1.0, obj["segments"], obj["rings"]),
                np.array([obj["radius"]] * 3))
    if kind == "box":
        return (kind,), primitives.box((1.0, 1.0, 1.0)), np.array(obj["size"])
    if kind in ("cylinder", "cone"):
        unit = primitives.cylinder if kind == "cylinder" else primitives.cone
        r, h = obj["radius"], obj["height"]
        return (kind, obj["segments"]), unit(1.0, 1.0, obj["segments"]), np.array([r, h, r])
    if kind == "ground":
        return (kind, obj["radius"]), primitives.ground(obj["radius"]), np.ones(3)
    sx, sz = obj["size"]
    return (kind,), primitives.plane(1.0, 1.0), np.array([sx, 1.0, sz])


def camera_from_spec(cam: Validated, ctx: ValidationContext) -> PinholeCamera:
    """PinholeCamera of a validated ``camera`` record (through the camera plugin)."""
    w, h = cam["width"], cam["height"]
    need, have = w * h * limits.BYTES_PER_PIXEL, limits.available_memory()
    if have is not None and need > have:
        ctx.error(cam.loc, f"{w} x {h} pixels need about {limits.fmt_bytes(need)} of memory to render and write; "
                           f"this machine has {limits.fmt_bytes(have)} available")
    params = given_params(cam, skip=("look_at",))
    if cam.get("look_at") is not None:
        la = cam["look_at"]
        with ctx.core(cam.locs["look_at"]):
            wfc = PinholeCamera.look_at(list(la["eye"]), list(la["target"]), list(la["up"]))
        params["world_from_camera"] = [float(x) for x in np.asarray(wfc).ravel()]
    with ctx.core(cam.loc):
        return PinholeCamera.from_params(params)


def build_validated(spec: Validated, ctx: ValidationContext) -> Tuple[Scene, Dict[str, Any], Dict[str, Any]]:
    """Builds a Scene from a validated scene spec (see :func:`validate_scene`).

    Returns ``(scene, render_settings, meta)`` like :func:`load_scene`. Errors of the
    native core are re-raised as :class:`SceneFileError` at the offending entry.
    """
    scene = Scene()
    meta: Dict[str, Any] = {"source": ctx.source, "description": spec.get("description"),
                            "textures": {}, "materials": {}, "objects": [], "lights": []}

    textures: Dict[str, int] = meta["textures"]
    for name in _dependency_order(spec["textures"], TextureName, "texture", "textures", ctx):
        tex = spec["textures"][name]
        params = _core_params(tex, textures, {}, ctx)
        with ctx.core(tex.loc):
            textures[name] = scene.add_texture(tex["type"], params)

    materials: Dict[str, int] = meta["materials"]
    for name in _dependency_order(spec["materials"], MaterialName, "material", "materials", ctx):
        mat = spec["materials"][name]
        params = _core_params(mat, textures, materials, ctx)
        with ctx.core(mat.loc):
            materials[name] = scene.add_material(mat["type"], params)

    mesh_cache: Dict[Any, Dict[str, Any]] = {}
    for obj in spec["objects"]:
        info: Dict[str, Any] = {"name": obj.get("name")}
        if obj.get("mesh") is not None:
            path = obj["mesh"]["file"]
            key: tuple = ("file", path)
            if key not in mesh_cache:
                with ctx.core(obj.locs["mesh"]):
                    mesh_cache[key] = dict(scene.load_mesh_file(path))
            info["mesh"] = path
            instance_from_object = np.eye(4)
        elif obj.get("shape") is not None:
            params = given_params(obj["shape"])
            key = ("shape", obj["shape"]["type"], repr(sorted(params.items())))
            if key not in mesh_cache:
                with ctx.core(obj.locs["shape"]):
                    mesh_cache[key] = {"mesh_id": scene.add_shape(obj["shape"]["type"], params)}
            info["shape"] = obj["shape"]["type"]
            instance_from_object = np.eye(4)
        else:
            key, arrays, size = _primitive_mesh(obj)
            if key not in mesh_cache:
                with ctx.core(obj.loc):
                    mesh_cache[key] = {"mesh_id": scene.add_mesh(**arrays, name=obj["primitive"])}
            info["primitive"] = obj["primitive"]
            instance_from_object = np.diag([*size, 1.0])
        mesh_id = mesh_cache[key]["mesh_id"]
        material_id = -1
        if obj.get("material") is not None:
            material_id = _lookup(ctx, materials, obj["material"], obj.locs["material"], "material", "materials")
        wfo = world_from_object(obj)
        with ctx.core(obj.locs.get("world_from_object", obj.loc)):
            handle = scene.add_instance(mesh_id, (wfo @ instance_from_object).astype(np.float32),
                                        class_id=obj["class_id"], instance_id=obj.get("instance_id"),
                                        material_id=material_id)
        info.update({
            "instance": handle,
            "instance_id": obj["instance_id"] if obj.get("instance_id") is not None else handle + 1,
            "class_id": obj["class_id"],
            "mesh_id": mesh_id,
            "material": obj.get("material"),
            "world_from_object": wfo.tolist(),  # of the primitive / mesh frame, before sizing
        })
        meta["objects"].append(info)

    for light in spec["lights"]:
        with ctx.core(light.loc):
            lid = scene.add_light(light["type"], given_params(light))
        meta["lights"].append({"name": light.get("name"), "type": light["type"], "id": lid})

    if spec.get("medium") is not None:
        with ctx.core(spec["medium"].loc):
            scene.set_medium(spec["medium"]["type"], given_params(spec["medium"]))
        meta["medium"] = {"type": spec["medium"]["type"], **given_params(spec["medium"])}

    scene.set_camera(camera_from_spec(spec["camera"], ctx))
    settings = {k: spec["render"][k] for k in RENDER.fields}
    return scene, settings, meta


def validate_render_settings(settings: Mapping[str, Any], source: str = "<render settings>") -> Dict[str, Any]:
    """Checks render settings (e.g. after command-line overrides) against the ``render``
    section of the schema; returns a complete dict of ``Scene.render`` keyword arguments."""
    rec = RENDER.validate(dict(settings), Loc("render"), ValidationContext(source))
    return {k: rec[k] for k in RENDER.fields}


def validate_scene(data: Any, source_name: str = "<scene>", base_dir: Optional[str] = None,
                   context: Optional[ValidationContext] = None,
                   allow_extensions: bool = False) -> Tuple[Validated, ValidationContext]:
    """Validates a scene description (a dict, e.g. from :func:`read_yaml`) against
    :data:`SCENE_SCHEMA`; returns ``(spec, context)``."""
    ctx = context or ValidationContext(source_name, base_dir)
    if data is None:
        ctx.error(Loc(), "the scene file is empty; expected a mapping with at least 'camera' and 'objects'")
    if isinstance(data, Mapping) and data.get("extensions"):
        load_file_extensions(data, SCENE_SCHEMA, ctx, allow_extensions)
    spec = SCENE_SCHEMA.validate(data, Loc.root(data), ctx)
    return spec, ctx


def load_file_extensions(data: Mapping[str, Any], schema: Record, ctx: ValidationContext,
                         allow_extensions: bool) -> List[Dict[str, Any]]:
    """Compiles and loads the ``extensions`` of a scene file or scenario (before the rest is
    validated: their textures and shapes are plugins the rest may use) -- only when the file
    says ``allow_extensions: true`` and the caller allows it too (``--allow-extensions``, or the
    Python argument): extensions run with your rights. Errors point at the file's entries."""
    from .extensions import NOT_ALLOWED, load_extension

    root = Loc.root(data)
    allowed = False
    if "allow_extensions" in data:
        allowed = schema.fields["allow_extensions"].validate(data["allow_extensions"],
                                                             root.value("allow_extensions", data), ctx)
    paths = schema.fields["extensions"].validate(data["extensions"], root.value("extensions", data), ctx)
    names = ", ".join(os.path.basename(p) for p in paths)
    if not allowed:
        ctx.error(root.key("extensions", data), NOT_ALLOWED.format(what=names) + " (the file lacks 'allow_extensions: "
                                                                               "true')")
    if not allow_extensions:
        ctx.error(root.key("extensions", data), NOT_ALLOWED.format(what=names) + " (the command line lacks "
                                                                               "--allow-extensions)")
    loaded = []
    for i, path in enumerate(paths):
        with ctx.core(root.value("extensions", data).value(i, data["extensions"])):
            loaded.append(load_extension(path))
    return loaded


def build_scene(data: Mapping[str, Any], source_name: str = "<scene>", base_dir: Optional[str] = None,
                context: Optional[ValidationContext] = None,
                allow_extensions: bool = False) -> Tuple[Scene, Dict[str, Any], Dict[str, Any]]:
    """Validates a scene description (dict in the scene file format) and builds it.

    ``source_name`` names the description in error messages; relative file paths are
    resolved against ``base_dir`` (default: the current directory). Returns
    ``(scene, render_settings, meta)``: ``render_settings`` are keyword arguments of
    ``Scene.render``; ``meta`` lists the ids given to named textures and materials and,
    per object, its instance handle, labels, mesh id and world_from_object.
    """
    spec, ctx = validate_scene(data, source_name, base_dir, context, allow_extensions)
    return build_validated(spec, ctx)


def load_scene(path: str | os.PathLike,
               allow_extensions: bool = False) -> Tuple[Scene, Dict[str, Any], Dict[str, Any]]:
    """Loads a YAML scene file: ``(scene, render_settings, meta)``.

    ``scene`` has its camera set; ``scene.render(**render_settings)`` renders it.
    Raises :class:`SceneFileError` (``FILE:LINE:COLUMN: key.path: reason``) on any
    problem in the file or in the files it references. ``allow_extensions``: the caller's
    consent to compile and run the C files the scene file lists under ``extensions`` (the file
    must say ``allow_extensions: true`` too; docs/extensions.md).
    """
    path = os.fspath(path)
    data = read_yaml(path)
    scene, settings, meta = build_scene(data, source_name=path, base_dir=os.path.dirname(os.path.abspath(path)),
                                        allow_extensions=allow_extensions)
    with open(path, "rb") as f:
        meta["source_sha256"] = hashlib.sha256(f.read()).hexdigest()
    return scene, settings, meta
