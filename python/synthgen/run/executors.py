"""Executors: where frames are rendered. :class:`LocalExecutor` (worker processes on this
machine, recycled after ``recycle`` frames) and :class:`DaskExecutor` (a Dask cluster) run
the same task function (:func:`synthgen.run.task.render_task`), so a frame is the same
whichever executor renders it.

What travels: each worker receives the run's shared part (the validated scenario, the output
directory, the thread count) once -- as its initializer's argument, or scattered to every Dask
worker -- and per frame only the frame's number (:attr:`task_bytes` measures it).

A worker process that dies (a crash in native code, e.g. a user's C extension, or the kernel's
out-of-memory killer) takes only its frame: the frames in flight are rendered again one at a
time in a fresh process, and the one that kills its process again is reported failed
(``worker process died``) while the run goes on; finished frames are on disk already. A frame
that takes longer than ``frame_timeout`` seconds (a loop in a C extension) has its worker
killed and is rendered again alone with the same limit; timed out again, it is reported failed
(``timed out after N s``). With one worker, frames render in a worker process too (unless
``isolate=False``: in this process, as a debugger or a test's monkeypatch needs), so that a
crash or a hang never takes the run down and Ctrl-C (the parent terminates its workers) stops
the run at once.
"""
from __future__ import annotations

import os
import pickle
import signal
import socket
import time
from collections import deque
from typing import Any, Callable, Deque, Dict, Iterator, List, Optional, Sequence

__all__ = ["LocalExecutor", "DaskExecutor", "FRAME_TIMEOUT"]

#: The shared part of the run, set once per worker process.
_SHARED: Dict[str, Any] = {}


def _init_worker(shared: tuple) -> None:
    # Ctrl-C is handled by the parent, which then terminates the pool.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _SHARED["args"] = shared


def _run(fn: Callable, frame: int, options: Dict[str, Any]) -> Dict[str, Any]:
    """A frame in a worker: ``fn(*shared[:2], frame, *shared[2:], **options)``."""
    shared = _SHARED["args"]
    return fn(shared[0], shared[1], frame, *shared[2:], **options)


def _alone_worker(conn: Any, shared: tuple, fn: Callable, frame: int, options: Dict[str, Any]) -> None:
    """A frame in a process of its own: its result through `conn` (nothing when it dies)."""
    _init_worker(shared)
    conn.send(_run(fn, frame, options))
    conn.close()


#: Seconds a frame may take by default before its worker is killed (``frame_timeout``).
FRAME_TIMEOUT = 1800.0


def _timed_out(frame: int, seconds: float) -> Dict[str, Any]:
    return {"frame": frame, "ok": False, "pid": None,
            "error": f"TimedOut: frame {frame} timed out after {seconds:g} s, again when it was rendered alone (its "
                     "worker process was killed): a loop in native code (a C extension?) or a frame too slow for "
                     "the limit (--frame-timeout); the other frames are unaffected",
            "traceback": ""}


def _died(frame: int, exitcode: Optional[int], journal: str = "") -> Dict[str, Any]:
    from ..scene.extensions import exit_description

    how = exit_description(exitcode)
    return {"frame": frame, "ok": False, "pid": None,
            "error": f"WorkerDied: the worker process died while rendering frame {frame}{how}, again when the frame "
                     "was rendered alone: a crash in native code (a C extension?) or the out-of-memory killer; the "
                     "other frames are unaffected",
            "traceback": "", **({"journal": journal} if journal else {})}


