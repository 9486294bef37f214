#!/usr/bin/env python3
"""Peer benchmark: synthgen vs Blender Cycles (CPU) on the same scenes, same settings.

    .venv/bin/python bench/vs_cycles.py                      # all scenes, 256x256, 64 spp, 2 threads
    .venv/bin/python bench/vs_cycles.py --scenes cbox,sunlit --spp 128 --runs 3
    .venv/bin/python bench/vs_cycles.py --check              # camera / light / bounce conversions
    .venv/bin/python bench/vs_cycles.py --make-references    # tests/python/references/cycles/*.exr

Installs Debian's `blender` and `blender-data` (HDR maps) with apt-get if missing and runs
Blender 3.4 as `blender -b --factory-startup --python-exit-code 1 -P bench/cycles_scene.py -- spec.json`.
Each scene is written once as a JSON description (meshes as vertex arrays, synthgen material
and light plugin parameters, OpenCV camera); this script builds the synthgen scene from it and
bench/cycles_scene.py builds the Blender scene from it, so both get the same geometry, camera,
lights and materials. Settings are equal on both sides: resolution, spp, max path length
(Cycles max_bounces = synthgen max_depth - 2, see --check), box pixel filter of width 1,
threads, no adaptive sampling, denoising, clamping or glossy filtering, linear float EXR.

Scenes: `cbox` (Ignis Cornell box from ../shared/assets/ignis-cbox, max_depth 6),
`materials` (coated / conductor / dielectric / rough dark spheres on a ground plane under
an HDR map from blender-data; only the synthgen materials available at run time),
`sunlit` (diffuse objects on a plane under a sun and a constant sky).

Per scene it prints render time (Cycles: bpy.ops.render.render, which includes Cycles' scene
sync and BVH build; synthgen: commit() + render(), the latter = stats['wall_time_s']) and
whole-process time (subprocess start to exit, incl. scene load and writing the EXR) of both,
medians over --runs interleaved runs; the PSNR of both images against a converged synthgen
image (--ref-spp, cached in --ref-dir), and of the Cycles image against a converged Cycles
image; the per-channel mean difference in percent between the converged Cycles and synthgen
images; and an equal-noise speedup (synthgen's time scaled by the sample factor it needs to
reach Cycles' noise). Last lines:

    speedup_vs_cycles=<geometric mean over scenes of Cycles render time / synthgen render time>
    max_mean_diff_pct=<largest |mean difference| over scenes whose light transport models agree>

Figures, conversions and the known model differences: docs/benchmarks.md.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
CYCLES_SCRIPT = os.path.join(REPO, "bench", "cycles_scene.py")
HDR_DIR = "/usr/share/blender/datafiles/studiolights/world"
CBOX_DIR = os.path.abspath(os.path.join(REPO, "..", "shared", "assets", "ignis-cbox"))
TEST_REF_DIR = os.path.join(REPO, "tests", "python", "references", "cycles")
ALL_SCENES = ("cbox", "materials", "sunlit")
# Scenes whose light transport models are the same in both renderers (Lambertian surfaces,
# area / sun / constant-environment lights); the materials scene compares different BSDFs.
MODELS_AGREE = ("cbox", "sunlit")


def _sg():
    import synthgen as sg  # imported lazily: --help and the Blender checks need no native module

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
    sys.path.insert(0, os.path.join(REPO, "tests", "python"))
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
    from synthgen import primitives as P

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
    from synthgen import primitives as P

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


def synthgen_render(spec: dict, spp: int, seed: int, threads: int):
    """Renders in this process; returns (rgb float32 HxWx3, timings dict)."""
    arrays = _synthgen_arrays(spec)
    t0 = time.perf_counter()
    scene = synthgen_scene(spec, arrays)
    t1 = time.perf_counter()
    scene.commit()
    t2 = time.perf_counter()
    res = scene.render(spp=spp, max_depth=int(spec["max_depth"]), seed=seed, threads=threads)
    t3 = time.perf_counter()
    st = res.stats
    return np.array(res.rgb, dtype=np.float32), {
        "build_s": t1 - t0, "commit_s": t2 - t1, "render_call_s": t3 - t2, "wall_time_s": st["wall_time_s"],
        # Like Cycles' render time (scene sync, BVH build, light set-up, render): the scene API
        # calls (meshes, materials, lights incl. environment-map loading) + commit + render.
        "render_s": (t1 - t0) + (t2 - t1) + st["wall_time_s"], "nan_samples": st["nan_samples"],
        "rays_per_s": st["rays_per_s"]}


def _render_synthgen_main(spec_path: str) -> int:
    """Entry point of the synthgen subprocess (whole-process timing): spec -> EXR."""
    with open(spec_path) as f:
        spec = json.load(f)
    # Process start-up (module import, the OpenImageIO plugin's libraries) is not render time,
    # as Blender's start-up is not part of Cycles' render time; the whole-process time has it.
    _sg().load_image_plugin()
    rgb, t = synthgen_render(spec, int(spec["spp"]), int(spec.get("seed", 0)), int(spec.get("threads", 0)))
    from synthgen.outputs.files import write_exr

    write_exr(spec["output"], rgb)
    print("SYNTHGEN_RESULT " + json.dumps(t), flush=True)
    return 0


def run_synthgen_process(spec: dict, workdir: str, tag: str) -> tuple:
    path = os.path.join(workdir, f"{tag}.json")
    with open(path, "w") as f:
        json.dump(spec, f)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, os.path.abspath(__file__), "--render-synthgen", path],
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"synthgen subprocess failed:\n{p.stdout}\n{p.stderr}")
    line = [x for x in p.stdout.splitlines() if x.startswith("SYNTHGEN_RESULT ")][-1]
    t = json.loads(line.split(" ", 1)[1])
    t["process_s"] = wall
    return read_exr(spec["output"]), t


# ---------------------------------------------------------------------------------------------
# Cycles side


def ensure_blender(need_hdr: bool = True) -> str:
    blender = shutil.which("blender")
    if blender is None or (need_hdr and not os.path.isdir(HDR_DIR)):
        sudo = [] if os.geteuid() == 0 else ["sudo"]
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        print("installing Debian packages blender blender-data ...", flush=True)
        subprocess.run(sudo + ["apt-get", "update", "-qq"], check=True, env=env)
        subprocess.run(sudo + ["apt-get", "install", "-y", "-qq", "blender", "blender-data"], check=True, env=env,
                       stdout=subprocess.DEVNULL)
        blender = shutil.which("blender")
        if blender is None:
            raise SystemExit("blender is not installed and could not be installed")
    return blender


def run_cycles(spec: dict, workdir: str, tag: str, blender: str = "blender") -> tuple:
    path = os.path.join(workdir, f"{tag}.json")
    with open(path, "w") as f:
        json.dump(spec, f)
    cmd = [blender, "-b", "--factory-startup", "--python-exit-code", "1", "-P", CYCLES_SCRIPT, "--", path]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    lines = [x for x in p.stdout.splitlines() if x.startswith("CYCLES_RESULT ")]
    if p.returncode != 0 or not lines:
        raise RuntimeError(f"Blender failed ({' '.join(cmd)}):\n{p.stdout[-4000:]}\n{p.stderr[-4000:]}")
    t = json.loads(lines[-1].split(" ", 1)[1])
    t["process_s"] = wall
    img, meta = read_exr(spec["output"], with_meta=True)
    # Cycles' own figures (EXR header): path tracing alone, and scene synchronisation.
    for key, name in (("render_time", "pathtrace_s"), ("synchronization_time", "sync_s")):
        v = meta.get(f"cycles.ViewLayer.{key}")
        if v:
            t[name] = _parse_blender_time(v)
    return img, t


def _parse_blender_time(s: str) -> float:
    parts = [float(x) for x in s.split(":")]
    v = 0.0
    for x in parts:
        v = v * 60.0 + x
    return v


# ---------------------------------------------------------------------------------------------
# Images and figures


def read_exr(path: str, with_meta: bool = False):
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise OSError(f"{path}: {buf.geterror()}")
    px = np.ascontiguousarray(buf.get_pixels(oiio.FLOAT)[:, :, :3], dtype=np.float32)
    if not with_meta:
        return px
    meta = {a.name: a.value for a in buf.spec().extra_attribs}
    return px, meta


def write_exr_half(path: str, rgb: np.ndarray, attributes: dict | None = None) -> None:
    """Small reference EXR: RGB float16, lossless ZIP."""
    import OpenImageIO as oiio

    h, w, _ = rgb.shape
    spec = oiio.ImageSpec(w, h, 3, oiio.HALF)
    spec.channelnames = ("R", "G", "B")
    spec.attribute("compression", "zip")
    for k, v in (attributes or {}).items():
        spec.attribute(k, v)
    tmp = path + ".tmp.exr"
    out = oiio.ImageOutput.create(tmp)
    if out is None or not out.open(tmp, spec):
        raise OSError(f"{path}: cannot write: {oiio.geterror()}")
    ok = out.write_image(np.ascontiguousarray(rgb.astype(np.float16)))
    out.close()
    if not ok:
        raise OSError(f"{path}: write failed")
    os.replace(tmp, path)


def psnr(img: np.ndarray, ref: np.ndarray, peak_of: np.ndarray | None = None) -> float:
    """PSNR in dB of linear radiance; the peak is the 99th percentile of the per-pixel max channel
    of `peak_of` (default: the reference), a robust white level (emitters seen directly would
    otherwise set it)."""
    peak = float(np.percentile((ref if peak_of is None else peak_of).max(axis=-1), 99.0))
    mse = float(np.mean((img.astype(np.float64) - ref.astype(np.float64)) ** 2))
    return float("inf") if mse == 0 else 10.0 * math.log10(peak * peak / mse)


def mean_diff_pct(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per channel, 100 (mean(a) / mean(b) - 1)."""
    return 100.0 * (a.astype(np.float64).mean(axis=(0, 1)) / b.astype(np.float64).mean(axis=(0, 1)) - 1.0)


