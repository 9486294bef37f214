"""The peer-benchmark scenes, each described once as a JSON-able spec (meshes as vertex arrays,
synthgen material and light plugin parameters, an OpenCV camera) and built from that
description by synthgen here and by Blender in :mod:`synthgen.bench.cycles_scene`.

Used by ``synthgen bench``, bench/vs_cycles.py (re-exported by bench/vs_cycles_scenes.py) and
tests/python/test_vs_cycles_reference.py. The ``cbox`` scene needs the source tree: the Ignis
Cornell box of ``<repo>/../shared/assets/ignis-cbox`` and the loader tests/python/ignis_scene.py.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import sys
import time

import numpy as np

#: The source tree (this file is python/synthgen/bench/scenes.py).
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
HDR_DIR = "/usr/share/blender/datafiles/studiolights/world"
CBOX_DIR = os.path.abspath(os.path.join(REPO, "..", "shared", "assets", "ignis-cbox"))


def _sg():
    from .. import _core as sg  # imported lazily: --help and the Blender checks need no native module

    return sg


# ---------------------------------------------------------------------------------------------
# Scene descriptions (shared by both renderers)


def _rows(m) -> list:
    return [[float(x) for x in r] for r in np.asarray(m, dtype=np.float64).reshape(4, 4)]


def _mesh_entry(name, mesh: dict) -> dict:
    return {"name": name, "positions": np.asarray(mesh["positions"], np.float64).tolist(),
            "indices": np.asarray(mesh["indices"], np.int64).tolist(),
            "normals": None if mesh.get("normals") is None else np.asarray(mesh["normals"], np.float64).tolist()}


def _camera_entry(cam) -> dict:
    return {"fx": float(cam.fx), "fy": float(cam.fy), "cx": float(cam.cx), "cy": float(cam.cy),
            "world_from_camera": _rows(cam.world_from_camera)}


def available_plugins() -> dict:
    """Material and light plugin names the synthgen build knows (from its own error message)."""
    sg = _sg()
    out = {}
    for kind, add in (("material", lambda s: s.add_material("__none__", {})),
                      ("light", lambda s: s.add_light("__none__", {}))):
        try:
            add(sg.Scene())
            names = []
        except sg.SynthgenError as e:
            msg = str(e)
            tail = msg.split("known types:", 1)[1] if "known types:" in msg else ""
            names = [n.strip(" .") for n in tail.split("(")[0].split(",") if n.strip(" .")]
        out[kind] = set(names)
    return out


def _plugin_accepts(kind: str, type_: str, params: dict) -> str | None:
    """None if synthgen accepts the parameters, else the error message."""
    sg = _sg()
    s = sg.Scene()
    try:
        if kind == "material":
            s.add_material(type_, _synthgen_params(params))
        else:
            s.add_light(type_, _synthgen_params(params))
    except sg.SynthgenError as e:
        return str(e)
    return None


def spec_cbox(width: int, height: int) -> dict:
    if not os.path.isdir(CBOX_DIR):
        raise FileNotFoundError(f"scene cbox: shared assets not found: {CBOX_DIR}")
    tests = os.path.join(REPO, "tests", "python")
    if tests not in sys.path:
        sys.path.insert(0, tests)
    from ignis_scene import IGNIS_TO_OPENCV, _load_json_with_externals, _rgb, _transform

    sg = _sg()
    path = os.path.join(CBOX_DIR, "cbox-d6.json")
    j = _load_json_with_externals(path)
    bsdfs = {b["name"]: _rgb(b.get("reflectance", 0.5), b["name"]) for b in j["bsdfs"]}
    shapes = {s["name"]: s for s in j["shapes"]}
    lights = {lt["entity"]: _rgb(lt["radiance"], lt["name"]) for lt in j["lights"]}
    tmp = sg.Scene()
    meshes, mesh_index, materials, instances = [], {}, [], []
    for e in j["entities"]:
        shape = shapes[e["shape"]]
        if e["shape"] not in mesh_index:
            # The geometry synthgen's own OBJ import (assimp) produces, passed to both renderers.
            mid = tmp.load_mesh_file(os.path.join(CBOX_DIR, shape["filename"]))["mesh_id"]
            arrays = tmp.mesh_arrays(mid)
            mesh_index[e["shape"]] = len(meshes)
            meshes.append(_mesh_entry(e["shape"], {"positions": arrays["positions"], "indices": arrays["indices"]}))
        world = _transform(e.get("transform"), e["name"]) @ _transform(shape.get("transform"), shape["name"])
        if e["name"] in lights:
            materials.append({"type": "emissive", "params": {"radiance": lights[e["name"]], "albedo": bsdfs[e["bsdf"]]}})
        else:
            materials.append({"type": "diffuse", "params": {"albedo": bsdfs[e["bsdf"]]}})
        instances.append({"mesh": mesh_index[e["shape"]], "material": len(materials) - 1, "world_from_object": _rows(world)})
    wfc = _transform(j["camera"]["transform"], "camera") @ IGNIS_TO_OPENCV
    cam = sg.PinholeCamera.from_fov(float(j["camera"]["fov"]), width, height, wfc.astype(np.float32))
    return {"name": "cbox", "max_depth": int(j["technique"]["max_depth"]), "camera": _camera_entry(cam),
            "meshes": meshes, "materials": materials, "instances": instances, "lights": [],
            "notes": ["Ignis Cornell box (../shared/assets/ignis-cbox), luminaire as a one-sided area light"]}


def _ggx_roughness_to_blender(r: float) -> float:
    """Blender's roughness r gives GGX alpha = r^2; synthgen's `roughness` too
    (material/microfacet.h roughness_to_alpha), so the value passes through."""
    return float(r)


def spec_materials(width: int, height: int, hdr: str = "courtyard.exr") -> dict:
    sg = _sg()
    from ..scene import primitives as P

    plugins = available_plugins()
    notes = []
    meshes = [_mesh_entry("ground", P.plane(12.0, 12.0)), _mesh_entry("sphere", P.uv_sphere(0.4, 96, 48))]
    materials = [{"type": "diffuse", "params": {"albedo": [0.35, 0.35, 0.35]}}]
    instances = [{"mesh": 0, "material": 0, "world_from_object": _rows(np.eye(4))}]
    candidates = [
        ("car paint", "coated", {"albedo": [0.55, 0.04, 0.03], "ior": 1.5, "roughness": 0.05}),
        ("gold", "conductor", {"metal": "gold", "roughness": 0.25}),
        ("glass", "dielectric", {"ior": 1.5, "roughness": 0.0}),
        ("rubber", "diffuse", {"albedo": [0.03, 0.03, 0.03]}),
    ]
    xs = [-1.5, -0.5, 0.5, 1.5]
    used = []
    for (label, type_, params), x in zip(candidates, xs):
        if type_ not in plugins["material"]:
            notes.append(f"{label}: synthgen has no '{type_}' material yet, sphere left out")
            continue
        err = _plugin_accepts("material", type_, params)
        if err:
            notes.append(f"{label}: synthgen rejected the '{type_}' parameters ({err}), sphere left out")
            continue
        p = dict(params)
        if "roughness" in p:
            p["_blender_roughness"] = _ggx_roughness_to_blender(p["roughness"])
        materials.append({"type": type_, "params": p})
        instances.append({"mesh": 1, "material": len(materials) - 1,
                          "world_from_object": _rows(P.translate([x, 0.4, 0.0]))})
        used.append(label)
    lights = []
    hdr_path = os.path.join(HDR_DIR, hdr)
    envmap = {"filename": hdr_path, "strength": 1.0}
    if "envmap" in plugins["light"] and _plugin_accepts("light", "envmap", envmap) is None:
        lights.append({"type": "envmap", "params": envmap_params(envmap)})
    else:
        notes.append("synthgen has no usable 'envmap' light yet: constant sky + sun instead of the HDR map")
        lights.append({"type": "environment", "params": {"radiance": [0.45, 0.5, 0.6]}})
        lights.append({"type": "sun", "params": {"direction": [-0.5, 0.8, -0.4], "irradiance": [3.0, 2.9, 2.7]}})
    wfc = sg.PinholeCamera.look_at([0.0, 1.7, -5.2], [0.0, 0.3, 0.0], [0.0, 1.0, 0.0])
    cam = sg.PinholeCamera.from_fov(44.0 * max(1.0, height / width), width, height, wfc)
    return {"name": "materials", "max_depth": 8, "camera": _camera_entry(cam), "meshes": meshes,
            "materials": materials, "instances": instances, "lights": lights, "notes": notes,
            "spheres": used, "skip": not any(t in plugins["material"] for t in ("coated", "conductor", "dielectric"))}


def envmap_params(p: dict) -> dict:
    """synthgen envmap parameters plus the hints cycles_scene.py needs: the lookup matrix and
    nearest-pixel interpolation (synthgen's envmap reads the nearest pixel)."""
    q = dict(p)
    q["_blender_mapping"] = envmap_blender_mapping(float(p.get("rotation", 0.0)), p.get("up", (0.0, 1.0, 0.0))).tolist()
    q["_blender_interpolation"] = "Closest"
    return q


def envmap_blender_mapping(rotation_deg: float = 0.0, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """3x3 M with Blender lookup direction = M @ world direction, for synthgen's "envmap".

    synthgen (cpp/light/equirect.h, Mitsuba's convention, map space y up): top row +y,
    u = atan2(x, -z) / 2 pi (image centre +z, u = 1/4 +x); world_from_map = align(+y -> up) @
    R_y(rotation) (cpp/light/envmap.cpp). Cycles' equirect lookup (Z up): top row +Z,
    u = 1/2 - atan2(Y, X) / 2 pi. Both agree when (X, Y, Z) = (z, x, y) of the map-space
    direction, so M = P @ map_from_world with P the cyclic permutation below."""
    a = math.radians(rotation_deg)
    ca, sa = math.cos(a), math.sin(a)
    ry = np.array([[ca, 0, sa], [0, 1, 0], [-sa, 0, ca]])
    n = np.asarray(up, np.float64) / np.linalg.norm(up)
    if n[1] < -1.0 + 1e-12:
        align = np.diag([1.0, -1.0, -1.0])
    else:
        v = np.array([n[2], 0.0, -n[0]])
        k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
        align = np.eye(3) + k + k @ k / (1.0 + n[1])
    world_from_map = align @ ry
    perm = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], np.float64)
    return perm @ world_from_map.T