def _share_cores(workers: int) -> int:
    """Render threads for each of `workers` processes on this machine: its cores shared among
    them; 0 (all cores) for a worker alone here (or none)."""
    return max(1, (os.cpu_count() or 1) // workers) if workers > 1 else 0


class LocalExecutor:
    """Frames on a pool of worker processes on this machine (one worker: a worker process too,
    unless ``isolate`` is False: in this process). Workers keep their scene across frames and
    are replaced after ``recycle`` frames, so memory cannot grow without bound. A frame longer
    than ``frame_timeout`` seconds (None or 0: no limit) has its worker killed; in this process
    (``isolate`` False) no limit applies."""

    def __init__(self, workers: int = 1, recycle: int = 200, isolate: bool = True,
                 frame_timeout: Optional[float] = FRAME_TIMEOUT):
        self.workers = max(1, int(workers))
        self.recycle = max(1, int(recycle))
        self.isolate = bool(isolate) or self.workers > 1
        self.frame_timeout = float(frame_timeout) if frame_timeout else 0.0
        self._pool: Any = None
        self._proc: Any = None  # a frame's own process (_alone)
        #: Bytes pickled per frame (the task: function reference, frame, options) and once per
        #: worker (the shared part), measured by the last map().
        self.task_bytes = 0
        self.shared_bytes = 0

    def default_threads(self) -> int:
        """Render threads per worker when none are asked: this machine's cores shared by the
        workers (0, all cores, for one worker)."""
        return _share_cores(self.workers)

    def _new_pool(self, workers: int, shared: tuple) -> Any:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        # NOTE: spawn, no fork of a process with TBB/Embree threads; max_tasks_per_child
        # (Python 3.11) replaces a worker after `recycle` frames.
        self._pool = ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn"), initializer=_init_worker,
                                         initargs=(shared,), max_tasks_per_child=self.recycle)
        return self._pool

    def map(self, fn: Callable, shared: tuple, frames: Sequence[int], options: Optional[Dict[str, Any]] = None,
            alone_options: Optional[Dict[str, Any]] = None,
            alone_journal: Optional[Callable[[int], str]] = None) -> Iterator[Dict[str, Any]]:
        """Results of ``fn(shared[0], shared[1], frame, *shared[2:], **options)`` per frame, in
        completion order. ``alone_options``: more keyword arguments of the frames rendered alone
        after a worker died (e.g. to write the frame's journal before rendering);
        ``alone_journal(frame)``: the journal such a frame leaves when its process dies again."""
        options = dict(options or {})
        self.shared_bytes = len(pickle.dumps(shared))
        self.task_bytes = len(pickle.dumps((_run, fn, frames[0] if frames else 0, options)))
        if not self.isolate:
            for k in frames:
                yield fn(shared[0], shared[1], k, *shared[2:], **options)
            return
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        limit = self.frame_timeout
        pending: Deque[int] = deque(frames)
        while pending:
            pool = self._new_pool(self.workers, shared)
            inflight: Dict[Any, int] = {}
            started: Dict[Any, float] = {}
            suspects: List[int] = []
            overdue: List[int] = []
            try:
                while (pending or inflight) and not suspects and not overdue:
                    # At most one frame per worker in flight: when a worker dies, only these
                    # frames can have killed it, and a frame's time starts when it is submitted.
                    while pending and len(inflight) < self.workers:
                        k = pending.popleft()
                        f = pool.submit(_run, fn, k, options)
                        inflight[f], started[f] = k, time.monotonic()
                    wait_s = max(0.0, min(started[f] for f in inflight) + limit - time.monotonic()) if limit else None
                    done, _ = wait(inflight, timeout=wait_s, return_when=FIRST_COMPLETED)
                    for f in done:
                        k = inflight.pop(f)
                        try:
                            r = f.result()
                        except BrokenProcessPool:
                            suspects.append(k)
                            continue
                        yield r
                    if limit:
                        now = time.monotonic()
                        overdue.extend(k for f, k in inflight.items() if now - started[f] >= limit)
                suspects.extend(k for k in inflight.values() if k not in overdue)
            except BaseException:
                self.shutdown()
                raise
            if overdue:  # a worker that does not finish its frame is killed with its pool
                self.shutdown()
            else:
                pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
            # Frames in flight when a worker died or was killed, rendered alone: the one that
            # kills its process (or times out) again is the culprit. Its journal was written
            # before the render (alone_options).
            for k in sorted(set(suspects) | set(overdue)):
                r = self._alone(fn, shared, k, {**options, **(alone_options or {})})
                if not r["ok"] and r["error"].startswith(("WorkerDied", "TimedOut")) and alone_journal is not None:
                    path = alone_journal(k)
                    if os.path.isfile(path):
                        r["journal"] = path
                yield r

    def _alone(self, fn: Callable, shared: tuple, frame: int, options: Dict[str, Any]) -> Dict[str, Any]:
        """Renders one frame in a fresh process of its own (not a pool: its exit status is
        known for certain): its result, or the report of its death."""
        import multiprocessing as mp

        ctx = mp.get_context("spawn")
        receive, send = ctx.Pipe(duplex=False)
        proc = ctx.Process(target=_alone_worker, args=(send, shared, fn, frame, options))
        self._proc = proc
        limit = self.frame_timeout
        try:
            proc.start()
            send.close()  # the child's end: a dead child leaves the pipe at end of file
            deadline = time.monotonic() + limit
            if not receive.poll(max(0.0, deadline - time.monotonic()) if limit else None):
                proc.kill()  # nothing came (not even the end of file of a death) by the deadline
                proc.join()
                return _timed_out(frame, limit)
            try:
                result = receive.recv()
            except EOFError:
                proc.join()
                return _died(frame, proc.exitcode)
            proc.join()
            return result
        except BaseException:
            if proc.is_alive():
                proc.kill()
            raise
        finally:
            receive.close()
            self._proc = None

    def shutdown(self) -> None:
        """Stops every worker now (SIGKILL: a worker busy in native code, or in a loop of a C
        extension, may not heed SIGTERM soon) and waits for them to be gone."""
        proc, self._proc = self._proc, None
        if proc is not None and proc.is_alive():
            proc.kill()
            proc.join()
        pool, self._pool = self._pool, None
        if pool is not None:
            procs = list((getattr(pool, "_processes", None) or {}).values())
            for p in procs:
                if p.is_alive():
                    p.kill()
            pool.shutdown(wait=False, cancel_futures=True)
            for p in procs:
                p.join()


