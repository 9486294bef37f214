"""Speed against accuracy (``synthgen bench``): PSNR against render time of synthgen's sampling
methods and of peer renderers, each against a converged image of the same renderer.

Every method renders each scene at a ladder of budgets (samples per pixel); a run's time is
its wall time (see :data:`TIME_DEFINITIONS`), its error the PSNR of
:func:`synthgen.post.quality.psnr` (linear RGB clamped to [0, 1], peak 1) against a
``ref_spp``-sample uniform render of the same renderer (cached). The time to reach
:data:`TARGET_DB` is interpolated in log-time between the two budgets that bracket it.
"""
from __future__ import annotations

import json
import math
import os
import statistics
import tempfile
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..post.quality import psnr
from . import peers
from .scenes import CBOX_DIR, build_spec, spec_digest, synthgen_render

#: Scenes of ``synthgen bench``: the Cycles peer scenes (bench/vs_cycles.py) and Embree's
#: tutorial Cornell box (the only scene Embree's ``pathtracer`` renders that synthgen rebuilds).
SCENES = ("cbox", "materials", "sunlit", "embree_cbox")
#: The PSNR whose reaching time is compared (dB).
TARGET_DB = 35.0
REF_SEED = 1_000_003

TIME_DEFINITIONS = {
    "synthgen": "in process: the scene's API calls + commit() + the whole Scene.render() call "
                "(BVH build, path tracing, adaptive rounds, a denoiser if the call runs one)",
    "cycles": "bpy.ops.render.render() wall time inside Blender (scene sync, BVH build, path tracing, "
              "adaptive sampling); not Blender's start-up, the Python scene construction or the EXR write",
    "embree": "pathtracer process wall time minus its start-up (median of three 1x1-pixel 1-spp runs: "
              "process start, scene load, BVH build, image write)",
}

#: Which peer renders which scene, or why it cannot.
PEER_SCENES = {
    "cycles": {"cbox": None, "materials": None, "sunlit": None,
               "embree_cbox": "not mapped: the Cycles spec builder has no description of Embree's OBJ/MTL box"},
    "embree": {"cbox": "not mapped: Embree's pathtracer renders its own tutorial scenes (embree_cbox only)",
               "materials": "not mapped: Embree's pathtracer renders its own tutorial scenes (embree_cbox only)",
               "sunlit": "not mapped: Embree's pathtracer renders its own tutorial scenes (embree_cbox only)",
               "embree_cbox": None},
}


@dataclass
class Options:
    """The settings of one benchmark invocation (the command's options)."""
    scenes: Sequence[str] = ("cbox", "materials", "sunlit", "embree_cbox")
    out_dir: str = os.path.join("out", "bench")
    budgets: Sequence[int] = (1, 2, 4, 8, 16, 32, 64, 256, 1024)
    width: int = 256
    height: int = 192
    threads: int = 2
    ref_spp: int = 4096
    ref_dir: Optional[str] = None  # default: out_dir/references
    chart: Optional[str] = None  # default: out_dir/speed_accuracy.png
    noise_threshold: float = 0.01
    cycles_threshold: float = 0.01
    cycles_time_limits: Sequence[float] = ()
    runs: int = 1
    peers: bool = True
    quick: bool = False
    say: Callable[[str], None] = print


@dataclass(frozen=True)
class Method:
    """One curve of the chart: a renderer and how a budget becomes its settings."""
    name: str
    renderer: str  # "synthgen", "cycles" or "embree"
    doc: str
    ladder: Callable[[Options], List[Tuple[str, Dict[str, Any]]]]  # [(budget label, settings)]


def _spp_ladder(extra: Callable[[int, Options], Dict[str, Any]],
               least: int = 1) -> Callable[[Options], List[Tuple[str, Dict[str, Any]]]]:
    """Budgets of `least` spp and more (the denoiser needs 2: its two half-sample images)."""
    return lambda o: [(f"{b} spp", dict(spp=int(b), **extra(int(b), o))) for b in o.budgets if int(b) >= least]


def _cycles_ladder(o: Options) -> List[Tuple[str, Dict[str, Any]]]:
    common = {"adaptive_sampling": True, "adaptive_threshold": float(o.cycles_threshold)}
    if o.cycles_time_limits:
        return [(f"{t:g} s", dict(spp=int(o.ref_spp), time_limit=float(t), **common)) for t in o.cycles_time_limits]
    return [(f"{b} spp", dict(spp=int(b), **common)) for b in o.budgets]