def _fmt(v) -> str:
    return ",".join(f"{x:.4g}" for x in v)


# ---------------------------------------------------------------------------------------------
# Converged references (cached)


def reference_images(spec: dict, args, blender: str, workdir: str) -> tuple:
    """(synthgen reference, Cycles reference) at args.ref_spp, rendered once and cached."""
    sg = _sg()
    os.makedirs(args.ref_dir, exist_ok=True)
    digest = spec_digest(spec)
    base = f"{spec['name']}_{spec['width']}x{spec['height']}_d{spec['max_depth']}_{args.ref_spp}spp_{digest}"
    sg_path = os.path.join(args.ref_dir, f"synthgen-{sg.__version__}_{base}.exr")
    cy_path = os.path.join(args.ref_dir, f"cycles_{base}.exr")
    if os.path.exists(sg_path):
        sg_ref = read_exr(sg_path)
        print(f"  reference synthgen {args.ref_spp} spp: cached {os.path.relpath(sg_path, REPO)}")
    else:
        t0 = time.perf_counter()
        sg_ref, _ = synthgen_render(spec, args.ref_spp, seed=1_000_003, threads=args.threads)
        from synthgen.outputs.files import write_exr

        write_exr(sg_path, sg_ref)
        print(f"  reference synthgen {args.ref_spp} spp: rendered in {time.perf_counter() - t0:.1f} s "
              f"-> {os.path.relpath(sg_path, REPO)}", flush=True)
    if os.path.exists(cy_path):
        cy_ref = read_exr(cy_path)
        print(f"  reference Cycles {args.ref_spp} spp: cached {os.path.relpath(cy_path, REPO)}")
    else:
        s = dict(spec, spp=args.ref_spp, seed=1_000_003, threads=args.threads, output=cy_path)
        cy_ref, t = run_cycles(s, workdir, f"{spec['name']}_cycles_ref", blender)
        print(f"  reference Cycles {args.ref_spp} spp: rendered in {t['render_s']:.1f} s "
              f"-> {os.path.relpath(cy_path, REPO)}", flush=True)
    return sg_ref, cy_ref


