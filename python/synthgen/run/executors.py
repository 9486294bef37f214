"""Executors: where frames are rendered. :class:`LocalExecutor` (worker processes on this
machine, recycled after ``recycle`` frames) and :class:`DaskExecutor` (a Dask cluster) run
the same task function (:func:`synthgen.run.task.render_task`), so a frame is the same
whichever executor renders it."""
from __future__ import annotations

import signal
import time
from typing import Any, Callable, Dict, Iterator, List

__all__ = ["LocalExecutor", "DaskExecutor"]


def _init_worker() -> None:
    # Ctrl-C is handled by the parent, which then terminates the pool.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


class LocalExecutor:
    """Frames on a pool of worker processes on this machine (``workers`` = 1: in this
    process). Workers keep their scene across frames and are replaced after ``recycle``
    frames, so memory cannot grow without bound."""

    def __init__(self, workers: int = 1, recycle: int = 200):
        self.workers = max(1, int(workers))
        self.recycle = max(1, int(recycle))
        self._pool = None

    def map(self, fn: Callable, args: List[tuple]) -> Iterator[Dict[str, Any]]:
        if self.workers == 1:
            for a in args:
                yield fn(*a)
            return
        import multiprocessing as mp

        ctx = mp.get_context("spawn")  # no fork of a process with TBB/Embree threads
        self._pool = ctx.Pool(self.workers, initializer=_init_worker, maxtasksperchild=self.recycle)
        try:
            for r in self._pool.imap_unordered(_star, [(fn, a) for a in args]):
                yield r
            self._pool.close()
        except BaseException:
            self._pool.terminate()
            raise
        finally:
            self._pool.join()

    def shutdown(self) -> None:
        if self._pool is not None:
            self._pool.terminate()


def _star(fa):
    fn, a = fa
    return fn(*a)


class DaskExecutor:
    """Frames on a Dask distributed cluster (``address`` of a scheduler, or a
    ``distributed.Client``). Workers keep their scene across frames like local ones."""

    def __init__(self, address: Any):
        from distributed import Client

        self.client = address if isinstance(address, Client) else Client(address)
        self._own = not isinstance(address, Client)

    def map(self, fn: Callable, args: List[tuple]) -> Iterator[Dict[str, Any]]:
        from distributed import as_completed

        futures = [self.client.submit(fn, *a, pure=False, key=f"synthgen-frame-{a[2]}-{time.time_ns()}") for a in args]
        for fut in as_completed(futures):
            yield fut.result()

    def shutdown(self) -> None:
        if self._own:
            self.client.close()