#: The methods, in the order of the table and the chart's legend.
METHODS: Tuple[Method, ...] = (
    Method("uniform", "synthgen", "spp = the budget, every pixel", _spp_ladder(lambda b, o: {})),
    Method("adaptive", "synthgen", "adaptive sampling: max_spp = the budget, noise_threshold (default 0.01)",
           _spp_ladder(lambda b, o: {"max_spp": b, "noise_threshold": float(o.noise_threshold)})),
    Method("adaptive+denoise", "synthgen", "adaptive as above, then the denoiser (render(..., denoise=True))",
           _spp_ladder(lambda b, o: {"max_spp": b, "noise_threshold": float(o.noise_threshold), "denoise": True},
                       least=2)),
    Method("cycles", "cycles", "Blender Cycles CPU, its adaptive sampling: samples = the budget as the maximum, "
           "adaptive_threshold (default 0.01, 0 = Cycles' automatic); or time_limit budgets", _cycles_ladder),
    Method("embree", "embree", "Embree's tutorial pathtracer, spp = the budget (no adaptive sampling)",
           _spp_ladder(lambda b, o: {})),
)


@dataclass
class Run:
    """One render of one method at one budget."""
    scene: str
    method: str
    budget: str
    seconds: float
    spp: float
    psnr_db: float
    times: Dict[str, float] = field(default_factory=dict)


class Unavailable(Exception):
    """A method cannot run here (missing program, feature not built yet)."""


# ---------------------------------------------------------------------------------------------
# Time to the target


def time_to_target(points: Sequence[Tuple[float, float]], target: float = TARGET_DB) -> Tuple[Optional[float], str]:
    """Time at which a method reaches ``target`` dB, from its (seconds, PSNR) points in budget
    order: interpolated linearly in log(seconds) between the first point at or above the target
    and the one before it (status "interpolated"); the first point's time when that one is
    already at the target (status "at_first_budget": an upper bound); (None, "not_reached")."""
    for i, (t, p) in enumerate(points):
        if p >= target:
            if i == 0:
                return float(t), "at_first_budget"
            t0, p0 = points[i - 1]
            f = (target - p0) / (p - p0)
            return float(math.exp(math.log(t0) + f * (math.log(t) - math.log(t0)))), "interpolated"
    return None, "not_reached"


def format_time_to_target(value: Optional[float], status: str) -> str:
    if value is None:
        return "not reached"
    return f"<= {value:.3g} s" if status == "at_first_budget" else f"{value:.3g} s"


def speedup_vs_cycles(ttt: Dict[str, Dict[str, Tuple[Optional[float], str]]]) -> Tuple[float, List[str]]:
    """Geometric mean over scenes of Cycles' time to the target / synthgen's best method's time
    (the smallest of its methods'). A scene counts only when both times are interpolated
    between bracketing budgets; scenes without a Cycles run, where either did not reach the
    target or reached it at its first budget are left out (listed in the notes). NaN when no
    scene counts."""
    logs, notes = [], []
    for scene, by_method in ttt.items():
        cy = by_method.get("cycles")
        sg = [(v, s, m) for m, (v, s) in by_method.items() if _renderer(m) == "synthgen" and v is not None]
        if cy is None:
            notes.append(f"{scene}: no Cycles run")
            continue
        if cy[0] is None or not sg:
            notes.append(f"{scene}: {'Cycles' if cy[0] is None else 'synthgen'} did not reach {TARGET_DB:g} dB")
            continue
        v, s, m = min(sg)
        if s != "interpolated" or cy[1] != "interpolated":
            who = "Cycles" if cy[1] != "interpolated" else f"synthgen {m}"
            notes.append(f"{scene}: left out, {who} reached {TARGET_DB:g} dB at its first budget (no bracket: "
                         "add a smaller budget)")
            continue
        logs.append(math.log(cy[0] / v))
        notes.append(f"{scene}: Cycles {cy[0]:.3g} s / synthgen {m} {v:.3g} s = {cy[0] / v:.3f}")
    return (math.exp(sum(logs) / len(logs)) if logs else math.nan), notes


def _renderer(method: str) -> str:
    return {m.name: m.renderer for m in METHODS}[method]


# ---------------------------------------------------------------------------------------------
# Renders