# ---------------------------------------------------------------------------------------------
# Modes


def run_benchmark(args, blender: str) -> int:
    print(f"settings: {args.width}x{args.height}, {args.spp} spp, {args.threads} threads, {args.runs} run(s) each, "
          f"references {args.ref_spp} spp (cache {os.path.relpath(args.ref_dir, REPO)})")
    speedups, equal_noise, agree_diffs, agree_names = [], [], [], []
    with tempfile.TemporaryDirectory(prefix="vs_cycles_") as work:
        for name in args.scenes:
            if name == "cbox" and not os.path.isdir(CBOX_DIR):
                print(f"scene cbox: skipped (shared assets not found: {CBOX_DIR})")
                continue
            spec = build_spec(name, args.width, args.height)
            for note in spec.get("notes", []):
                print(f"  note [{name}]: {note}")
            if spec.get("skip"):
                print(f"scene {name}: skipped (none of the synthgen materials coated/conductor/dielectric exist yet)")
                continue
            print(f"scene {name}: {len(spec['meshes'])} meshes, {len(spec['instances'])} instances, "
                  f"max_depth {spec['max_depth']} (Cycles max_bounces {max(0, spec['max_depth'] - 2)}), "
                  f"spec {spec_digest(spec)}", flush=True)
            cy_runs, sg_runs = [], []
            for r in range(args.runs):
                s = dict(spec, spp=args.spp, seed=r + 1, threads=args.threads)
                cy_img, ct = run_cycles(dict(s, output=os.path.join(work, f"{name}_cycles.exr")), work, f"{name}_c", blender)
                sg_img, st = run_synthgen_process(dict(s, output=os.path.join(work, f"{name}_sg.exr")), work, f"{name}_s")
                cy_runs.append(ct)
                sg_runs.append(st)
            med = lambda runs, k: statistics.median(t[k] for t in runs)  # noqa: E731
            cy_render, sg_render = med(cy_runs, "render_s"), med(sg_runs, "render_s")
            sg_ref, cy_ref = reference_images(spec, args, blender, work)
            diff = mean_diff_pct(cy_ref, sg_ref)
            speedups.append(cy_render / sg_render)
            # Noise of each renderer against its own converged image (no model difference), same peak.
            noise_cy, noise_sg = psnr(cy_img, cy_ref, sg_ref), psnr(sg_img, sg_ref)
            # synthgen's MSE falls as 1/spp (independent samples): the time it needs to match Cycles'
            # noise is its time x 10^(dPSNR / 10).
            eq = cy_render / (sg_render * 10.0 ** ((noise_cy - noise_sg) / 10.0))
            equal_noise.append(eq)
            print(f"{name}_cycles_render_s={cy_render:.3f}")
            if all("pathtrace_s" in t for t in cy_runs):
                print(f"{name}_cycles_pathtrace_s={med(cy_runs, 'pathtrace_s'):.2f}  (Cycles' own figure, 10 ms resolution)")
            print(f"{name}_synthgen_render_s={sg_render:.3f}  (scene build {med(sg_runs, 'build_s'):.3f} + "
                  f"commit {med(sg_runs, 'commit_s'):.3f} + render {med(sg_runs, 'wall_time_s'):.3f})")
            print(f"{name}_cycles_process_s={med(cy_runs, 'process_s'):.3f}")
            print(f"{name}_synthgen_process_s={med(sg_runs, 'process_s'):.3f}")
            print(f"{name}_psnr_cycles_db={psnr(cy_img, sg_ref):.2f}  (vs synthgen {args.ref_spp} spp; "
                  f"vs Cycles {args.ref_spp} spp: {noise_cy:.2f})")
            print(f"{name}_psnr_synthgen_db={psnr(sg_img, sg_ref):.2f}  (vs synthgen {args.ref_spp} spp)")
            print(f"{name}_mean_rgb_synthgen_ref={_fmt(sg_ref.mean(axis=(0, 1)))}")
            print(f"{name}_mean_rgb_cycles_ref={_fmt(cy_ref.mean(axis=(0, 1)))}")
            print(f"{name}_mean_diff_pct={_fmt(diff)}  (Cycles vs synthgen, {args.ref_spp} spp each)")
            print(f"{name}_speedup_vs_cycles={cy_render / sg_render:.3f}")
            print(f"{name}_equal_noise_speedup={eq:.3f}  (Cycles time / synthgen time to reach Cycles' "
                  f"{args.spp}-spp noise, each against its own converged image)", flush=True)
            if name in MODELS_AGREE:
                agree_diffs.append(float(np.abs(diff).max()))
                agree_names.append(name)
    if not speedups:
        print("no scene rendered")
        return 1
    print(f"models_agree_scenes={','.join(agree_names) if agree_names else '(none)'}")
    print(f"equal_noise_speedup_vs_cycles={math.exp(sum(math.log(s) for s in equal_noise) / len(equal_noise)):.3f}")
    print(f"speedup_vs_cycles={math.exp(sum(math.log(s) for s in speedups) / len(speedups)):.3f}")
    print(f"max_mean_diff_pct={max(agree_diffs) if agree_diffs else float('nan'):.3f}")
    return 0