def spec_sunlit(width: int, height: int) -> dict:
    sg = _sg()
    from ..scene import primitives as P

    meshes = [_mesh_entry("ground", P.plane(30.0, 30.0)), _mesh_entry("box", P.box()),
              _mesh_entry("sphere", P.uv_sphere(1.0, 96, 48))]
    materials = [{"type": "diffuse", "params": {"albedo": [0.45, 0.42, 0.38]}},
                 {"type": "diffuse", "params": {"albedo": [0.2, 0.35, 0.7]}},
                 {"type": "diffuse", "params": {"albedo": [0.75, 0.2, 0.15]}},
                 {"type": "diffuse", "params": {"albedo": [0.25, 0.6, 0.25]}}]
    instances = [
        {"mesh": 0, "material": 0, "world_from_object": _rows(np.eye(4))},
        {"mesh": 1, "material": 1, "world_from_object": _rows(P.translate([-1.3, 0.5, 0.6]) @ P.rotate([0, 1, 0], 30.0))},
        {"mesh": 2, "material": 2, "world_from_object": _rows(P.translate([0.5, 0.6, -0.4]) @ P.scale(0.6))},
        {"mesh": 1, "material": 3, "world_from_object": _rows(P.translate([1.7, 0.9, 1.3]) @ P.rotate([0, 1, 0], -20.0)
                                                               @ P.scale([0.5, 1.8, 0.5]))},
    ]
    lights = [{"type": "sun", "params": {"direction": [-0.5, 0.75, -0.45], "irradiance": [3.2, 3.0, 2.7],
                                          "angular_diameter": 0.53}},
              {"type": "environment", "params": {"radiance": [0.12, 0.16, 0.24]}}]
    wfc = sg.PinholeCamera.look_at([0.3, 2.4, -5.2], [0.2, 0.5, 0.3], [0.0, 1.0, 0.0])
    cam = sg.PinholeCamera.from_fov(42.0, width, height, wfc)
    return {"name": "sunlit", "max_depth": 6, "camera": _camera_entry(cam), "meshes": meshes,
            "materials": materials, "instances": instances, "lights": lights,
            "notes": ["sun (0.53 deg disc) + constant sky, Lambertian objects"]}


