#!/usr/bin/env python3
"""Peer benchmark: synthgen vs Blender Cycles (CPU) on the same scenes, same settings.

    .venv/bin/python bench/vs_cycles.py                      # all scenes, 256x256, 64 spp, 2 threads
    .venv/bin/python bench/vs_cycles.py --scenes cbox,sunlit --spp 128 --runs 3
    .venv/bin/python bench/vs_cycles.py --check              # camera / light / bounce conversions
    .venv/bin/python bench/vs_cycles.py --make-references    # tests/python/references/cycles/*.exr

Installs Debian's `blender` and `blender-data` (HDR maps) with apt-get if missing and runs
Blender 3.4 as `blender -b --factory-startup --python-exit-code 1 -P bench/cycles_scene.py -- spec.json`.
Each scene is written once as a JSON description (bench/vs_cycles_scenes.py: meshes as vertex
arrays, synthgen material and light plugin parameters, OpenCV camera); this script builds the
synthgen scene from it and bench/cycles_scene.py builds the Blender scene from it, so both get
the same geometry, camera, lights and materials (the --check conversions: bench/vs_cycles_check.py).
Settings are equal on both sides: resolution, spp, max path length
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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# The scene descriptions (shared with the tests and cycles_scene.py's input) and the Cycles
# runner live in the package (synthgen.bench, shared with `synthgen bench`).
from vs_cycles_scenes import (CBOX_DIR, HDR_DIR, _sg, build_spec, spec_digest, synthgen_render,  # noqa: E402
                              synthgen_scene)  # noqa: F401  (tests/python/test_vs_cycles_reference.py)
from synthgen.bench.peers import read_exr, run_cycles  # noqa: E402
from vs_cycles_common import _fmt, mean_diff_pct  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
TEST_REF_DIR = os.path.join(REPO, "tests", "python", "references", "cycles")
ALL_SCENES = ("cbox", "materials", "sunlit")
# Scenes whose light transport models are the same in both renderers (Lambertian surfaces,
# area / sun / constant-environment lights); the materials scene compares different BSDFs.
MODELS_AGREE = ("cbox", "sunlit")


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


# ---------------------------------------------------------------------------------------------
# Images and figures


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
        from vs_cycles_check import run_check

        return run_check(args, blender)
    if args.make_references:
        return run_make_references(args, blender)
    return run_benchmark(args, blender)


if __name__ == "__main__":
    sys.exit(main())
