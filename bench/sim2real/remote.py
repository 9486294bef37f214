"""Runs training jobs of ``bench/sim2real.py`` on the accelerator machine, which has PyTorch
with CUDA but not synthgen's compiled core (``synthgen._core``): this file puts a stand-in for
the core's error type in its place, so the evaluate stage (pure Python on PyTorch) imports, and
reads images with Pillow (:mod:`synthgen.evaluate.images`). Everything that needs synthgen
proper (reading datasets and label files, decoding with synthgen's strict reader, rendering)
happens on the CPU machine, which writes the jobs (:func:`write_job`).

A job file (JSON): ``{"jobs": [{"name", "classes", "pools": {POOL: [SAMPLE, ...]}, "mix",
"options": TrainOptions fields, "test": [SAMPLE, ...], "init": model file or null}, ...]}``,
a SAMPLE ``[image path relative to the root, boxes (x0 y0 x1 y1 px), classes, ignore flags]``.

    python3 bench/sim2real/remote.py JOBS.json --root DIR --out DIR [--device cuda] [--workers N]
        [--parallel P] [--pack MiB]

writes per job ``NAME.model`` and, for all jobs, ``results.json``: per job the scores of its
test samples (AP50 with its bootstrap interval, AP50:95, R@0.1FPPI, per size bucket), the
training manifest, the loss curve (every 10th step) and the seconds it took.

``--parallel P`` trains P jobs at a time (each in its own process with ``workers // P`` data
workers, sharing the one GPU: the small detector leaves the GPU idle while the CPUs augment, so
P jobs finish in about the time of one). A job's model does not depend on P: its batches depend
on its seed alone (synthgen.evaluate.train). ``--pack MiB`` then moves the models into tar files
of at most that size (``models_K.tar``), since a device call brings back only a few files.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
import types
from dataclasses import dataclass
from typing import Any, List

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
PYTHON = os.path.join(HERE, "..", "..", "python")


def _import_evaluate() -> None:
    """synthgen.evaluate without synthgen's compiled core, when the core is missing."""
    sys.path.insert(0, PYTHON)
    try:
        if os.environ.get("SYNTHGEN_REMOTE_STANDIN") != "1":  # 1: use the stand-in (to test it)
            import synthgen._core  # noqa: F401  (the whole synthgen is there)
            return
    except ImportError:
        pass
    for k in [k for k in sys.modules if k == "synthgen" or k.startswith("synthgen.")]:
        del sys.modules[k]
    pkg = types.ModuleType("synthgen")
    pkg.__path__ = [os.path.join(PYTHON, "synthgen")]
    core = types.ModuleType("synthgen._core")

    class SynthgenError(Exception):
        pass

    core.SynthgenError = SynthgenError
    core.__getattr__ = _missing  # any other name: ImportError, as without the core
    pkg._core = core
    sys.modules["synthgen"] = pkg
    sys.modules["synthgen._core"] = core


def _missing(name: str) -> Any:
    raise AttributeError(name)


@dataclass
class Sample:
    image: str
    boxes: Any
    classes: List[str]
    ignore: Any
    source: str = ""
    where: str = ""


