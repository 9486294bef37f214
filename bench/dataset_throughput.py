#!/usr/bin/env python3
"""Dataset throughput of the scenario runner (a script that prints figures, not a test).

Renders scenarios/default.yaml at 640x480 with every output kind (sRGB PNG and linear EXR,
depth EXR and 16-bit PNG, instance and semantic masks, COCO, YOLO, KITTI, metadata) with 1
and with 2 worker processes, then on a Dask LocalCluster of 2 worker processes (--dask 0: not),
and prints frames/s, the mean seconds per stage (scene update, layout with its visibility checks
and amodal masks, path tracing, writing) and what travels to the workers: the scenario once
per worker (``scenario_bytes``), per frame only the task (``task_bytes``: the function's
reference, the frame number, options). CPU time: per run the mean CPU seconds of a frame in its
worker (every thread) and of its path tracing (the render call of the image), and the CPU time of
the whole run, this process and its worker processes (resource.getrusage: self and children).
The last lines are ``non_render_fraction=<float>`` (over every run's frames: the CPU time of the
frames outside the path tracer's render call / their CPU time), ``bytes_per_frame_to_workers=<int>``
(the Dask run's task), ``frames_per_second=<float>`` and ``frames_per_cpu_hour=<float>`` (frames /
CPU hours of the run), both of the best configuration on this machine.

    .venv/bin/python bench/dataset_throughput.py [--frames 8] [--workers 1,2] [--dask 2]
"""
from __future__ import annotations

import argparse
import contextlib
import os
import resource
import shutil
import sys
import tempfile

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "python"))

import yaml  # noqa: E402

from synthgen import outputs, run as runner  # noqa: E402


def cpu_seconds() -> float:
    """CPU seconds (user and system) of this process and of its children that have ended."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def every_output_scenario(scenario: str, tmp: str) -> tuple:
    """(path, spec) of `scenario` at 640x480 with every output kind, written into `tmp`."""
    with open(scenario) as f:
        spec = yaml.safe_load(f)
    spec["resolution"] = [640, 480]
    spec["outputs"] = list(outputs.kind_names())
    path = os.path.join(tmp, "scenario.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(spec, f, sort_keys=False)
    return path, spec


@contextlib.contextmanager
def local_cluster(workers: int):
    """A client of a Dask LocalCluster of `workers` processes, one task thread each, on this
    machine: ``with local_cluster(2) as client: ...``."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        yield client


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=8, help="frames per configuration (default 8)")
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts (default 1,2)")
    ap.add_argument("--scenario", default=os.path.join(REPO, "scenarios", "default.yaml"))
    ap.add_argument("--dask", type=int, default=2, help="Dask LocalCluster worker processes (0: no Dask run)")
    args = ap.parse_args(argv)
    tmp = tempfile.mkdtemp(prefix="synthgen-throughput-")
    try:
        path, spec = every_output_scenario(args.scenario, tmp)
        print(f"scenario: {os.path.relpath(args.scenario, REPO)} at 640x480, {spec['render']['spp']} spp, "
              f"max_depth {spec['render']['max_depth']}, outputs: {', '.join(outputs.kind_names())}; "
              f"{args.frames} frames per run; {os.cpu_count()} cores")
        print(f"spp={spec['render']['spp']}")
        best = best_cpu = 0.0
        frames_cpu = frames_other_cpu = 0.0
        runs = [(f"workers={w}", dict(workers=w)) for w in (int(x) for x in args.workers.split(","))]
        if args.dask > 0:
            runs.append((f"dask_workers={args.dask}", None))
        task_bytes = 0
        for name, kw in runs:
            out = os.path.join(tmp, name.replace("=", ""))
            c0 = cpu_seconds()
            if kw is None:
                threads = max(1, (os.cpu_count() or 1) // args.dask)
                with local_cluster(args.dask) as client:
                    s = runner.run(path, out, count=args.frames, scheduler=client, threads=threads, progress=False)
                task_bytes = s["task_bytes"]
            else:
                s = runner.run(path, out, count=args.frames, progress=False, **kw)
            run_cpu = cpu_seconds() - c0  # after the workers ended (pool shut down, cluster closed)
            if s["failures"]:
                print(s.text())
                return 1
            st, ct = s["stage_s"], s["stage_cpu_s"]
            per_cpu_hour = s["rendered"] / (run_cpu / 3600.0) if run_cpu > 0 else 0.0
            print(f"{name} frames={s['rendered']} wall_s={s['wall_s']:.2f} frames_per_s={s['frames_per_s']:.3f} "
                  f"s_per_frame_per_worker={s['mean_s_per_frame']:.3f} stage_s: update={st['update_s']:.3f} "
                  f"layout={st['layout_s']:.3f} render={st['render_s']:.3f} write={st['write_s']:.3f} "
                  f"scenario_bytes={s['shared_bytes']} task_bytes={s['task_bytes']}")
            print(f"{name} cpu_s_per_frame={ct['total_s']:.3f} render_cpu_s_per_frame={ct['render_s']:.3f} "
                  f"other_cpu_s_per_frame={ct['other_s']:.3f} non_render_fraction={s['non_render_fraction']:.4f} "
                  f"run_cpu_s={run_cpu:.2f} frames_per_cpu_hour={per_cpu_hour:.1f}")
            best = max(best, s["frames_per_s"])
            best_cpu = max(best_cpu, per_cpu_hour)
            frames_cpu += ct["total_s"] * s["rendered"]
            frames_other_cpu += ct["other_s"] * s["rendered"]
        print(f"non_render_fraction={frames_other_cpu / frames_cpu if frames_cpu > 0 else 0.0:.4f}")
        if args.dask > 0:
            print(f"bytes_per_frame_to_workers={task_bytes}")
        print(f"frames_per_second={best:.3f}")
        print(f"frames_per_cpu_hour={best_cpu:.1f}")
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
