#!/usr/bin/env python3
"""Dataset throughput of the scenario runner (a script that prints figures, not a test).

Renders scenarios/default.yaml at 640x480 with every output kind (sRGB PNG and linear EXR,
depth EXR and 16-bit PNG, instance and semantic masks, COCO, YOLO, KITTI, metadata) with 1
and with 2 worker processes, and prints frames/s and the mean seconds per stage (scene
update, layout with label-only renders and amodal masks, path tracing, writing). The last
line is ``frames_per_second=<float>``: the best configuration on this machine.

    .venv/bin/python bench/dataset_throughput.py [--frames 8] [--workers 1,2]
"""
from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "python"))

import yaml  # noqa: E402

from synthgen import outputs, run as runner  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=8, help="frames per configuration (default 8)")
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts (default 1,2)")
    ap.add_argument("--scenario", default=os.path.join(REPO, "scenarios", "default.yaml"))
    args = ap.parse_args(argv)
    with open(args.scenario) as f:
        spec = yaml.safe_load(f)
    spec["resolution"] = [640, 480]
    spec["outputs"] = list(outputs.kind_names())
    tmp = tempfile.mkdtemp(prefix="synthgen-throughput-")
    try:
        path = os.path.join(tmp, "scenario.yaml")
        with open(path, "w") as f:
            yaml.safe_dump(spec, f, sort_keys=False)
        print(f"scenario: {os.path.relpath(args.scenario, REPO)} at 640x480, {spec['render']['spp']} spp, "
              f"max_depth {spec['render']['max_depth']}, outputs: {', '.join(outputs.kind_names())}; "
              f"{args.frames} frames per run; {os.cpu_count()} cores")
        best = 0.0
        for w in (int(x) for x in args.workers.split(",")):
            out = os.path.join(tmp, f"out{w}")
            s = runner.run(path, out, count=args.frames, workers=w, progress=False)
            if s["failures"]:
                print(s.text())
                return 1
            st = s["stage_s"]
            print(f"workers={w} frames={s['rendered']} wall_s={s['wall_s']:.2f} frames_per_s={s['frames_per_s']:.3f} "
                  f"s_per_frame_per_worker={s['mean_s_per_frame']:.3f} stage_s: update={st['update_s']:.3f} "
                  f"layout={st['layout_s']:.3f} render={st['render_s']:.3f} write={st['write_s']:.3f}")
            best = max(best, s["frames_per_s"])
        print(f"frames_per_second={best:.3f}")
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
