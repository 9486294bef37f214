"""The peer renderers of the benchmarks, run as separate processes: Blender Cycles (CPU, the
scene built by :mod:`synthgen.bench.cycles_scene`) and Embree's tutorial ``pathtracer``
(Debian ``embree-tools``, its own Cornell box only); image reading for both.

Times:

* Cycles: ``render_s``, the wall time of ``bpy.ops.render.render()`` measured inside Blender
  (Cycles' scene synchronisation, BVH build, path tracing and adaptive-sampling filtering; not
  Blender's start-up, the Python scene construction or writing the EXR). Cycles' own
  ``render_time`` figure (EXR header, path tracing only, 10 ms resolution) is kept as
  ``pathtrace_s``.
* Embree ``pathtracer``: it prints no render time, so ``render_s`` is the process's wall time
  minus its start-up, measured as the median wall time of three runs of the same scene at
  1 x 1 pixel and 1 spp (process start, scene load, BVH build, writing the image).
"""
from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import time
from typing import Any, Dict, Optional, Tuple

import numpy as np

#: The Blender-side script (runs inside Blender).
CYCLES_SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "cycles_scene.py")
#: Embree's tutorial models (Debian embree-tools).
EMBREE_MODELS = "/usr/share/doc/embree3/models"


def find_blender() -> Optional[str]:
    """Path of ``blender`` on PATH, or None (nothing is installed here)."""
    return shutil.which("blender")


def find_pathtracer() -> Optional[str]:
    """Path of Embree's tutorial ``pathtracer`` if it and its Cornell box are installed, else None."""
    exe = shutil.which("pathtracer")
    return exe if exe and os.path.isfile(os.path.join(EMBREE_MODELS, "cornell_box.ecs")) else None


# ---------------------------------------------------------------------------------------------
# Images