class SceneRunner:
    """Renders one scene with each renderer, and their cached converged references."""

    def __init__(self, name: str, opts: Options, workdir: str, blender: Optional[str], pathtracer: Optional[str]):
        self.name, self.o, self.work = name, opts, workdir
        self.blender, self.pathtracer = blender, pathtracer
        self.spec: Optional[dict] = None
        self.notes: List[str] = []
        self._embree_startup: Optional[float] = None
        if name == "embree_cbox":
            if not os.path.isfile(os.path.join(peers.EMBREE_MODELS, "cornell_box.obj")):
                raise Unavailable(f"Embree's tutorial models not found in {peers.EMBREE_MODELS} (Debian embree-tools)")
            self.max_depth = peers.EMBREE_PATH_LENGTH + 1
            self.digest = f"embree-L{peers.EMBREE_PATH_LENGTH}"
        else:
            if name == "cbox" and not os.path.isdir(CBOX_DIR):
                raise Unavailable(f"shared assets not found: {CBOX_DIR}")
            self.spec = build_spec(name, opts.width, opts.height)
            if self.spec.get("skip"):
                raise Unavailable("none of the synthgen materials coated/conductor/dielectric exist yet")
            self.notes = list(self.spec.get("notes", []))
            self.max_depth = int(self.spec["max_depth"])
            self.digest = spec_digest(self.spec)

    # -- one render per renderer: (rgb, seconds, mean spp, timings)

    def synthgen(self, settings: Dict[str, Any], seed: int) -> Tuple[np.ndarray, float, float, dict]:
        kw = dict(settings)
        spp = int(kw.pop("spp"))
        try:
            if self.spec is None:
                rgb, t = peers.synthgen_embree_cbox(self.o.width, self.o.height, spp, seed, self.o.threads, **kw)
            else:
                rgb, t = synthgen_render(self.spec, spp, seed, self.o.threads, **kw)
        except TypeError as e:
            # pybind11 lists the accepted signature before "Invoked with": keys missing from it
            # are settings this build does not have (e.g. denoise before the denoiser exists).
            accepted = str(e).split("Invoked with")[0]
            bad = [k for k in kw if f"{k}:" not in accepted and f"{k}=" not in accepted]
            if bad:
                raise Unavailable(f"Scene.render has no setting {', '.join(bad)} in this build (TypeError)") from None
            raise
        return rgb, t["render_call_total_s"], t["mean_spp"], t

    def cycles(self, settings: Dict[str, Any], seed: int, tag: str) -> Tuple[np.ndarray, float, float, dict]:
        if self.blender is None:
            raise Unavailable("blender not found on PATH")
        why = PEER_SCENES["cycles"][self.name]
        if why:
            raise Unavailable(why)
        s = dict(self.spec, seed=seed, threads=self.o.threads, output=os.path.join(self.work, f"{tag}.exr"), **settings)
        rgb, t = peers.run_cycles(s, self.work, tag, self.blender)
        return rgb, t["render_s"], float(settings["spp"]), t

    def embree(self, settings: Dict[str, Any], seed: int, tag: str) -> Tuple[np.ndarray, float, float, dict]:
        if self.pathtracer is None:
            raise Unavailable("Embree's pathtracer not found (Debian embree-tools)")
        why = PEER_SCENES["embree"][self.name]
        if why:
            raise Unavailable(why)
        if self._embree_startup is None:
            self._embree_startup = peers.pathtracer_startup(self.pathtracer, self.o.threads, self.work)
        rgb, t = peers.run_pathtracer(self.pathtracer, self.o.width, self.o.height, int(settings["spp"]),
                                      self.o.threads, self.work, self._embree_startup)
        return rgb, t["render_s"], float(settings["spp"]), t

    def render(self, method: Method, settings: Dict[str, Any], seed: int, tag: str) -> Tuple[np.ndarray, float, float, dict]:
        if method.renderer == "synthgen":
            return self.synthgen(settings, seed)
        if method.renderer == "cycles":
            return self.cycles(settings, seed, tag)
        return self.embree(settings, seed, tag)

    # -- converged references, rendered once and cached

    def reference(self, renderer: str) -> np.ndarray:
        from .._core import __version__
        from ..outputs.files import write_exr

        o = self.o
        base = f"{self.name}_{o.width}x{o.height}_d{self.max_depth}_{o.ref_spp}spp_{self.digest}"
        prefix = {"synthgen": f"synthgen-{__version__}", "cycles": "cycles", "embree": "embree"}[renderer]
        path = os.path.join(o.ref_dir, f"{prefix}_{base}.exr")
        if os.path.exists(path):
            o.say(f"  reference {renderer} {o.ref_spp} spp: cached {path}")
            return peers.read_exr(path)
        os.makedirs(o.ref_dir, exist_ok=True)
        t0 = time.perf_counter()
        if renderer == "synthgen":
            rgb = self.synthgen({"spp": o.ref_spp}, REF_SEED)[0]
        elif renderer == "cycles":
            # A converged image of Cycles itself: uniform sampling (adaptive sampling off).
            rgb = self.cycles({"spp": o.ref_spp}, REF_SEED, f"{self.name}_cycles_ref")[0]
        else:
            rgb = self.embree({"spp": o.ref_spp}, REF_SEED, f"{self.name}_embree_ref")[0]
        write_exr(path, rgb)
        o.say(f"  reference {renderer} {o.ref_spp} spp: rendered in {time.perf_counter() - t0:.1f} s -> {path}")
        return rgb