def _run_dask(fn: Callable, shared: tuple, frame: int, options: Dict[str, Any]) -> Dict[str, Any]:
    return fn(shared[0], shared[1], frame, *shared[2:], **options)


class DaskExecutor:
    """Frames on a Dask distributed cluster (``address`` of a scheduler, or a
    ``distributed.Client``). Workers keep their scene across frames like local ones; the shared
    part is scattered to every worker once (a task carries its key and the frame number). A task
    whose workers died (Dask retries it on others) is reported failed, and the run goes on."""

    def __init__(self, address: Any):
        from distributed import Client

        self.client = address if isinstance(address, Client) else Client(address)
        self._own = not isinstance(address, Client)
        self.task_bytes = 0
        self.shared_bytes = 0

    def default_threads(self) -> int:
        """Render threads per worker when none are asked. Workers on this machine (a
        LocalCluster) share its cores; a worker elsewhere gets 0, all the cores of its node, which
        is right for one worker process per node (docs/cluster.md: several per node are faster;
        then pass --threads). NOTE: the client cannot see a remote node's cores; using its own count, as
        before, starved large nodes and oversubscribed small ones."""
        workers = self.client.scheduler_info().get("workers", {}).values()
        local = {"127.0.0.1", "::1", "localhost", socket.gethostname()}
        try:
            local.add(socket.gethostbyname(socket.gethostname()))
        except OSError:
            pass
        return _share_cores(sum(1 for w in workers if w.get("host") in local))

    def map(self, fn: Callable, shared: tuple, frames: Sequence[int], options: Optional[Dict[str, Any]] = None,
            alone_options: Optional[Dict[str, Any]] = None,
            alone_journal: Optional[Callable[[int], str]] = None) -> Iterator[Dict[str, Any]]:
        from distributed import as_completed

        options = dict(options or {})
        self.shared_bytes = len(pickle.dumps(shared))
        # NOTE: scatter() splits a sequence into one future per element: the tuple goes in a list.
        handle = self.client.scatter([shared], broadcast=True, hash=False)[0]
        self.task_bytes = len(pickle.dumps((_run_dask, fn, handle.key, frames[0] if frames else 0, options)))
        stamp = time.time_ns()
        futures = {self.client.submit(_run_dask, fn, handle, k, options, pure=False,
                                      key=f"synthgen-frame-{k}-{stamp}"): k for k in frames}
        for fut in as_completed(futures):
            try:
                yield fut.result()
            except Exception as e:  # noqa: BLE001 -- a task Dask gave up on (KilledWorker, ...)
                k = futures[fut]
                yield {"frame": k, "ok": False, "error": f"{type(e).__name__}: {e}", "traceback": "", "pid": None}

    def shutdown(self) -> None:
        if self._own:
            self.client.close()