def run_make_references(args, blender: str) -> int:
    """Cycles renders stored as test references (RGB float16 EXR + JSON sidecar)."""
    os.makedirs(args.references_out, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="vs_cycles_") as work:
        for name in args.scenes:
            if name == "cbox" and not os.path.isdir(CBOX_DIR):
                print(f"scene cbox: skipped (shared assets not found: {CBOX_DIR})")
                continue
            spec = build_spec(name, args.width, args.height)
            if spec.get("skip"):
                print(f"scene {name}: skipped (none of the synthgen materials coated/conductor/dielectric exist yet)")
                continue
            s = dict(spec, spp=args.ref_spp, seed=7, threads=args.threads, output=os.path.join(work, f"{name}.exr"))
            img, t = run_cycles(s, work, name, blender)
            exr = os.path.join(args.references_out, f"{name}.exr")
            write_exr_half(exr, img)
            side = {
                "scene": name, "spec_sha1": spec_digest(spec), "width": spec["width"], "height": spec["height"],
                "spp": args.ref_spp, "max_depth": spec["max_depth"], "cycles_max_bounces": max(0, spec["max_depth"] - 2),
                "seed": 7, "threads": args.threads, "renderer": f"Blender {t['blender']} Cycles CPU",
                "cycles_settings": {"adaptive_sampling": False, "denoising": False, "clamp": 0, "filter_glossy": 0,
                                    "light_sampling_threshold": 0, "pixel_filter": "BOX 1.0 px",
                                    "shadow_terminator_offsets": 0, "sampling_pattern": t.get("sampling_pattern"),
                                    "view_transform": "Standard (linear EXR)"},
                "render_s": round(t["render_s"], 2), "mean_rgb": [float(x) for x in img.astype(np.float64).mean(axis=(0, 1))],
                "models_agree": name in MODELS_AGREE, "materials": [m["type"] for m in spec["materials"]],
                "lights": [lt["type"] for lt in spec["lights"]], "notes": spec.get("notes", []),
                "made_by": f"bench/vs_cycles.py --make-references --scenes {name} --width {spec['width']} "
                           f"--height {spec['height']} --ref-spp {args.ref_spp} --threads {args.threads}",
                "format": "RGB float16 OpenEXR (ZIP), linear radiance W/(m^2 sr), rows top to bottom",
            }
            with open(os.path.join(args.references_out, f"{name}.json"), "w") as f:
                json.dump(side, f, indent=1)
                f.write("\n")
            print(f"{name}: {args.ref_spp} spp in {t['render_s']:.1f} s, mean {_fmt(side['mean_rgb'])} -> "
                  f"{os.path.relpath(exr, REPO)} ({os.path.getsize(exr) // 1024} KiB)", flush=True)
    return 0


