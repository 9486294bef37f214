"""``synthgen run``: a scenario's frames -> a labelled dataset on disk.

Every file is written to a temporary name and renamed; the metadata is written last and
marks a frame complete, so ``--resume`` renders exactly the frames without it and a killed
run leaves no partial file under a final name. Frames go to an executor
(:mod:`synthgen.run.executors`: each worker gets the validated scenario once, a task only its
frame); a failed frame leaves its scene's change journal in ``failed/``; the dataset-level
files (``annotations/coco.json``, ``dataset.yaml``) are written at the end from the
per-frame metadata. The layout of the directory: :mod:`synthgen.outputs`.
"""
from __future__ import annotations

import glob
import os
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

from .. import outputs
from .._core import SynthgenError
from ..outputs.files import write_json
from ..outputs import split
from ..outputs.meta import completed_frames, frame_status, read_meta
from ..outputs.registry import frame_name
from .manifest import build_manifest, check_manifest, write_manifest
from ..scenario import check_inputs, load_scenario
from ..scenario.load import check_memory
from .executors import FRAME_TIMEOUT, DaskExecutor, LocalExecutor
from .task import journal_path, render_task

__all__ = ["run", "RunSummary", "remove_temporaries", "ABORT_AFTER"]

#: A run stops when this many frames failed with one and the same error before any succeeded.
ABORT_AFTER = 3


def remove_temporaries(out_dir: str) -> int:
    """Deletes temporary files left by an interrupted run; returns how many."""
    n = 0
    for p in glob.glob(os.path.join(out_dir, "*", ".*.tmp*")) + glob.glob(os.path.join(out_dir, ".*.tmp*")):
        try:
            os.unlink(p)
            n += 1
        except OSError:
            pass
    return n


def _camera_match(results) -> Dict[str, Any]:
    """Per camera-matching check, {frame: object ids} over the frames' results; ``cap_spp``."""
    out: Dict[str, Any] = {}
    for r in sorted(results, key=lambda r: r["frame"]):
        for check, ids in (r.get("camera_match") or {}).items():
            if check == "cap_spp":
                if ids:
                    out["cap_spp"] = ids
                continue
            out.setdefault(check, {})[r["frame"]] = ids
    return out


class RunSummary(dict):
    """frames, failures (frame, reason), mean seconds per frame and per stage (wall time:
    ``stage_s``; CPU time of the workers: ``stage_cpu_s``, ``non_render_fraction``); photo
    frames: ``camera_match``, per check camera matching failed, {frame: object ids}."""

    def text(self, debug: bool = False) -> str:
        """The summary; with ``debug``, each failed frame's traceback too."""
        lines = [f"frames rendered: {self['rendered']} (skipped as already complete: {self['skipped']}), "
                 f"failures: {len(self['failures'])}"]
        for f in self["failures"][:20]:
            lines.append(f"  frame {f['frame']}: {f['error']}")
            if f.get("journal"):
                lines.append(f"    its scene: synthgen replay {f['journal']}")
            if debug and f.get("traceback"):
                lines.append("    " + f["traceback"].rstrip().replace("\n", "\n    "))
        if self["rendered"]:
            st = ", ".join(f"{k[:-2]} {v:.3f}" for k, v in self["stage_s"].items())
            lines.append(f"mean seconds/frame: {self['mean_s_per_frame']:.3f} (per stage: {st}); "
                         f"wall {self['wall_s']:.1f} s, {self['frames_per_s']:.3f} frames/s")
            if "stage_cpu_s" in self:
                c = self["stage_cpu_s"]
                lines.append(f"mean CPU seconds/frame: {c['total_s']:.3f} (path tracing {c['render_s']:.3f}, other "
                             f"{c['other_s']:.3f}: {100 * self['non_render_fraction']:.1f}%)")
        dropped = self.get("dropped", [])
        if dropped:
            n = sum(len(d["objects"]) for d in dropped)
            lines.append(f"objects dropped (their placement limits not met after the retries): {n} in "
                         f"{len(dropped)} frame(s); the frames are kept without them"
                         + (" (placement.allow_drops)" if self.get("drops_allowed") else ""))
            for d in dropped[:10]:
                lines.append(f"  frame {d['frame']}: " + "; ".join(f"object {o['index']} ({o['class']}): "
                                                              f"{o['reason']}" for o in d["objects"]))
        cm = self.get("camera_match")
        if cm:
            lines.append(camera_match_line(cm))
        for f in self.get("incomplete", [])[:20]:
            lines.append(f"  frame {f['frame']} was incomplete and is rendered again: {f['reason']}")
        if self.get("aborted"):
            lines.append(self["aborted"])
        if self.get("interrupted"):
            left = self.get("requested", 0) - self.get("complete_requested", 0)
            lines.append(f"interrupted: {self['rendered']} frame(s) finished in this run, {self['complete']} complete "
                         f"in the directory and kept; the same command with --resume renders the {left} missing")
        return "\n".join(lines)