def build_spec(name: str, width: int, height: int) -> dict:
    spec = {"cbox": spec_cbox, "materials": spec_materials, "sunlit": spec_sunlit}[name](width, height)
    spec.update(width=int(width), height=int(height))
    return spec


def spec_digest(spec: dict) -> str:
    """Hash of what is rendered (geometry, materials, lights, camera, size, max_depth)."""
    keys = ("width", "height", "max_depth", "camera", "meshes", "materials", "instances", "lights")
    blob = json.dumps({k: spec[k] for k in keys}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha1(blob.encode()).hexdigest()[:16]


# ---------------------------------------------------------------------------------------------
# synthgen side


def _synthgen_params(p: dict) -> dict:
    """Plugin parameters without the Blender-only hints (keys starting with '_')."""
    return {k: v for k, v in p.items() if not k.startswith("_")}


def _synthgen_arrays(spec: dict) -> list:
    """The spec's meshes as numpy arrays (the JSON-to-array conversion is harness work, on the
    Blender side done by cycles_scene.py before the timed render, so it is not timed here)."""
    out = []
    for m in spec["meshes"]:
        normals = None if m.get("normals") is None else np.asarray(m["normals"], np.float32)
        out.append((np.asarray(m["positions"], np.float32), np.asarray(m["indices"], np.uint32), normals,
                    m.get("name", "")))
    return out


def synthgen_scene(spec: dict, arrays: list | None = None):
    sg = _sg()
    scene = sg.Scene()
    mesh_ids = [scene.add_mesh(p, i, normals=n, name=name) for p, i, n, name in (arrays or _synthgen_arrays(spec))]
    mat_ids = [scene.add_material(m["type"], _synthgen_params(m.get("params", {}))) for m in spec["materials"]]
    assert mat_ids == list(range(len(mat_ids))), "material ids must equal their index (mix references)"
    for i, inst in enumerate(spec["instances"]):
        scene.add_instance(mesh_ids[inst["mesh"]], np.asarray(inst["world_from_object"], np.float32),
                           class_id=1, material_id=mat_ids[inst["material"]] if inst.get("material", -1) >= 0 else -1)
    for light in spec["lights"]:
        scene.add_light(light["type"], _synthgen_params(light.get("params", {})))
    c = spec["camera"]
    scene.set_camera(sg.PinholeCamera(c["fx"], c["fy"], c["cx"], c["cy"], spec["width"], spec["height"],
                                      np.asarray(c["world_from_camera"], np.float32)))
    return scene


def synthgen_render(spec: dict, spp: int, seed: int, threads: int, **settings):
    """Renders in this process; returns (rgb float32 HxWx3, timings dict). ``settings`` are
    further ``Scene.render`` keywords (noise_threshold, max_spp, ...).

    ``render_s`` is the scene API calls + commit + the render's own wall time;
    ``render_call_total_s`` has the whole ``render`` call instead (with what it does after
    the path tracing, e.g. a denoiser)."""
    arrays = _synthgen_arrays(spec)
    t0 = time.perf_counter()
    scene = synthgen_scene(spec, arrays)
    t1 = time.perf_counter()
    scene.commit()
    t2 = time.perf_counter()
    res = scene.render(spp=spp, max_depth=int(spec["max_depth"]), seed=seed, threads=threads, **settings)
    t3 = time.perf_counter()
    st = res.stats
    count = getattr(res, "sample_count", None)
    return np.array(res.rgb, dtype=np.float32), {
        "build_s": t1 - t0, "commit_s": t2 - t1, "render_call_s": t3 - t2, "wall_time_s": st["wall_time_s"],
        # Like Cycles' render time (scene sync, BVH build, light set-up, render): the scene API
        # calls (meshes, materials, lights incl. environment-map loading) + commit + render.
        "render_s": (t1 - t0) + (t2 - t1) + st["wall_time_s"], "render_call_total_s": t3 - t0,
        "nan_samples": st["nan_samples"], "rays_per_s": st["rays_per_s"],
        "mean_spp": float(np.asarray(count).mean()) if count is not None else float(spp)}