# ---------------------------------------------------------------------------------------------
# The benchmark


def run_benchmark(o: Options) -> Dict[str, Any]:
    """Runs every method on every scene; writes the chart, the table and results.json to
    ``o.out_dir``; returns {"runs", "time_to_target", "speedup", "notes", "skipped"}.
    The caller prints the last line (:func:`last_line`)."""
    o.ref_dir = os.path.abspath(o.ref_dir or os.path.join(o.out_dir, "references"))
    o.chart = o.chart or os.path.join(o.out_dir, "speed_accuracy.png")
    os.makedirs(o.out_dir, exist_ok=True)
    blender = peers.find_blender() if o.peers else None
    pathtracer = peers.find_pathtracer() if o.peers else None
    say = o.say
    say(f"settings: {o.width}x{o.height}, budgets {','.join(map(str, o.budgets))} spp, {o.threads} threads, "
        f"{o.runs} run(s) per point (median time), references {o.ref_spp} spp in {o.ref_dir}")
    if not o.peers:
        say("peers: skipped (--no-peers)")
    else:
        say(f"peers: Cycles {'= ' + blender if blender else 'skipped (blender not found on PATH)'}; "
            f"Embree pathtracer {'= ' + pathtracer if pathtracer else 'skipped (pathtracer not found: Debian embree-tools)'}")
    for r, d in TIME_DEFINITIONS.items():
        say(f"time [{r}]: {d}")
    runs: List[Run] = []
    skipped: Dict[str, str] = {}  # method -> why (the first reason seen)
    ttt: Dict[str, Dict[str, Tuple[Optional[float], str]]] = {}
    with tempfile.TemporaryDirectory(prefix="synthgen_bench_") as work:
        for name in o.scenes:
            try:
                sr = SceneRunner(name, o, work, blender, pathtracer)
            except Unavailable as e:
                say(f"scene {name}: skipped ({e})")
                continue
            say(f"scene {name}: max_depth {sr.max_depth}")
            for note in sr.notes:
                say(f"  note [{name}]: {note}")
            refs: Dict[str, np.ndarray] = {}
            ttt[name] = {}
            for m in METHODS:
                if m.renderer != "synthgen" and not o.peers:
                    continue
                if m.name in skipped and m.renderer == "synthgen":
                    continue
                points: List[Tuple[float, float]] = []
                try:
                    for label, settings in m.ladder(o):
                        times, img, spp, t = [], None, 0.0, {}
                        for k in range(o.runs):
                            img, secs, spp, t = sr.render(m, settings, seed=1 + k, tag=f"{name}_{m.name}")
                            times.append(secs)
                        if m.renderer not in refs:
                            refs[m.renderer] = sr.reference(m.renderer)
                        secs = statistics.median(times)
                        db = psnr(img, refs[m.renderer], 1.0)
                        runs.append(Run(name, m.name, label, secs, spp, db,
                                        {k: v for k, v in t.items() if isinstance(v, (int, float))}))
                        points.append((secs, db))
                        say(f"  {name} {m.name:<16} {label:>9}: {secs:8.3f} s  {spp:8.1f} spp  {db:6.2f} dB")
                except Unavailable as e:
                    say(f"  {name} {m.name}: skipped ({e})")
                    skipped.setdefault(m.name, str(e))
                    continue
                ttt[name][m.name] = time_to_target(points)
    speedup, notes = speedup_vs_cycles(ttt)
    if "cycles" not in skipped and (not o.peers or blender is None):
        skipped["cycles"] = "--no-peers" if not o.peers else "blender not found on PATH"
    write_table(os.path.join(o.out_dir, "benchmarks_table.md"), runs, ttt, o)
    write_chart(o.chart, runs, o)
    result = {"runs": [r.__dict__ for r in runs], "time_to_target": ttt, "speedup": speedup, "notes": notes,
              "skipped": skipped, "target_db": TARGET_DB, "time_definitions": TIME_DEFINITIONS,
              "options": {k: v for k, v in o.__dict__.items() if k != "say"}}
    with open(os.path.join(o.out_dir, "results.json"), "w") as f:
        json.dump(result, f, indent=1, default=str)
        f.write("\n")
    say(f"time to {TARGET_DB:g} dB (interpolated in log-time between the bracketing budgets; '<=': "
        "reached at the first budget):")
    for scene, by_method in ttt.items():
        say(f"  {scene}: " + "; ".join(f"{m} {format_time_to_target(*v)}" for m, v in by_method.items()))
    for note in notes:
        say(f"  speedup: {note}")
    say(f"wrote {os.path.join(o.out_dir, 'benchmarks_table.md')}, {o.chart}, {os.path.join(o.out_dir, 'results.json')}")
    return result


