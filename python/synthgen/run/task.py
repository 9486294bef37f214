"""The task every executor runs: one frame rendered and written by a worker process."""
from __future__ import annotations

import ctypes
import ctypes.util
import os
import time
import traceback
from typing import Any, Dict

from .. import outputs
from .._core import load_image_plugin
from ..frame import FrameRenderer
from ..scenario import Scenario

__all__ = ["render_task", "journal_path", "resident_bytes", "release_free_memory"]

_WORKER: Dict[str, Any] = {}


def resident_bytes() -> int:
    """This process's resident memory (Linux /proc/self/statm; 0 elsewhere)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def _libc_malloc_trim():
    """glibc's malloc_trim, or None (another C library)."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        trim = libc.malloc_trim
    except (OSError, AttributeError):
        return None
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return trim


_MALLOC_TRIM = _libc_malloc_trim()


def release_free_memory() -> None:
    """Gives the heap's free pages back to the system (glibc malloc_trim(0); nothing elsewhere).

    NOTE: glibc keeps memory freed by a frame in its arenas (one per thread that allocated:
    the render threads') and returns only the top of each heap by itself; a long run's frames,
    each freeing textures and buffers of different sizes, leave free pages spread over them that
    count as resident. malloc_trim(0) releases every free page of every arena (madvise
    MADV_DONTNEED; glibc >= 2.8), a few milliseconds per frame."""
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)


def journal_path(out_dir: str, frame: int, failed: bool) -> str:
    """Where a frame's journal goes: ``journals/`` (``--journal``) or ``failed/`` (a failure)."""
    return os.path.join(out_dir, "failed" if failed else "journals", outputs.frame_name(frame) + ".journal")


def _save_journal(fr: Any, path: str) -> str:
    """The frame's journal saved to ``path`` ("" when it cannot be: the failure stays reported)."""
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        fr.scene.save_journal(path)
        return path
    except Exception:  # noqa: BLE001 -- the frame's own error is what gets reported
        return ""


def render_task(scenario: Scenario, out_dir: str, frame: int, threads: int = 0, journal: bool = False,
                journal_first: bool = False) -> Dict[str, Any]:
    """Renders and writes one frame in the calling process, reusing this process's
    FrameRenderer for the same scenario. Workers receive the validated scenario itself
    (pickled), never a path they would read again. Returns {frame, ok, error, timings}: wall
    seconds per stage, and CPU seconds of the frame (``cpu_s``) and of its path tracing
    (``render_cpu_s``).

    The scene records its change journal from the frame's start (Scene.begin_journal): a frame
    that fails leaves it in ``failed/`` (``journal`` in the result: ``synthgen replay`` renders
    it again outside the run); ``journal`` writes it to ``journals/`` for every frame;
    ``journal_first`` writes it before each render (a frame rendered alone after a worker died:
    a crash leaves the journal of the render it happened in)."""
    fr = None
    try:
        key = (scenario.sha256, scenario.base_dir, threads)
        fr = _WORKER.get("renderer")
        if fr is None or _WORKER.get("key") != key:
            load_image_plugin()
            fr = FrameRenderer(scenario, threads)
            _WORKER.update(renderer=fr, key=key, frames=0)
        c0 = time.process_time()
        fr.scene.begin_journal()
        failed_path = journal_path(out_dir, frame, True)
        if journal_first:
            os.makedirs(os.path.dirname(failed_path), exist_ok=True)
            fr.scene.set_journal_autosave(failed_path)
        t0 = time.perf_counter()
        arrays, meta, timings = fr.render(frame)
        t1 = time.perf_counter()
        if journal_first:
            fr.scene.set_journal_autosave("")
            for p in (failed_path, failed_path + ".bin"):
                if os.path.exists(p):
                    os.unlink(p)
        if journal:
            _save_journal(fr, journal_path(out_dir, frame, False))
        outputs.write_frame(out_dir, frame, arrays, meta, fr.sc.spec["outputs"])
        timings["write_s"] = time.perf_counter() - t1
        timings["total_s"] = time.perf_counter() - t0
        _WORKER["frames"] += 1
        del arrays
        release_free_memory()
        # The frame's CPU time in this process, every thread's (the path tracer's: render_cpu_s).
        timings["cpu_s"] = time.process_time() - c0
        dropped = [{"index": o["index"], "class": o["class"], "reason": o["dropped"]}
                   for o in meta["objects"] if o.get("dropped")]
        # Photo frames: the objects camera matching could not match (meta background.camera_match).
        cm = (meta.get("background") or {}).get("camera_match") or {}
        unmatched = {}
        for o, checks in (cm.get("unmatched") or {}).items():
            for c in checks:
                unmatched.setdefault(c["check"], []).append(o)
        if unmatched:
            unmatched["cap_spp"] = (cm.get("sampling") or {}).get("cap_spp")
        return {"frame": frame, "ok": True, "timings": timings, "dropped": dropped, "pid": os.getpid(),
                "rss_bytes": resident_bytes(), "camera_match": unmatched}
    except Exception as e:  # reported per frame; the run goes on
        out = {"frame": frame, "ok": False, "error": f"{type(e).__name__}: {e}",
               "traceback": traceback.format_exc(), "pid": os.getpid()}
        if fr is not None and fr.scene.journaling:
            fr.scene.set_journal_autosave("")
            out["journal"] = _save_journal(fr, journal_path(out_dir, frame, True))
        return out
