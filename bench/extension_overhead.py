#!/usr/bin/env python3
"""Cost of the C extension mechanism (a script that prints figures, not a test).

Hydra Render measured its extensions against built-in code (rust +21% render time, scratches
+15% over grey diffuse; Sanzharov 2023). Here, in one run (interleaved, median of --runs): the
scene of bench/wear_overhead.py (the Kenney truck on a ground plane under a sky) with the model
grey diffuse, rusted by the built-in preset (synthgen.wear.rust: a graph of noise, gradient,
edges and blend textures) and rusted by the same preset on the example extension rust.c
(synthgen.scene.wear_ext.rust: three C functions calling synthgen's noise). The last lines are
``psnr_extension_vs_builtin_db=<float>`` (the two rust renders) and
``extension_vs_builtin_overhead_pct=<float>`` (the extension rust's render time over the
built-in's, minus 1; target <= 10).

Then the cost of isolation (docs/extensions.md: ``synthgen run`` renders in a worker process
even with one worker, so that an extension's crash or loop fails only its frame): a small
scenario whose ground is rusted by rust.c (``--isolation-frames`` frames, 160x120, 8 spp) run by
synthgen.run.run in this process (``isolate=False``, the FrameRenderer built anew each run) and
in a worker process (the default), with 1 frame and with N frames, interleaved, median of
--runs. Overhead = a + b x frames: ``isolation_overhead_s_per_run=<a>`` (the worker's start, its
imports and scenario load) and ``isolation_overhead_s_per_frame=<b>`` (the result's way back),
``isolation_overhead_pct=<float>`` (of the in-process N-frame run's wall time).

    .venv/bin/python bench/extension_overhead.py [--runs 3] [--spp 32] [--part all|render|isolation]
"""
from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import synthgen as sg  # noqa: E402
from synthgen import wear  # noqa: E402
from synthgen.scene import wear_ext  # noqa: E402
from wear_overhead import build  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("--part", choices=("all", "render", "isolation"), default="all")
    ap.add_argument("--isolation-frames", type=int, default=4)
    args = ap.parse_args(argv)
    if args.part in ("all", "render"):
        render_comparison(args)
    if args.part in ("all", "isolation"):
        isolation_cost(args)
    return 0


ISOLATION_SCENARIO = """
version: 1
seed: 3
count: {count}
resolution: [160, 120]
allow_extensions: true
extensions: [{rust}]
camera:
  fov_y: 45
  pose: {{type: orbit, target: [0, 0.3, 0], distance: 5, elevation: 25, azimuth: {{uniform: [0, 360]}}}}
lights: [{{type: sky, elevation: 40, azimuth: 130}}]
ground: {{size: 20, material: {{type: diffuse, albedo: {{texture: {{type: rust_color, seed: {{int: [0, 100]}}}}}}}}}}
objects: [{{class: box, primitive: box, size: [0.8, 0.8, 0.8], material: {{type: diffuse, albedo: 0.5}}}}]
placement: {{region: [-1, -1, 1, 1]}}
render: {{spp: 8, max_depth: 4}}
outputs: [rgb, instance, coco]
"""


def isolation_cost(args) -> None:
    """synthgen run in this process against in a worker process (see the module doc)."""
    from synthgen.run import run, task
    from synthgen.scene import extensions

    n = max(2, args.isolation_frames)
    work = tempfile.mkdtemp(prefix="synthgen-isolation-")
    try:
        path = os.path.join(work, "rust_ground.yaml")
        with open(path, "w") as f:
            f.write(ISOLATION_SCENARIO.format(count=n, rust=extensions.example("rust")))
        print(f"scenario: 160x120, 8 spp, ground rusted by rust.c; 1 and {n} frames; synthgen.run.run in this "
              f"process and in a worker process; median of {args.runs} interleaved runs")
        walls = {(iso, k): [] for iso in (False, True) for k in (1, n)}
        for r in range(args.runs + 1):  # the first round warms the caches (compiled extension, imports)
            for (iso, k) in walls:
                task._WORKER.clear()  # in this process, as in a fresh one: the FrameRenderer built again
                out = os.path.join(work, f"out-{r}-{int(iso)}-{k}")
                t0 = time.perf_counter()
                s = run(path, out, count=k, progress=False, allow_extensions=True, isolate=iso)
                wall = time.perf_counter() - t0
                assert s["rendered"] == k and not s["failures"], s.text()
                if r:
                    walls[(iso, k)].append(wall)
                shutil.rmtree(out)
        med = {key: statistics.median(v) for key, v in walls.items()}
        for (iso, k), v in sorted(med.items()):
            print(f"{'worker_process' if iso else 'in_process'}_{k}_frames_wall_s={v:.3f}")
        over_1, over_n = med[(True, 1)] - med[(False, 1)], med[(True, n)] - med[(False, n)]
        per_frame = (over_n - over_1) / (n - 1)
        print(f"isolation_overhead_s_per_run={over_1 - per_frame:.3f}")
        print(f"isolation_overhead_s_per_frame={per_frame:.3f}")
        print(f"isolation_overhead_pct={100.0 * over_n / med[(False, n)]:.1f}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


def render_comparison(args) -> None:
    sg.load_image_plugin()
    wear.rust_extension = wear_ext.rust  # build() looks presets up by name in synthgen.wear
    scenes = {}
    for e in ("grey", "rust", "rust_extension"):
        scenes[e], what = build(e, args.width, args.height)
    print(f"scene: {what}, {args.width}x{args.height}, {args.spp} spp, max_depth 6; median of {args.runs} "
          "interleaved runs")
    times = {e: [] for e in scenes}
    images = {}
    for _ in range(args.runs):
        for e, s in scenes.items():
            r = s.render(spp=args.spp, max_depth=6, seed=1)
            times[e].append(r.stats["wall_time_s"])
            images[e] = r.rgb
    med = {e: statistics.median(v) for e, v in times.items()}
    for e in scenes:
        print(f"{e}_render_s={med[e]:.3f}")
    a, b = images["rust"].astype(np.float64), images["rust_extension"].astype(np.float64)
    mse = float(np.mean((a - b) ** 2))
    psnr = float("inf") if mse == 0.0 else 10.0 * np.log10(float(a.max()) ** 2 / mse)
    print(f"builtin_rust_vs_grey_overhead_pct={100.0 * (med['rust'] / med['grey'] - 1.0):.1f}")
    print(f"extension_rust_vs_grey_overhead_pct={100.0 * (med['rust_extension'] / med['grey'] - 1.0):.1f}")
    print(f"psnr_extension_vs_builtin_db={psnr:.2f}")
    print(f"extension_vs_builtin_overhead_pct={100.0 * (med['rust_extension'] / med['rust'] - 1.0):.1f}")


if __name__ == "__main__":
    sys.exit(main())
