#!/usr/bin/env python3
"""Does the data work: trains the reference detector (synthgen.evaluate) on synthgen frames and
scores it on the real highway frames and plate photos of ../shared/realdata (docs/sim2real.md).

    python bench/sim2real.py --budget small              # CPU only, a smoke run: every key
    python bench/sim2real.py --budget full --phase render   # the renders (CPU, cached)
    python bench/sim2real.py --budget full --phase stage --jobs NAME,...  # files for the accelerator
    python bench/sim2real.py --budget full --phase report --models DIR    # score trained models

Prints ``KEY=value`` lines (AP50 with its bootstrap 95% interval as ``KEY_ci=[lo, hi]``):
``sim2real_car_ap50`` (cars inserted into the car-free frames + pure synthetic frames),
``sim2real_car_ap50_pure`` (pure synthetic frames only), ``paste_control_ap50`` (the inserted
cars as flat albedo silhouettes + the same pure frames), ``real_trained_ap50`` (the dev frames:
the ceiling), ``augment_gain_ap50_at_K`` (K real frames + synthgen frames made from them, against
the K frames alone; mean and sd over draws), ``sim2real_plate_ap50`` (EU plates; ``_us``: a
style never shown), and ``ablation_NAME_ap50`` beside ``ablation_NAME_render_cpu_s`` (inserted
frames only, one knob changed, seeds averaged).

One run at a time per cache (two would render into the same folders). Splits (bench/sim2real/splits.py): the test frames are fixed frame-number blocks; nothing within
200 frames of them trains. Renders are cached under ``--cache`` (default bench/.cache/sim2real)
by their scenario's text, so a run continues where one stopped.

Training runs here (``--device cpu`` or ``cuda`` if this machine has one) or, with ``--phase
stage``, is written as jobs for ``bench/sim2real/remote.py`` on the accelerator machine, whose
returned models ``--phase report --models DIR`` then scores here.
"""
from __future__ import annotations

import argparse
import functools
import glob
import hashlib
import json
import math
import os
import subprocess
import sys
import time
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(REPO, "python"))
sys.path.insert(0, HERE)

from sim2real import data, pure, splits  # noqa: E402  (bench/sim2real/, the package)

SHARED = os.path.abspath(os.path.join(REPO, "..", "shared", "realdata"))
HIGHWAY = os.path.join(SHARED, "cars_highway")
PLATES = os.path.join(SHARED, "plates_openalpr")
BACKBONE = os.path.join(SHARED, "backbones", "shufflenetv2_x0.5_imagenet.pth")

#: The highway rig (bench/sim2real/highway_rig.yaml) for the pure synthetic camera.
RIG = {"fov_x": 90.0, "camera_height": 2.1, "horizon": 175.0, "distortion": [-0.223, 0.045, 0.0, 0.0, 0.0]}

BUDGETS: Dict[str, Dict[str, Any]] = {
    # CPU only, <= 30 minutes on 2 cores: a smoke run of every experiment and key
    "small": dict(inserted=12, pure=8, spp=4, augment_per_frame=1, augment_spp=2, ks=(10, 25, 50), draws=2,
                  plates=8, ablation_frames=6, ablation_seeds=(0, 1), spps=(4, 16, 64), steps=12, batch=2,
                  test_every=3, bootstrap=200, workers=0),
    # the accelerator for training; renders on the CPU, cached between sessions
    "full": dict(inserted=256, pure=256, spp=16, augment_per_frame=2, augment_spp=16, ks=(10, 25, 50), draws=5,
                 plates=256, ablation_frames=128, ablation_seeds=(0, 1), spps=(4, 16, 64), steps=1000, batch=32,
                 test_every=1, bootstrap=1000, workers=8),
}
# the full budget's renders, trained on the CPU (300 steps of 8, ~4 min a job on 2 cores): a
# figure without an accelerator, below the full budget's training
BUDGETS["medium"] = dict(BUDGETS["full"], steps=300, batch=8, workers=0)

#: Ablations: one knob of bench/sim2real/data.py changed from its default.
ABLATIONS = {"base": {}, "no_wear": {"wear": False}, "no_shadow_catcher": {"shadow_catcher": False},
             "no_camera_match": {"camera_match": False}, "no_denoise": {"denoise": False},
             "plain_light": {"lighting": "plain"}, "one_paint": {"paint_variety": False}, "one_car": {"vehicles": "one"}}
