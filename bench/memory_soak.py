#!/usr/bin/env python3
"""Resident memory of dataset workers over a long run (docs/texture_lod.md): scenarios/road_signs.yaml
(a new sign face, plates and wear textures every frame) rendered by 2 worker processes that are
never recycled, at reduced resolution and spp, with texture_lod; every 200 frames the resident
memory (RSS) each worker reported after its frames of the last 200: the median, and the
largest in brackets. Workers give their free heap pages back after each frame (malloc_trim), so
the RSS follows what a frame holds, which changes with its content (how many signs, plates
and wear textures: about +-8% from frame to frame); the median of a window is what a worker
needs, the trend of the medians is what a long run accumulates. The last line is exactly

    rss_growth_pct=<float>

the largest growth of a worker's median RSS from the first window to the last, in percent (the
first frames load the meshes, fonts and the image plugin: growth after them is what a long run
would accumulate).

    .venv/bin/python bench/memory_soak.py [--frames 2000] [--workers 2] [--resolution 160 120] [--spp 4]
"""
from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(REPO, "python"))

SCENARIO = os.path.join(REPO, "scenarios", "road_signs.yaml")


def main(argv=None) -> int:
    from synthgen.run.executors import LocalExecutor
    from synthgen.run.task import render_task
    from synthgen.scenario import check_inputs, load_scenario

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=2000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--resolution", type=int, nargs=2, default=(160, 120))
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--every", type=int, default=200)
    args = ap.parse_args(argv)

    sc = load_scenario(SCENARIO, overrides=[("resolution", list(args.resolution)), ("render.spp", args.spp),
                                            ("render.texture_lod", True)])
    check_inputs(sc)
    out = tempfile.mkdtemp(prefix="synthgen-soak-")
    print(f"scenario: {os.path.relpath(SCENARIO, REPO)}, {args.frames} frames, {args.workers} workers (never "
          f"recycled), {args.resolution[0]}x{args.resolution[1]}, {args.spp} spp, texture_lod", flush=True)
    threads = max(1, (os.cpu_count() or 1) // args.workers)
    ex = LocalExecutor(args.workers, recycle=args.frames + 1)
    window: dict = {}
    first, latest, failures = {}, {}, 0
    try:
        for n, r in enumerate(ex.map(render_task, [(sc, out, k, threads) for k in range(args.frames)]), 1):
            if not r["ok"]:
                failures += 1
                print(f"frame {r['frame']} failed: {r['error']}", flush=True)
                continue
            window.setdefault(r["pid"], []).append(r["rss_bytes"])
            if n % args.every == 0 or n == args.frames:
                latest = {p: statistics.median(v) for p, v in window.items()}
                if not first:
                    first = dict(latest)
                rss = ", ".join(f"worker {i}: {latest[p] / 2**20:.1f} MiB [{max(window[p]) / 2**20:.1f}]"
                                for i, p in enumerate(sorted(latest)))
                print(f"frames {n}: {rss}", flush=True)
                window = {}
    finally:
        shutil.rmtree(out, ignore_errors=True)
    growth = max(100.0 * (latest[p] / first[p] - 1.0) for p in first if p in latest)
    print(f"failures: {failures}")
    print(f"rss_growth_pct={growth:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
