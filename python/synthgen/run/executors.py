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
(``worker process died``) while the run goes on; finished frames are on disk already.
"""
from __future__ import annotations

import os
import pickle
import signal
import socket
import time
from collections import deque
from typing import Any, Callable, Deque, Dict, Iterator, List, Optional, Sequence

__all__ = ["LocalExecutor", "DaskExecutor"]

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


def _died(frame: int, exitcode: Optional[int], journal: str = "") -> Dict[str, Any]:
    how = ""
    if exitcode is not None and exitcode < 0:
        try:
            how = f" (killed by {signal.Signals(-exitcode).name})"
        except ValueError:
            how = f" (killed by signal {-exitcode})"
    elif exitcode is not None:
        how = f" (exit code {exitcode})"
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
    """Frames on a pool of worker processes on this machine (``workers`` = 1: in this
    process). Workers keep their scene across frames and are replaced after ``recycle``
    frames, so memory cannot grow without bound."""

    def __init__(self, workers: int = 1, recycle: int = 200):
        self.workers = max(1, int(workers))
        self.recycle = max(1, int(recycle))
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
        if self.workers == 1:
            for k in frames:
                yield fn(shared[0], shared[1], k, *shared[2:], **options)
            return
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        pending: Deque[int] = deque(frames)
        while pending:
            pool = self._new_pool(self.workers, shared)
            inflight: Dict[Any, int] = {}
            suspects: List[int] = []
            try:
                while (pending or inflight) and not suspects:
                    # At most one frame per worker in flight: when a worker dies, only these
                    # frames can have killed it.
                    while pending and len(inflight) < self.workers:
                        k = pending.popleft()
                        inflight[pool.submit(_run, fn, k, options)] = k
                    done, _ = wait(inflight, return_when=FIRST_COMPLETED)
                    for f in done:
                        k = inflight.pop(f)
                        try:
                            r = f.result()
                        except BrokenProcessPool:
                            suspects.append(k)
                            continue
                        yield r
                suspects.extend(inflight.values())
            except BaseException:
                self.shutdown()
                raise
            pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
            for k in sorted(set(suspects)):
                r = self._alone(fn, shared, k, {**options, **(alone_options or {})})
                if not r["ok"] and r["error"].startswith("WorkerDied") and alone_journal is not None:
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
        try:
            proc.start()
            send.close()  # the child's end: a dead child leaves the pipe at end of file
            try:
                result = receive.recv()
            except EOFError:
                proc.join()
                return _died(frame, proc.exitcode)
            proc.join()
            return result
        except BaseException:
            if proc.is_alive():
                proc.terminate()
            raise
        finally:
            receive.close()
            self._proc = None

    def shutdown(self) -> None:
        proc, self._proc = self._proc, None
        if proc is not None and proc.is_alive():
            proc.terminate()
        pool, self._pool = self._pool, None
        if pool is not None:
            procs = list((getattr(pool, "_processes", None) or {}).values())
            pool.shutdown(wait=False, cancel_futures=True)
            for p in procs:
                if p.is_alive():
                    p.terminate()


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