def samples(rows, root: str, source: str = "") -> List[Sample]:
    return [Sample(os.path.join(root, r[0]), np.asarray(r[1], np.float64).reshape(-1, 4), list(r[2]),
                   np.asarray(r[3], bool).reshape(-1), source, r[0]) for r in rows]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("jobs")
    ap.add_argument("--root", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--device", default="cuda")
    ap.add_argument("--workers", type=int, default=8)
    ap.add_argument("--only", default="")
    ap.add_argument("--parallel", type=int, default=1)
    ap.add_argument("--results", default="results.json")
    ap.add_argument("--pack", type=float, default=0.0, help="pack the models into tar files of at most this many MiB")
    a = ap.parse_args(argv)
    if a.parallel > 1:
        return _parallel(a)
    _import_evaluate()
    from synthgen.evaluate import augment as A
    from synthgen.evaluate import train as T
    from synthgen.evaluate.detector import Detector
    from synthgen.evaluate.score import GroundTruth, score, format_table

    with open(a.jobs) as f:
        jobs = json.load(f)["jobs"]
    results = {}
    rpath = os.path.join(a.out, a.results)
    if os.path.exists(rpath):
        with open(rpath) as f:
            results = json.load(f)
    for job in jobs:
        name = job["name"]
        if a.only and name not in a.only.split(","):
            continue
        t0 = time.time()
        pools = {k: samples(v, a.root, k) for k, v in job["pools"].items()}
        opts = dict(job.get("options", {}))
        if "augment" in opts:
            opts["augment"] = A.Augment(**{k: tuple(v) if isinstance(v, list) else v for k, v in opts["augment"].items()})
        if "size" in opts:
            opts["size"] = tuple(opts["size"])
        if opts.get("backbone"):
            opts["backbone"] = os.path.join(a.root, opts["backbone"])
        o = T.TrainOptions(**opts, device=a.device, workers=a.workers, mix=job.get("mix"))
        init = Detector.from_file(os.path.join(a.root, job["init"])) if job.get("init") else None
        res = T.train(pools, job["classes"], o, model=init, progress=False,
                      log=lambda m: print(f"[{name}] {m}", flush=True))
        res.model.save(os.path.join(a.out, name + ".model"), metadata=res.manifest)
        if not job.get("test"):
            results[name] = {"manifest": res.manifest, "seconds": time.time() - t0,
                             "loss": [round(l["total"], 4) for l in res.losses[::10]]}
            with open(rpath, "w") as f:
                json.dump(results, f, indent=1)
            continue
        test = samples(job["test"], a.root)
        dets = T.detect_samples(res.model, test, device=a.device, batch=16)
        gt = {s.image: GroundTruth(s.boxes, s.classes, crowd=[c == "" for c in s.classes], ignore=s.ignore)
              for s in test}
        sc = score(gt, dets, bootstrap=1000)
        print(f"[{name}] {time.time() - t0:.0f} s\n" + format_table(sc), flush=True)
        rows = {f"{r.cls}/{r.bucket}": {"ap50": r.ap50, "ap50_ci": list(r.ap50_ci), "ap": r.ap, "ap_ci": list(r.ap_ci),
                                      "recall_at_01fppi": r.recall_at_fppi, "gt": r.n_gt} for r in sc.rows}
        results[name] = {"scores": rows, "manifest": res.manifest, "seconds": time.time() - t0,
                         "loss": [round(l["total"], 4) for l in res.losses[::10]]}
        with open(rpath, "w") as f:
            json.dump(results, f, indent=1)
    if a.pack:
        pack(a.out, a.pack)
    return 0


def _parallel(a) -> int:
    """``a.parallel`` processes of this script, the jobs dealt round-robin, their results merged
    into ``results.json``; a failed process fails the whole run (after the others finish)."""
    import subprocess

    with open(a.jobs) as f:
        names = [j["name"] for j in json.load(f)["jobs"]]
    if a.only:
        names = [n for n in names if n in a.only.split(",")]
    procs = []
    for i in range(a.parallel):
        mine = names[i::a.parallel]
        if not mine:
            continue
        cmd = [sys.executable, os.path.abspath(__file__), a.jobs, "--root", a.root, "--out", a.out, "--device",
               a.device, "--workers", str(max(0, a.workers // a.parallel)), "--only", ",".join(mine),
               "--results", f"results_{i}.json"]
        procs.append((i, subprocess.Popen(cmd)))
    failed = [i for i, p in procs if p.wait() != 0]
    merged = {}
    rpath = os.path.join(a.out, a.results)
    if os.path.exists(rpath):
        with open(rpath) as f:
            merged = json.load(f)
    for i, _ in procs:
        part = os.path.join(a.out, f"results_{i}.json")
        if os.path.exists(part):
            with open(part) as f:
                merged.update(json.load(f))
            os.remove(part)
    with open(rpath, "w") as f:
        json.dump(merged, f, indent=1)
    if failed:
        print(f"remote: the process(es) {failed} failed; results.json holds the jobs that finished", file=sys.stderr)
    if a.pack:
        pack(a.out, a.pack)
    return 1 if failed else 0


def pack(out: str, mib: float) -> List[str]:
    """Moves ``out``'s ``*.model`` files into ``models_K.tar`` files of at most ``mib`` MiB each
    (in name order; a model larger than that gets a tar of its own), numbered after any tars
    already there (a second pack never overwrites the first); returns the new tar files."""
    import tarfile

    models = sorted(f for f in os.listdir(out) if f.endswith(".model"))
    groups: List[List[str]] = []
    size = 0.0
    for m in models:
        n = os.path.getsize(os.path.join(out, m)) + 1536   # a tar header and padding
        if not groups or size + n > mib * 2**20 - 10240:   # the end-of-archive blocks
            groups.append([])
            size = 0.0
        groups[-1].append(m)
        size += n
    tars = []
    first = len([f for f in os.listdir(out) if f.startswith("models_") and f.endswith(".tar")])
    for k, g in enumerate(groups, start=first):
        t = os.path.join(out, f"models_{k}.tar")
        with tarfile.open(t, "w") as tf:
            for m in g:
                tf.add(os.path.join(out, m), arcname=m)
        for m in g:
            os.remove(os.path.join(out, m))
        tars.append(t)
    return tars


if __name__ == "__main__":
    sys.exit(main())