#: The camera-matching checks a frame's meta reports (background.camera_match.unmatched), in the
#: summary's words.
CAMERA_MATCH_CHECKS = (("render_noise", "render noise above the target"),
                       ("noise_loop", "noise loop not converged (3 %)"),
                       ("blur_clamp", "sharpness clamp hit"))


def camera_match_line(cm: Dict[str, Any]) -> str:
    """One line: per check, the objects and frames camera matching could not match (``cm``: the
    summary's ``camera_match``: per check, frame -> object ids; ``cap_spp``)."""
    parts = []
    for check, words in CAMERA_MATCH_CHECKS:
        frames = cm.get(check) or {}
        if frames:
            n = sum(len(v) for v in frames.values())
            extra = f" (sample cap {cm['cap_spp']} spp)" if check == "render_noise" and cm.get("cap_spp") else ""
            parts.append(f"{words} for {n} object(s) in {len(frames)} frame(s){extra}: frames "
                         + ", ".join(str(k) for k in sorted(frames)[:10]) + (" ..." if len(frames) > 10 else ""))
    return ("camera matching not reached (meta background.camera_match.unmatched): " + "; ".join(parts))


def run(scenario_path: str, out_dir: str, count: Optional[int] = None, workers: int = 1,
        scheduler: Any = None, resume: bool = False, only: Optional[Sequence[int]] = None,
        recycle: int = 200, progress: bool = True, threads: Optional[int] = None,
        overrides: Sequence[Tuple[str, Any]] = (), allow_extensions: bool = False,
        journal: bool = False, frame_timeout: Optional[float] = FRAME_TIMEOUT, isolate: bool = True) -> RunSummary:
    """Renders a scenario into ``out_dir`` (layout: :mod:`synthgen.outputs`); ``overrides``:
    (key path, value) pairs set in the scenario before validation (``--set``);
    ``allow_extensions``: consent to compile and run the scenario's C extensions; ``journal``:
    write every frame's change journal into ``journals/`` (a failed frame's always goes into
    ``failed/``: ``synthgen replay`` renders it again); ``frame_timeout``: seconds a frame may
    take before its worker is killed and the frame reported failed (None or 0: no limit; local
    workers only); ``isolate``: False renders the frames of one worker in this process (no
    protection from crashes and hangs, no time limit: for debuggers and tests). Worker processes
    are spawned: a script calling this needs multiprocessing's ``if __name__ == "__main__":``
    guard."""
    if not isolate and (workers > 1 or scheduler is not None):
        raise SynthgenError("--in-process (isolate=False) renders in this process: not with --workers above 1 or "
                            "--scheduler")
    sc = load_scenario(scenario_path, overrides, allow_extensions)  # validate before anything renders ...
    found: List[str] = []              # suspicious, not wrong (a photo's geometry)
    check_inputs(sc, found)            # ... and load every input file once (extensions' code: isolated)
    for w in list(sc.warnings) + found:  # valid, but likely not meant (a sky nothing exposes)
        print(f"warning: {w}", file=sys.stderr, flush=True)
    n = int(count) if count is not None else sc.count
    if scheduler is None:  # local workers share this machine's memory
        why = check_memory(*sc.resolution, workers=workers)
        if why:
            raise SynthgenError(f"{scenario_path}: {why}; use fewer --workers or a smaller resolution")
    frames = list(only) if only is not None else list(range(n))
    os.makedirs(out_dir, exist_ok=True)
    complete, broken = frame_status(out_dir)
    done = set(complete)
    if (done or broken) and not resume and only is None:
        raise SynthgenError(f"{out_dir} already holds {len(done) + len(broken)} frame(s); use --resume to complete "
                            f"it or choose another output directory")
    manifest = build_manifest(sc)
    check_manifest(out_dir, manifest, sorted(done | set(broken)))
    write_manifest(out_dir, manifest)
    removed = remove_temporaries(out_dir)
    for k in broken:  # incomplete: rendered again below (they are not in `done`)
        os.unlink(os.path.join(out_dir, "meta", frame_name(k) + ".json"))
    todo = [k for k in frames if not (resume and k in done)] if only is None else frames
    executor = (DaskExecutor(scheduler) if scheduler is not None
                else LocalExecutor(workers, recycle, isolate=isolate, frame_timeout=frame_timeout))
    if threads is None:  # cores / workers on this machine; a cluster's worker alone on its node: all of them
        threads = executor.default_threads()
    if sc.spec["render"]["threads"]:
        threads = sc.spec["render"]["threads"]
    results, failures = [], []
    interrupted = False
    t0 = time.perf_counter()
    bar = None
    if progress:
        try:
            from tqdm import tqdm

            bar = tqdm(total=len(todo), unit="frame", desc="synthgen", dynamic_ncols=True)
        except ImportError:
            bar = None
    aborted = ""
    try:
        out_abs = os.path.abspath(out_dir)
        for r in executor.map(render_task, (sc, out_abs, threads), todo,
                              options={"journal": True} if journal else {}, alone_options={"journal_first": True},
                              alone_journal=lambda k: journal_path(out_abs, k, True)):
            (results if r["ok"] else failures).append(r)
            if bar is not None:
                bar.update(1)
                if not r["ok"]:
                    bar.write(f"frame {r['frame']} failed: {r['error']}")
            if not results and len(failures) >= ABORT_AFTER and len({f["error"] for f in failures}) == 1:
                # The same error on every frame so far: not a frame's bad luck but the scenario.
                aborted = f"stopped after {len(failures)} frames failed with the same error and none succeeded"
                executor.shutdown()
                break
    except KeyboardInterrupt:
        interrupted = True
        executor.shutdown()
    finally:
        if bar is not None:
            bar.close()
        if scheduler is not None and not interrupted:
            executor.shutdown()
    wall = time.perf_counter() - t0
    if scheduler is None:
        # Local workers are gone: a worker killed (Ctrl-C, a time limit) may have been writing.
        remove_temporaries(out_dir)
    complete = completed_frames(out_dir)
    finished = [k for k in complete if k < n or only is not None]
    sp = sc.spec["split"]
    split.write_splits(out_dir, [read_meta(os.path.join(out_dir, "meta", frame_name(k) + ".json")) for k in finished],
                       sc.seed, sp["val"], sp["test"])
    outputs.finalize_dataset(out_dir, sc.spec["outputs"], sc.class_names, finished)
    stages: Dict[str, float] = {}
    for r in results:
        for k, v in r["timings"].items():
            stages[k] = stages.get(k, 0.0) + v
    m = max(1, len(results))
    cpu, render_cpu = stages.pop("cpu_s", 0.0), stages.pop("render_cpu_s", 0.0)
    summary = RunSummary(
        rendered=len(results), skipped=len(frames) - len(todo),
        failures=[{"frame": f["frame"], "error": f["error"], "traceback": f.get("traceback", ""),
                   "journal": f.get("journal", "")} for f in failures],
        wall_s=wall, frames_per_s=len(results) / wall if wall > 0 else 0.0,
        mean_s_per_frame=stages.get("total_s", 0.0) / m,
        stage_s={k: v / m for k, v in stages.items() if k != "total_s"},
        # CPU seconds per frame in the workers (every thread): the whole frame, its path tracing
        # and the rest (scene set-up, layout checks, labels, writing); the rest's share of it.
        stage_cpu_s={"total_s": cpu / m, "render_s": render_cpu / m, "other_s": (cpu - render_cpu) / m},
        non_render_fraction=(cpu - render_cpu) / cpu if cpu > 0 else 0.0,
        interrupted=interrupted, temporaries_removed=removed, complete=len(complete),
        requested=len(frames), complete_requested=len(set(frames) & set(complete)),
        incomplete=[{"frame": k, "reason": r} for k, r in broken.items()], aborted=aborted,
        dropped=sorted(({"frame": r["frame"], "objects": r["dropped"]} for r in results if r.get("dropped")),
                       key=lambda d: d["frame"]),
        drops_allowed=bool(sc.spec["placement"]["allow_drops"]),
        camera_match=_camera_match(results),
        task_bytes=executor.task_bytes, shared_bytes=executor.shared_bytes)
    write_json(os.path.join(out_dir, "run_summary.json"), dict(summary))
    return summary