# ---------------------------------------------------------------------------------------------
# --check: conversions verified numerically


def _quad_facing(centre, normal, size, a=None) -> dict:
    """Square of side `size` centred at `centre`, front face (counter-clockwise) towards `normal`,
    one edge along `a` (any perpendicular direction if None)."""
    c = np.asarray(centre, np.float64)
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    if a is None:
        a = np.cross(n, [0.0, 1.0, 0.0] if abs(n[1]) < 0.9 else [1.0, 0.0, 0.0])
    a = np.asarray(a, np.float64) - n * np.dot(a, n)
    a /= np.linalg.norm(a)
    b = np.cross(n, a)  # (a, b, n) right-handed: counter-clockwise seen from +n
    h = 0.5 * size
    p = [c - h * a - h * b, c + h * a - h * b, c + h * a + h * b, c - h * a + h * b]
    return {"positions": np.array(p), "indices": np.array([[0, 1, 2], [0, 2, 3]]), "normals": None}


def _check_spec(name, width, height, camera, meshes, materials, instances, lights, max_depth):
    return {"name": name, "width": width, "height": height, "max_depth": max_depth, "camera": _camera_entry(camera),
            "meshes": meshes, "materials": materials, "instances": instances, "lights": lights}


def run_check(args, blender: str) -> int:
    sg = _sg()
    from synthgen import primitives as P

    spp, ok_all = 64, True
    eye4 = _rows(np.eye(4))

    def both(spec, tag, n=None, **cy_extra):
        n = n or spp
        s = dict(spec, spp=n, seed=3, threads=args.threads)
        sg_img, _ = synthgen_render(s, n, seed=3, threads=args.threads)
        cy_img, _ = run_cycles(dict(s, output=os.path.join(work, f"{tag}.exr"), **cy_extra), work, tag, blender)
        return sg_img.astype(np.float64), cy_img.astype(np.float64)

    def verdict(ok):
        nonlocal ok_all
        ok_all &= bool(ok)
        return "ok" if ok else "FAIL"

    with tempfile.TemporaryDirectory(prefix="vs_cycles_check_") as work:
        # 1. Camera: three small one-sided emitters (R, G, B) seen directly on a landscape (96x64)
        #    and a portrait (64x96) image with an off-centre principal point and a tilted pose; the
        #    radiance centroid of each channel must be the exact centroid of the emitter's
        #    box-filtered projection (OpenCV convention, pixel centres at +0.5) up to the sampling
        #    noise of the edge pixels (~0.01 px at 1024 spp).
        def overlap(lo, hi, n):
            k = np.arange(n, dtype=np.float64)
            return np.clip(np.minimum(hi, k + 1) - np.maximum(lo, k), 0.0, None)

        for W, H, cx, cy in ((96, 64, 41.3, 36.7), (64, 96, 36.7, 41.3)):
            eye = np.array([0.4, 1.1, -3.0])
            wfc = sg.PinholeCamera.look_at(eye.tolist(), [0.1, 0.3, 0.5], [0.15, 1.0, 0.0])
            cam = sg.PinholeCamera(70.0, 70.0, cx, cy, W, H, wfc)
            pts = [np.array(wfc[:3, :3] @ v + wfc[:3, 3], np.float64)
                   for v in ([-0.55, -0.3, 3.0], [0.45, 0.2, 2.6], [0.05, 0.32, 3.4])]
            # Parallel to the image plane (facing the camera's -z) with edges along the camera's x
            # and y, so each projects to an axis-aligned square [u0, u1] x [v0, v1] whose exact pixel
            # coverage gives the expected centroid of the box-filtered image.
            side = 0.12
            meshes = [_mesh_entry(f"q{i}", _quad_facing(p, -wfc[:3, 2], side, a=wfc[:3, 0])) for i, p in enumerate(pts)]
            mats = [{"type": "emissive", "params": {"radiance": c}} for c in ([1, 0, 0], [0, 1, 0], [0, 0, 1])]
            inst = [{"mesh": i, "material": i, "world_from_object": eye4} for i in range(3)]
            sgi, cyi = both(_check_spec("check_camera", W, H, cam, meshes, mats, inst, [], 1), "camera", n=1024)
            yy, xx = np.mgrid[0:H, 0:W] + 0.5
            areas = []
            for ch, p in enumerate(pts):
                u, v = cam.project(p.tolist())
                z = float(np.dot(p - wfc[:3, 3], wfc[:3, 2]))
                hu, hv = 0.5 * side * cam.fx / z, 0.5 * side * cam.fy / z
                cov = np.outer(overlap(v - hv, v + hv, H), overlap(u - hu, u + hu, W))
                areas.append(cov.sum())
                u, v = float((cov * xx).sum() / cov.sum()), float((cov * yy).sum() / cov.sum())
                cs = [(float((img[..., ch] * xx).sum() / img[..., ch].sum()),
                       float((img[..., ch] * yy).sum() / img[..., ch].sum())) for img in (sgi, cyi)]
                err = max(math.hypot(c[0] - u, c[1] - v) for c in cs)
                print(f"check camera {W}x{H} emitter {'RGB'[ch]}: exact ({u:.3f}, {v:.3f})  synthgen centroid "
                      f"({cs[0][0]:.3f}, {cs[0][1]:.3f})  Cycles centroid ({cs[1][0]:.3f}, {cs[1][1]:.3f})  "
                      f"max err {err:.3f} px {verdict(err < 0.03)}")
            # Emitted radiance seen directly (radiance 1 per channel): image sum = projected area in pixels.
            rel = [img.sum(axis=(0, 1)) / np.array(areas) - 1.0 for img in (sgi, cyi)]
            print(f"check camera {W}x{H} emitter radiance x area: synthgen/exact - 1 = {_fmt(100 * rel[0])} %  "
                  f"Cycles/exact - 1 = {_fmt(100 * rel[1])} % {verdict(all(np.all(np.abs(r) < 0.01) for r in rel))}")

        # 2. Sun: white-ish Lambertian plane facing the sun, E = 2 W/m^2 -> L = rho E / pi.
        d = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
        Rm = np.eye(4)
        y = d
        x = np.cross(y, [0, 0, 1.0]); x /= np.linalg.norm(x)
        z = np.cross(x, y)
        Rm[:3, :3] = np.stack([x, y, z], axis=1)
        rho, E = 0.8, 2.0
        cam2 = sg.PinholeCamera.from_fov(20.0, 32, 32, sg.PinholeCamera.look_at((3.0 * d + 0.4 * x).tolist(), [0, 0, 0],
                                                                                z.tolist()))
        spec = _check_spec("check_sun", 32, 32, cam2, [_mesh_entry("plane", P.plane(20, 20))],
                           [{"type": "diffuse", "params": {"albedo": [rho] * 3}}],
                           [{"mesh": 0, "material": 0, "world_from_object": _rows(Rm)}],
                           [{"type": "sun", "params": {"direction": d.tolist(), "irradiance": E, "angular_diameter": 0.53}}], 2)
        sgi, cyi = both(spec, "sun")
        want = rho * E / math.pi
        r = [img.mean() / want for img in (sgi, cyi)]
        print(f"check sun: rho E / pi = {want:.5f}  synthgen/expected = {r[0]:.5f}  Cycles/expected = {r[1]:.5f} "
              f"{verdict(all(abs(x - 1) < 0.005 for x in r))}")

        # 3. Point light: intensity I [W/sr] 2 m above a Lambertian plane; per pixel
        #    L = rho/pi * I cos(theta) / r^2 at the point the pixel centre sees.
        I, h = 5.0, 2.0
        wfc3 = sg.PinholeCamera.look_at([0.0, 3.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
        cam3 = sg.PinholeCamera.from_fov(30.0, 32, 32, wfc3)
        spec = _check_spec("check_point", 32, 32, cam3, [_mesh_entry("plane", P.plane(20, 20))],
                           [{"type": "diffuse", "params": {"albedo": [rho] * 3}}],
                           [{"mesh": 0, "material": 0, "world_from_object": eye4}],
                           [{"type": "point", "params": {"position": [0.0, h, 0.0], "intensity": I}}], 2)
        sgi, cyi = both(spec, "point")
        exp = np.zeros((32, 32))
        for j in range(32):
            for i in range(32):
                o, dr = cam3.generate_ray(i + 0.5, j + 0.5)
                t = -o[1] / dr[1]
                q = np.array(o) + t * np.array(dr)
                dl = np.array([0.0, h, 0.0]) - q
                r2 = dl @ dl
                exp[j, i] = rho / math.pi * I * (dl[1] / math.sqrt(r2)) / r2
        r = [img[..., 0].mean() / exp.mean() for img in (sgi, cyi)]
        print(f"check point light (Blender power = 4 pi I): synthgen/expected = {r[0]:.5f}  Cycles/expected = {r[1]:.5f} "
              f"{verdict(all(abs(x - 1) < 0.005 for x in r))}")

        # 4. Constant environment: an upward plane under a uniform sky of radiance Le: L = rho Le;
        #    the sky seen directly is Le.
        Le = [0.5, 0.4, 0.3]
        cam4 = sg.PinholeCamera.from_fov(40.0, 32, 32, sg.PinholeCamera.look_at([0.0, 2.0, -6.0], [0.0, 0.0, 6.0], [0, 1, 0]))
        spec = _check_spec("check_env", 32, 32, cam4, [_mesh_entry("plane", P.plane(1000, 1000))],
                           [{"type": "diffuse", "params": {"albedo": [rho] * 3}}],
                           [{"mesh": 0, "material": 0, "world_from_object": eye4}],
                           [{"type": "environment", "params": {"radiance": Le}}], 2)
        sgi, cyi = both(spec, "env")
        ground = slice(20, 32)  # rows below the horizon see the plane near the camera
        sky = slice(0, 4)
        for what, rows, want in (("plane", ground, rho * np.array(Le)), ("sky", sky, np.array(Le))):
            r = [img[rows].mean(axis=(0, 1)) / want for img in (sgi, cyi)]
            print(f"check environment {what}: synthgen/expected = {_fmt(r[0])}  Cycles/expected = {_fmt(r[1])} "
                  f"{verdict(all(np.all(np.abs(x - 1) < 0.005) for x in r))}")

        # 5. Environment map orientation: the map seen directly (max_depth 1) by a tilted wide-angle
        #    camera, with a non-zero rotation; the images must agree pixel by pixel up to noise
        #    (both read the nearest map pixel), and a sphere lit only by the map must agree in mean.
        plugins = available_plugins()
        if "envmap" in plugins["light"]:
            hdr = os.path.join(HDR_DIR, "courtyard.exr")
            lt = [{"type": "envmap", "params": envmap_params({"filename": hdr, "rotation": 40.0})}]
            for k, (target, up) in enumerate((([1.0, 0.3, 0.4], [0, 1, 0]), ([-0.3, -0.2, -1.0], [0.2, 1, 0]))):
                cam5 = sg.PinholeCamera.from_fov(90.0, 64, 48, sg.PinholeCamera.look_at([0, 0, 0], target, up))
                far = _quad_facing([0, 0, -1e4], [0, 0, 1], 1.0)  # out of view: the scene needs an instance
                spec = _check_spec("check_envmap", 64, 48, cam5, [_mesh_entry("far", far)],
                                   [{"type": "diffuse", "params": {"albedo": [0.5] * 3}}],
                                   [{"mesh": 0, "material": 0, "world_from_object": eye4}], lt, 1)
                sgi, cyi = both(spec, f"envmap{k}", n=256)
                rel = float(np.abs(cyi - sgi).mean() / sgi.mean())
                mirrored = float(np.abs(cyi[:, ::-1] - sgi).mean() / sgi.mean())
                print(f"check envmap seen directly, view {k}: mean |Cycles - synthgen| / mean = {100 * rel:.2f} % "
                      f"(mirrored image: {100 * mirrored:.1f} %) {verdict(rel < 0.02 and mirrored > 5 * rel)}")
            cam6 = sg.PinholeCamera.from_fov(30.0, 48, 48, sg.PinholeCamera.look_at([0, 0.5, -4], [0, 0.5, 0], [0, 1, 0]))
            spec = _check_spec("check_envmap_lit", 48, 48, cam6, [_mesh_entry("sphere", P.uv_sphere(0.5, 64, 32))],
                               [{"type": "diffuse", "params": {"albedo": [0.8] * 3}}],
                               [{"mesh": 0, "material": 0, "world_from_object": _rows(P.translate([0, 0.5, 0]))}],
                               [{"type": "envmap", "params": envmap_params({"filename": hdr, "rotation": 40.0,
                                                                              "visible": False})}], 2)
            sgi, cyi = both(spec, "envmap_lit", n=2048)
            d = mean_diff_pct(cyi, sgi)
            print(f"check envmap lighting a Lambertian sphere (map hidden from the camera): Cycles vs synthgen "
                  f"{_fmt(d)} % {verdict(np.all(np.abs(d) < 1.0))}")

        # 6. Path length: Cornell box at max_depth 3 and 4; Cycles max_bounces = max_depth - 2 must
        #    match, max_depth - 1 (one bounce more) must not.
        if os.path.isdir(CBOX_DIR):
            for depth in (3, 4):
                spec = dict(build_spec("cbox", 128, 128), max_depth=depth)
                s = dict(spec, spp=256, seed=3, threads=args.threads)
                sgi, _ = synthgen_render(s, 256, seed=3, threads=args.threads)
                cy_a, _ = run_cycles(dict(s, output=os.path.join(work, "cb_a.exr")), work, "cb_a", blender)
                cy_b, _ = run_cycles(dict(s, output=os.path.join(work, "cb_b.exr"), cycles_max_bounces=depth - 1),
                                     work, "cb_b", blender)
                da, db = mean_diff_pct(cy_a, sgi), mean_diff_pct(cy_b, sgi)
                print(f"check cbox max_depth {depth}: Cycles max_bounces {depth - 2} vs synthgen {_fmt(da)} %, "
                      f"max_bounces {depth - 1}: {_fmt(db)} % {verdict(np.all(np.abs(da) < 1.0) and np.abs(db).min() > 3 * np.abs(da).max())}")
    print(f"check_ok={int(ok_all)}")
    return 0 if ok_all else 1


# ---------------------------------------------------------------------------------------------


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default=",".join(ALL_SCENES), help="comma-separated subset of " + ",".join(ALL_SCENES))
    ap.add_argument("--width", type=int, default=256)
    ap.add_argument("--height", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", type=int, default=3, help="timed runs per renderer and scene (medians are reported)")
    ap.add_argument("--ref-spp", type=int, default=None,
                    help="spp of the converged images (default 4096; 1024 with --make-references)")
    ap.add_argument("--ref-dir", default=os.path.join(REPO, "bench", "references"),
                    help="cache of converged images (generated on first use)")
    ap.add_argument("--check", action="store_true", help="verify camera, light and bounce conversions numerically")
    ap.add_argument("--make-references", action="store_true",
                    help="store Cycles renders as test references (RGB float16 EXR + JSON) in --references-out")
    ap.add_argument("--references-out", default=TEST_REF_DIR)
    ap.add_argument("--render-synthgen", metavar="SPEC", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.render_synthgen:
        return _render_synthgen_main(args.render_synthgen)
    args.scenes = [s.strip() for s in args.scenes.split(",") if s.strip()]
    bad = [s for s in args.scenes if s not in ALL_SCENES]
    if bad:
        ap.error(f"unknown scene(s) {bad}; choose from {','.join(ALL_SCENES)}")
    if args.ref_spp is None:
        args.ref_spp = 1024 if args.make_references else 4096
    args.ref_dir = os.path.abspath(args.ref_dir)
    blender = ensure_blender()
    if args.check:
        return run_check(args, blender)
    if args.make_references:
        return run_make_references(args, blender)
    return run_benchmark(args, blender)


if __name__ == "__main__":
    sys.exit(main())