#: What each ablation changes (the table's words).
ABLATION_TEXT = {"base": "every knob at its default", "no_wear": "no wear", "no_shadow_catcher": "no shadow catcher",
                 "no_camera_match": "no camera matching", "no_denoise": "no denoising",
                 "plain_light": "plain light in place of sky/HDR", "one_paint": "one paint",
                 "one_car": "one car in place of the library", "spp4": "4 spp", "spp16": "16 spp", "spp64": "64 spp"}

#: Mixing policies: the real frames' share is fixed (half of each batch).
MIX_REAL = {"real": 0.5, "negative": 0.5}
MIX_AUGMENTED = {"real": 0.5, "synthetic": 0.35, "negative": 0.15}


def say(msg: str) -> None:
    print(f"[sim2real {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------
# renders


def _cost(dataset: str) -> Dict[str, float]:
    """CPU seconds per frame of a render dataset, accumulated over its runs in cost.json (called
    after every run: a later ``--resume`` rewrites run_summary.json)."""
    # the render is CACHE/KIND/<hash>/data; a post step's dataset (paste_control, ...) sits beside it
    root = os.path.join(os.path.dirname(dataset), "data")
    summ = os.path.join(root, "run_summary.json")
    cost = os.path.join(root, "cost.json")
    c = {"frames": 0, "cpu_s": 0.0, "summary_mtime": 0.0}
    if os.path.isfile(cost):
        with open(cost) as f:
            c = json.load(f)
    if os.path.isfile(summ) and os.path.getmtime(summ) != c["summary_mtime"]:
        with open(summ) as f:
            s = json.load(f)
        n = int(s.get("rendered", 0))
        if n and "stage_cpu_s" in s:
            c["frames"] += n
            c["cpu_s"] += n * float(s["stage_cpu_s"]["total_s"])
        c["summary_mtime"] = os.path.getmtime(summ)
        with open(cost, "w") as f:
            json.dump(c, f)
    return c


def render_inserted(cache: str, name: str, n: int, frames: Sequence[str], *, seed: int, spp: int,
                    labels_csv: Optional[str] = None, **knobs) -> str:
    say(f"render {name}: {n} frames, spp {spp}, seed {seed} {knobs or ''}")
    with open(os.path.join(cache, "render.log"), "a") as log:
        out = data.render(os.path.join(cache, "inserted"), n, list(frames), seed=seed, spp=spp, labels_csv=labels_csv,
                          log=log, **knobs)
    _cost(out)   # now: the next --resume of the same render rewrites its summary
    return out


def _run_cached(cache: str, kind: str, stage: str, n: int) -> str:
    """``synthgen run`` of the scenario written at ``stage`` into CACHE/KIND/<hash of its
    text>/data (``--resume``: an interrupted render continues); returns the dataset."""
    with open(stage, "rb") as f:
        key = hashlib.sha256(f.read()).hexdigest()[:16]
    root = os.path.join(cache, kind, key)
    os.makedirs(root, exist_ok=True)
    os.replace(stage, os.path.join(root, "scenario.yaml"))
    out = os.path.join(root, "data")
    if os.path.isfile(os.path.join(out, "run_summary.json")):
        with open(os.path.join(out, "run_summary.json")) as f:
            s = json.load(f)
        if s.get("requested") == n and s.get("complete_requested") == n and not s.get("failures"):
            return out
    cmd = [sys.executable, "-m", "synthgen", "run", os.path.join(root, "scenario.yaml"), "-o", out, "-n", str(n),
           "--no-progress"] + (["--resume"] if os.path.isdir(out) else [])
    with open(os.path.join(cache, "render.log"), "a") as log:
        r = subprocess.run(["nice", "-n", "10"] + cmd, stdout=log, stderr=subprocess.STDOUT,
                           env=dict(os.environ, PYTHONPATH=os.path.join(REPO, "python")))
    # exit status 3: every frame written, some clutter that found no place left out (the
    # scenario allows drops; the run lists them)
    if r.returncode not in (0, 3):
        raise SystemExit(f"sim2real: the {kind} render failed (exit status {r.returncode}); see {cache}/render.log")
    _cost(out)
    return out


def render_pure(cache: str, n: int, *, seed: int, spp: int) -> str:
    say(f"render pure: {n} frames, spp {spp}, seed {seed}")
    stage = os.path.join(cache, "pure", "staging.yaml")
    os.makedirs(os.path.dirname(stage), exist_ok=True)
    pure.write_pure_scenario(stage, seed=seed, count=n, spp=spp, rig=RIG)
    return _run_cached(cache, "pure", stage, n)


def render_plates(cache: str, n: int, *, seed: int, spp: int) -> List[str]:
    """The plate close-ups (bench/sim2real/plates.py): half the frames with painted library cars,
    half with textured ones (two scenarios), cached by their text like the others."""
    from sim2real import plates

    out = []
    for k, kind in enumerate(plates.VEHICLES):
        count = n // 2 + (n % 2 if k == 0 else 0)
        say(f"render plates ({kind}): {count} frames, spp {spp}, seed {seed + k}")
        stage = os.path.join(cache, "plates", "staging.yaml")
        os.makedirs(os.path.dirname(stage), exist_ok=True)
        plates.write_plate_scenario(stage, seed=seed + k, count=count, spp=spp, vehicles=kind)
        out.append(_run_cached(cache, "plates", stage, count))
    return out


def backgrounds_of(dataset: str) -> Dict[str, str]:
    """Each rendered frame's image path -> the real photo it was made from."""
    out = {}
    meta_dir = os.path.join(dataset, "meta")
    if not os.path.isdir(meta_dir):
        meta_dir = os.path.join(os.path.dirname(dataset), "data", "meta")
    for m in sorted(glob.glob(os.path.join(meta_dir, "*.json"))):
        with open(m) as f:
            d = json.load(f)
        stem = os.path.splitext(os.path.basename(m))[0]
        out[os.path.join(dataset, "images", stem + ".png")] = os.path.realpath(d["background"]["path"])
    return out


# ---------------------------------------------------------------------------------------
# samples and jobs


@functools.lru_cache(maxsize=None)
def real_sets():
    from synthgen.evaluate import datasets

    labelled = datasets.read_real(os.path.join(HIGHWAY, "boxes.csv"), default_class="car")
    negatives = datasets.read_negatives(os.path.join(HIGHWAY, "negatives"))
    sp = splits.split([s.image for s in labelled], [s.image for s in negatives])
    by = {s.image: s for s in list(labelled) + list(negatives)}
    return {k: [by[p] for p in v] for k, v in sp.items()}, sp


def synthgen_samples(dataset: str, n: int, classes=("car",)) -> list:
    """Frames 0 .. n-1 of a rendered dataset (a cache rendered further for another budget holds
    more: frame k depends on k alone)."""
    from synthgen.evaluate import datasets

    out = [s for s in datasets.read_synthgen(dataset, classes=list(classes))
           if int(os.path.splitext(os.path.basename(s.image))[0]) < n]
    if len(out) != n:
        raise SystemExit(f"sim2real: {dataset} holds {len(out)} of the {n} frames asked for")
    return out


def _row(s) -> list:
    return [s.image, np.asarray(s.boxes).round(3).tolist(), list(s.classes), np.asarray(s.ignore, bool).tolist()]


def job(name: str, classes: List[str], pools: Dict[str, list], mix: Optional[Dict[str, float]], b: Dict[str, Any],
        seed: int = 0) -> Dict[str, Any]:
    return {"name": name, "classes": classes, "pools": {k: [_row(s) for s in v] for k, v in pools.items() if v},
            "mix": mix, "options": {"steps": b["steps"], "batch": b["batch"], "seed": seed, "backbone": BACKBONE,
                                    "warmup": min(100, max(1, b["steps"] // 10))}}


def contiguous_draw(dev: list, k: int, rng: np.random.Generator, block: int = 5) -> list:
    """K dev frames in contiguous blocks of ``block`` frames (in frame order), blocks drawn
    without overlap."""
    order = sorted(dev, key=lambda s: splits.frame_number(s.image))
    starts = list(range(0, len(order) - block + 1, block))
    chosen = rng.choice(len(starts), size=-(-k // block), replace=False)
    picked = [s for c in sorted(chosen) for s in order[starts[c]:starts[c] + block]]
    return picked[:k]


#: Experiment groups (``--groups``): which renders each needs and which jobs it makes.
GROUPS = ("car", "real", "augment", "ablation", "plate")


def build_jobs(budget: str, cache: str, render_only: bool = False,
               groups: Sequence[str] = GROUPS) -> List[Dict[str, Any]]:
    """Renders what the ``groups`` need (cached) and returns their training jobs."""
    b = BUDGETS[budget]
    real, _ = real_sets()
    bg = [s.image for s in real["backgrounds"]]
    n_aug = b["augment_per_frame"] * len(real["dev"])
    costs: Dict[str, Any] = {}
    cpath = os.path.join(cache, f"costs_{budget}.json")
    if os.path.isfile(cpath):
        with open(cpath) as f:
            costs = json.load(f)
    if "car" in groups:
        inserted = render_inserted(cache, "inserted", b["inserted"], bg, seed=0, spp=b["spp"])
        paste = render_inserted(cache, "paste", b["inserted"], bg, seed=0, spp=b["spp"], paste_control=True)
        pure_ds = render_pure(cache, b["pure"], seed=0, spp=b["spp"])
        costs.update(inserted=_cost(inserted), pure=_cost(pure_ds))
    if "augment" in groups:
        augment = render_inserted(cache, "augment", n_aug, [s.image for s in real["dev"]], seed=1,
                                  spp=b["augment_spp"], labels_csv=os.path.join(HIGHWAY, "boxes.csv"))
        costs.update(augment=_cost(augment))
    abl = {}
    if "ablation" in groups:
        for name, knobs in ABLATIONS.items():
            for seed in b["ablation_seeds"]:
                abl[(name, seed)] = render_inserted(cache, f"ablation {name}", b["ablation_frames"], bg,
                                                    seed=100 + seed, spp=b["spp"], **knobs)
        for spp in b["spps"]:
            if spp == b["spp"]:
                continue    # = base (the same scenario text): one render, one model; the report aliases it
            for seed in b["ablation_seeds"]:
                abl[(f"spp{spp}", seed)] = render_inserted(cache, f"ablation spp {spp}", b["ablation_frames"], bg,
                                                           seed=100 + seed, spp=spp)
        costs.update({f"ablation_{n}_s{s}": _cost(ds) for (n, s), ds in abl.items()})
    if "plate" in groups:
        plates_ds = render_plates(cache, b["plates"], seed=0, spp=b["spp"])
    with open(cpath, "w") as f:
        json.dump(costs, f)
    if render_only:
        return []
    C = ["car"]
    jobs = []
    if "car" in groups:
        S = {k: synthgen_samples(v, b["inserted"] if k != "pure" else b["pure"])
             for k, v in [("inserted", inserted), ("paste", paste), ("pure", pure_ds)]}
        jobs += [job("car", C, {"synthetic": S["inserted"] + S["pure"]}, None, b),
                 job("car_pure", C, {"synthetic": S["pure"]}, None, b),
                 job("paste_control", C, {"synthetic": S["paste"] + S["pure"]}, None, b),
                 job("inserted_only", C, {"synthetic": S["inserted"]}, None, b)]
    if "real" in groups:
        jobs.append(job("real_all", C, {"real": real["dev"], "negative": real["backgrounds"]}, MIX_REAL, b))
    aug_by_photo: Dict[str, list] = {}
    if "augment" in groups:
        made_from = backgrounds_of(augment)
        aug = synthgen_samples(augment, n_aug)
        for s in aug:
            aug_by_photo.setdefault(made_from[s.image], []).append(s)
        jobs.append(job("augmented_all", C, {"real": real["dev"], "synthetic": aug,
                                              "negative": real["backgrounds"]}, MIX_AUGMENTED, b))
    for k in b["ks"]:
        for d in range(b["draws"]):
            pick = contiguous_draw(real["dev"], k, np.random.default_rng([k, d]))
            if "real" in groups:
                jobs.append(job(f"real_k{k}_d{d}", C, {"real": pick, "negative": real["backgrounds"]}, MIX_REAL, b,
                                seed=d))
            if "augment" in groups:
                syn = [s for p in pick for s in aug_by_photo.get(os.path.realpath(p.image), [])]
                jobs.append(job(f"augmented_k{k}_d{d}", C, {"real": pick, "synthetic": syn,
                                                             "negative": real["backgrounds"]}, MIX_AUGMENTED, b,
                                seed=d))
    for (name, seed), ds in abl.items():
        jobs.append(job(f"ablation_{name}_s{seed}", C, {"synthetic": synthgen_samples(ds, b["ablation_frames"])},
                        None, b, seed=seed))
    if "plate" in groups:
        from synthgen.evaluate import datasets

        ps = [s for ds in plates_ds for s in datasets.read_synthgen(ds, classes=["plate"])]
        if not ps:
            raise SystemExit("sim2real: the plate renders hold no frames")
        jobs.append(job("plate", ["plate"], {"synthetic": ps}, None, b))
    with open(os.path.join(cache, f"jobs_{budget}.json"), "w") as f:
        json.dump({"jobs": jobs}, f)
    return jobs


# ---------------------------------------------------------------------------------------
# training and scoring


def train_local(jobs: List[Dict[str, Any]], models: str, device: str, workers: int) -> None:
    from sim2real import remote

    todo = [j for j in jobs if not os.path.isfile(os.path.join(models, j["name"] + ".model"))]
    if not todo:
        return
    path = os.path.join(models, "jobs_todo.json")
    with open(path, "w") as f:
        json.dump({"jobs": todo}, f)
    say(f"training {len(todo)} models on {device}")
    remote.main([path, "--root", "/", "--out", models, "--device", device, "--workers", str(workers)])


def unpack(models: str) -> None:
    """Extracts the ``models_K.tar`` files a device call brought back (remote.py ``--pack``)
    into ``models``; a model already there is left as it is."""
    import tarfile

    for t in sorted(glob.glob(os.path.join(models, "models_*.tar"))):
        with tarfile.open(t) as tf:
            for m in tf.getmembers():
                if not (m.isfile() and m.name.endswith(".model") and "/" not in m.name):
                    raise SystemExit(f"sim2real: {t} holds {m.name!r}, not a model file")
                if not os.path.isfile(os.path.join(models, m.name)):
                    tf.extract(m, models)


def score_models(budget: str, models: str, jobs: List[Dict[str, Any]]) -> Dict[str, Any]:
    from synthgen.evaluate import datasets
    from synthgen.evaluate.detector import Detector
    from synthgen.evaluate.score import score
    from synthgen.evaluate.train import detect_samples

    b = BUDGETS[budget]
    unpack(models)
    real, _ = real_sets()
    test = real["test"][::b["test_every"]]
    gt = datasets.ground_truth(test)
    out = {}
    for j in jobs:
        p = os.path.join(models, j["name"] + ".model")
        if not os.path.isfile(p):
            continue
        m = Detector.from_file(p)
        if j["classes"] == ["plate"]:
            for style in ("eu", "us"):
                ps = datasets.read_real(os.path.join(PLATES, style), classes=["plate"])
                ps = list(ps)[::b["test_every"]]
                sc = score(datasets.ground_truth(ps), detect_samples(m, ps), classes=["plate"],
                           bootstrap=b["bootstrap"], min_height=0)
                out[f"plate_{style}"] = sc.row("plate")
            continue
        sc = score(gt, detect_samples(m, test), classes=["car"], bootstrap=b["bootstrap"])
        out[j["name"]] = sc.row("car")
    return out


def _f(x: float) -> str:
    return "nan" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.3f}"


def report(budget: str, cache: str, rows: Dict[str, Any], seconds: float, figure: Optional[str] = None) -> None:
    b = BUDGETS[budget]

    def ap(name: str, key: str) -> None:
        r = rows.get(name)
        if r is None:
            print(f"{key}=nan")
            print(f"{key}_ci=[nan, nan]")
            return
        print(f"{key}={_f(r.ap50)}")
        print(f"{key}_ci=[{_f(r.ap50_ci[0])}, {_f(r.ap50_ci[1])}]")

    real, _ = real_sets()
    print(f"budget={budget}")
    print(f"test_frames={len(real['test'][::b['test_every']])}")
    print(f"train_steps={b['steps']}")
    print(f"train_batch={b['batch']}")
    ap("car", "sim2real_car_ap50")
    ap("car_pure", "sim2real_car_ap50_pure")
    ap("paste_control", "paste_control_ap50")
    ap("inserted_only", "inserted_only_ap50")
    ap("real_all", "real_trained_ap50")
    for k in b["ks"]:
        gains = [rows[f"augmented_k{k}_d{d}"].ap50 - rows[f"real_k{k}_d{d}"].ap50 for d in range(b["draws"])
                 if f"augmented_k{k}_d{d}" in rows and f"real_k{k}_d{d}" in rows]
        base = [rows[f"real_k{k}_d{d}"].ap50 for d in range(b["draws"]) if f"real_k{k}_d{d}" in rows]
        print(f"augment_gain_ap50_at_{k}={_f(float(np.mean(gains))) if gains else 'nan'}")
        print(f"augment_gain_ap50_at_{k}_sd={_f(float(np.std(gains, ddof=1))) if len(gains) > 1 else 'nan'}")
        print(f"augment_gain_ap50_at_{k}_draws={len(gains)}")
        print(f"real_only_ap50_at_{k}={_f(float(np.mean(base))) if base else 'nan'}")
    if "augmented_all" in rows and "real_all" in rows:
        print(f"augment_gain_ap50_all_dev={_f(rows['augmented_all'].ap50 - rows['real_all'].ap50)}")
    else:
        print("augment_gain_ap50_all_dev=nan")
    ap("plate_eu", "sim2real_plate_ap50")
    ap("plate_us", "sim2real_plate_ap50_us")
    costs = {}
    cpath = os.path.join(cache, f"costs_{budget}.json")
    if os.path.isfile(cpath):
        with open(cpath) as f:
            costs = json.load(f)
    from sim2real import ablations

    names = list(ABLATIONS) + [f"spp{s}" for s in b["spps"]]
    abl = ablations.table(rows, costs, names, b["ablation_seeds"], aliases={f"spp{b['spp']}": "base"})
    for a in abl:
        print(f"ablation_{a.name}_ap50={_f(a.ap50)}")
        print(f"ablation_{a.name}_ap50_ci=[{_f(a.ap50_ci[0])}, {_f(a.ap50_ci[1])}]")
        print(f"ablation_{a.name}_ap50_seeds=[{', '.join(_f(v) for v in a.seeds)}]")
        if a.name != "base":
            print(f"ablation_{a.name}_delta={_f(a.delta)}")
            print(f"ablation_{a.name}_delta_ci=[{_f(a.delta_ci[0])}, {_f(a.delta_ci[1])}]")
            print(f"ablation_{a.name}_effect={a.effect.replace(' ', '_')}")
        print(f"ablation_{a.name}_render_cpu_s={_f(a.cpu_s)}")
    if any(a.seeds for a in abl):
        say("ablations (" + budget + " budget):\n" + ablations.markdown(abl, ABLATION_TEXT))
        if figure:
            ablations.figure(abl, figure, f"{budget} budget: car AP50 (seed mean, 95% interval) against render cost")
            say(f"wrote {figure}")
    for name in ("inserted", "pure", "augment"):
        c = costs.get(name)
        print(f"render_cpu_s_per_frame_{name}=" + (_f(c["cpu_s"] / c["frames"]) if c and c["frames"] else "nan"))
    print(f"sim2real_seconds={seconds:.0f}")


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budget", choices=sorted(BUDGETS), default="small")
    ap.add_argument("--phase", choices=("all", "render", "stage", "report"), default="all")
    ap.add_argument("--cache", default=os.path.join(HERE, ".cache", "sim2real"))
    ap.add_argument("--models", default=None, help="trained models (default CACHE/models_BUDGET)")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--jobs", default="", help="only these jobs (names or fnmatch patterns, comma-separated)")
    ap.add_argument("--groups", default=",".join(GROUPS),
                    help=f"the experiment groups to render, train and score (comma-separated, of {', '.join(GROUPS)})")
    ap.add_argument("--figure", default=None,
                    help="report: write the ablations' AP50 against render cost here (docs/sim2real.png)")
    ap.add_argument("--split", action="store_true",
                    help="stage: pack the jobs into STAGE_TO/part0, part1, ... (one device call each)")
    ap.add_argument("--stage-to", default=os.path.join(REPO, ".device"), help="stage: the folder (git-ignored)")
    a = ap.parse_args(argv)
    if not os.path.isfile(os.path.join(HIGHWAY, "boxes.csv")):
        print("sim2real: ../shared/realdata is not here; nothing to measure", file=sys.stderr)
        return 2
    start = time.time()
    os.makedirs(a.cache, exist_ok=True)
    models = a.models or os.path.join(a.cache, f"models_{a.budget}")
    os.makedirs(models, exist_ok=True)
    groups = [g for g in a.groups.split(",") if g]
    bad = sorted(set(groups) - set(GROUPS))
    if bad:
        ap.error(f"--groups: unknown group(s) {bad} (groups: {', '.join(GROUPS)})")
    if a.phase == "render":
        build_jobs(a.budget, a.cache, render_only=True, groups=groups)
        return 0
    jobs = build_jobs(a.budget, a.cache, groups=groups)
    names = [n for n in a.jobs.split(",") if n]
    if names:
        import fnmatch

        jobs = [j for j in jobs if any(fnmatch.fnmatchcase(j["name"], n) for n in names)]
    if a.phase == "stage":
        from sim2real import stage

        stage.stage(jobs, os.path.abspath(a.stage_to), split=a.split)
        return 0
    if a.phase == "all":
        train_local(jobs, models, a.device, BUDGETS[a.budget]["workers"])
    rows = score_models(a.budget, models, jobs)
    report(a.budget, a.cache, rows, time.time() - start, a.figure)
    return 0


if __name__ == "__main__":
    sys.exit(main())