def read_exr(path: str, with_meta: bool = False) -> Any:
    """RGB float32 H x W x 3 of an image file (any format OpenImageIO reads); with ``with_meta``
    also its header attributes as a dict."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise OSError(f"{path}: {buf.geterror()}")
    px = np.ascontiguousarray(buf.get_pixels(oiio.FLOAT)[:, :, :3], dtype=np.float32)
    if not with_meta:
        return px
    meta = {a.name: a.value for a in buf.spec().extra_attribs}
    return px, meta


def read_pfm(path: str) -> np.ndarray:
    """RGB float32 H x W x 3 of a colour PFM (rows stored bottom to top; returned top to bottom)."""
    with open(path, "rb") as f:
        data = f.read()
    head = data.split(b"\n", 3)
    if head[0].strip() != b"PF":
        raise OSError(f"{path}: not a colour PFM")
    w, h = (int(x) for x in head[1].split())
    scale = float(head[2])
    dtype = "<f4" if scale < 0 else ">f4"
    px = np.frombuffer(head[3][:w * h * 12], dtype=dtype).reshape(h, w, 3)
    return np.ascontiguousarray(px[::-1], dtype=np.float32)


def parse_blender_time(s: str) -> float:
    """Seconds of a Blender time string such as ``00:01.25`` or ``01:02:03.5``."""
    v = 0.0
    for x in s.split(":"):
        v = v * 60.0 + float(x)
    return v


# ---------------------------------------------------------------------------------------------
# Blender Cycles


def run_cycles(spec: Dict[str, Any], workdir: str, tag: str, blender: str = "blender") -> Tuple[np.ndarray, dict]:
    """Renders ``spec`` (a scene spec plus spp, seed, threads, output and the optional Cycles
    keys of cycles_scene.py) with Blender; returns (rgb, timings: render_s, process_s,
    pathtrace_s, sync_s, ...)."""
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
            t[name] = parse_blender_time(v)
    return img, t


# ---------------------------------------------------------------------------------------------
# Embree's tutorial path tracer and its Cornell box

#: Embree's --max-path-length (surface interactions; 1 = primary + shadow ray) of the benchmark
#: scene; synthgen's max_depth counts ray segments, so max_depth = this + 1 gives the same paths.
EMBREE_PATH_LENGTH = 8


def embree_cbox_scene(light: str = "point") -> Tuple[Any, np.ndarray]:
    """synthgen's build of ``pathtracer -c cornell_box.ecs``: the OBJ with its MTL diffuse
    colours (Kd), the .ecs point light (or, with ``light="area"``, the box's luminaire quad as
    an area light of the same power) and the camera's world_from_camera (-vp 278 273 -800
    -vi 278 273 0 -vu 0 1 0; -fov 37 is vertical). Returns (uncommitted scene, world_from_camera)."""
    from .. import _core as sg

    scene = sg.Scene()
    imported = scene.load_mesh_file(f"{EMBREE_MODELS}/cornell_box.obj")
    scene.add_instance(imported["mesh_id"])
    if light == "point":
        # -pointlight 213 300 227 100000 100000 100000
        scene.add_light("point", {"position": [213.0, 300.0, 227.0], "intensity": [1e5, 1e5, 1e5]})
    else:
        # The box's own luminaire quad (y = 548, x 213..343, z 227..332) as an area light
        # emitting downwards, with the same total power as the point light (4 pi I = pi L A).
        area = 130.0 * 105.0
        radiance = 4.0 * 1e5 / area
        light_mat = scene.add_material("emissive", {"radiance": [radiance] * 3, "two_sided": True})
        p = np.array([[213, 547.9, 227], [343, 547.9, 227], [343, 547.9, 332], [213, 547.9, 332]], np.float32)
        mesh = scene.add_mesh(p, np.array([[0, 1, 2], [0, 2, 3]], np.uint32), name="luminaire")
        scene.add_instance(mesh, material_id=light_mat)
    world_from_camera = sg.PinholeCamera.look_at([278, 273, -800], [278, 273, 0], [0, 1, 0])
    return scene, world_from_camera


def synthgen_embree_cbox(width: int, height: int, spp: int, seed: int, threads: int,
                         **settings: Any) -> Tuple[np.ndarray, dict]:
    """Renders Embree's Cornell box with synthgen in this process (max_depth =
    EMBREE_PATH_LENGTH + 1); returns (rgb, timings as :func:`synthgen.bench.scenes.synthgen_render`)."""
    from .. import _core as sg

    t0 = time.perf_counter()
    scene, wfc = embree_cbox_scene("point")
    scene.set_camera(sg.PinholeCamera.from_fov(37.0, width, height, wfc))
    t1 = time.perf_counter()
    scene.commit()
    t2 = time.perf_counter()
    res = scene.render(spp=spp, max_depth=EMBREE_PATH_LENGTH + 1, seed=seed, threads=threads, **settings)
    t3 = time.perf_counter()
    st = res.stats
    count = getattr(res, "sample_count", None)
    return np.array(res.rgb, dtype=np.float32), {
        "build_s": t1 - t0, "commit_s": t2 - t1, "wall_time_s": st["wall_time_s"],
        "render_s": (t1 - t0) + (t2 - t1) + st["wall_time_s"], "render_call_total_s": t3 - t0,
        "mean_spp": float(np.asarray(count).mean()) if count is not None else float(spp)}


def _pathtracer_cmd(exe: str, width: int, height: int, spp: int, threads: int, out: str) -> list:
    return [exe, "-c", os.path.join(EMBREE_MODELS, "cornell_box.ecs"), "--size", str(width), str(height),
            "--spp", str(spp), "--max-path-length", str(EMBREE_PATH_LENGTH), "--threads", str(threads), "-o", out]


def _run_timed(cmd: list) -> float:
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")
    return wall


def pathtracer_startup(exe: str, threads: int, workdir: str) -> float:
    """Median wall time of three 1 x 1-pixel, 1-spp runs: what a run costs besides rendering."""
    out = os.path.join(workdir, "embree_startup.pfm")
    return statistics.median(_run_timed(_pathtracer_cmd(exe, 1, 1, 1, threads, out)) for _ in range(3))


def run_pathtracer(exe: str, width: int, height: int, spp: int, threads: int, workdir: str,
                   startup_s: float) -> Tuple[np.ndarray, dict]:
    """Renders Embree's Cornell box with ``pathtracer`` (a PFM: Embree's 8-bit frame buffer,
    so values are clamped to [0, 1] and quantized to 1/255); returns (rgb, {render_s,
    process_s, startup_s})."""
    out = os.path.join(workdir, f"embree_{width}x{height}_{spp}.pfm")
    wall = _run_timed(_pathtracer_cmd(exe, width, height, spp, threads, out))
    return read_pfm(out), {"process_s": wall, "startup_s": startup_s, "render_s": max(wall - startup_s, 1e-4)}
