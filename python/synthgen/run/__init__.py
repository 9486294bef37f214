"""Runs: many frames on worker processes or a Dask cluster, resume, summaries.

- :mod:`.runner` -- :func:`run` (validation first, resume, the dataset-level files,
  :class:`RunSummary`);
- :mod:`.executors` -- :class:`LocalExecutor`, :class:`DaskExecutor`;
- :mod:`.task` -- :func:`render_task`, what a worker does for one frame.
"""
from .executors import DaskExecutor, LocalExecutor  # noqa: F401
from .runner import ABORT_AFTER, RunSummary, remove_temporaries, run  # noqa: F401
from .task import render_task  # noqa: F401