def last_line(speedup: float) -> str:
    """The command's last line (``nan`` when no scene has both a Cycles and a synthgen time)."""
    return f"time_to_35db_speedup_vs_cycles={'nan' if math.isnan(speedup) else f'{speedup:.3f}'}"


def write_table(path: str, runs: Sequence[Run], ttt: Dict[str, Dict[str, Tuple[Optional[float], str]]],
                o: Options) -> None:
    """Markdown: one row per scene, method and budget; then the time to the target per scene."""
    lines = [f"<!-- synthgen bench: {o.width}x{o.height}, {o.threads} threads, references {o.ref_spp} spp -->", "",
             "| scene | method | budget | seconds | spp | PSNR (dB) |", "|---|---|---|---|---|---|"]
    for r in runs:
        lines.append(f"| {r.scene} | {r.method} | {r.budget} | {r.seconds:.3f} | {r.spp:.1f} | {r.psnr_db:.2f} |")
    methods = [m.name for m in METHODS if any(m.name in v for v in ttt.values())]
    lines += ["", f"Time to {TARGET_DB:g} dB:", "", "| scene | " + " | ".join(methods) + " |",
              "|---|" + "---|" * len(methods)]
    for scene, by_method in ttt.items():
        cells = [format_time_to_target(*by_method[m]) if m in by_method else "-" for m in methods]
        lines.append(f"| {scene} | " + " | ".join(cells) + " |")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_chart(path: str, runs: Sequence[Run], o: Options) -> None:
    """PNG: per scene a panel of PSNR (dB) against seconds (log x), a curve per method, a
    dashed line at the target."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r.scene for r in runs))
    n = max(1, len(scenes))
    cols = min(n, 2)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.8 * rows), squeeze=False)
    styles = {m.name: s for m, s in zip(METHODS, ("o-", "s-", "D-", "^--", "v:"))}
    colours = {m.name: f"C{i}" for i, m in enumerate(METHODS)}  # the same colour in every panel
    for ax, scene in zip(axes.flat, scenes):
        for m in METHODS:
            pts = [(r.seconds, r.psnr_db) for r in runs if r.scene == scene and r.method == m.name]
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], styles[m.name], color=colours[m.name], label=m.name)
        ax.axhline(TARGET_DB, color="grey", linestyle="--", linewidth=1)
        ax.set_xscale("log")
        ax.set_title(scene)
        ax.set_xlabel("seconds")
        ax.set_ylabel("PSNR (dB)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    for ax in list(axes.flat)[len(scenes):]:
        ax.axis("off")
    if not scenes:
        axes.flat[0].text(0.5, 0.5, "no scene rendered", ha="center", va="center")
    fig.suptitle(f"synthgen bench: {o.width}x{o.height}, {o.threads} threads, PSNR vs each renderer's "
                 f"{o.ref_spp}-spp image", fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
