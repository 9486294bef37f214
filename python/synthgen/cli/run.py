"""``synthgen run SCENARIO.yaml -o DIR``: render a scenario into a labelled dataset."""
from __future__ import annotations

import argparse

from . import Command, register
from .common import (EXIT_DROPPED, EXIT_INTERRUPTED, add_extension_option, add_scenario_overrides,
                     nonnegative_float, positive_int, scenario_overrides)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", metavar="SCENARIO.yaml", help="scenario file (see scenarios/default.yaml)")
    p.add_argument("-o", "--output", metavar="DIR", required=True, help="output directory")
    p.add_argument("-n", "--count", type=positive_int, metavar="N", help="frames (default: the scenario's count)")
    p.add_argument("--workers", type=positive_int, default=1, metavar="N",
                   help="worker processes on this machine (default 1)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address (tcp://host:8786): run there")
    p.add_argument("--resume", action="store_true", help="render only the frames missing from DIR")
    p.add_argument("--only", type=int, nargs="+", metavar="K", help="(re-)render just these frames")
    p.add_argument("--recycle", type=positive_int, default=200, metavar="N",
                   help="replace a worker process after N frames (default 200)")
    # NOTE: the default is synthgen.run.executors.FRAME_TIMEOUT (not imported here: the command
    # line is parsed before the heavy modules load).
    p.add_argument("--frame-timeout", type=nonnegative_float, metavar="S",
                   help="seconds a frame may take before its worker process is killed and the frame reported failed "
                        "(default 1800; 0: no limit; local workers only)")
    p.add_argument("--in-process", action="store_true",
                   help="render the frames in this process, not in a worker process (one worker; for a debugger: gdb, "
                        "pdb): a crash or a hang then takes the run down, no --frame-timeout, Ctrl-C waits for the "
                        "frame")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--journal", action="store_true",
                   help="write each frame's scene journal into DIR/journals (a failed frame's always goes into "
                        "DIR/failed); `synthgen replay` renders one again")
    add_scenario_overrides(p)
    add_extension_option(p)


def run(args: argparse.Namespace) -> int:
    from ..run import run as run_scenario
    from ..run.executors import FRAME_TIMEOUT

    summary = run_scenario(args.scenario, args.output, count=args.count, workers=args.workers,
                           scheduler=args.scheduler, resume=args.resume, only=args.only, recycle=args.recycle,
                           progress=not args.no_progress, overrides=scenario_overrides(args),
                           allow_extensions=args.allow_extensions, journal=args.journal,
                           frame_timeout=FRAME_TIMEOUT if args.frame_timeout is None else args.frame_timeout,
                           isolate=not args.in_process)
    print(summary.text(debug=getattr(args, "debug", False)))
    if summary["interrupted"]:
        return EXIT_INTERRUPTED
    if summary["failures"]:
        return 1
    return EXIT_DROPPED if summary["dropped"] and not summary.get("drops_allowed") else 0


register(Command("run", "render a scenario into a labelled dataset",
                 "Render the frames of a scenario file into a dataset: images, depth, instance and semantic masks, "
                 "COCO / YOLO / KITTI labels, per-frame metadata. Exit status: 0 done, 1 some frames failed, 3 every "
                 "frame written but some objects dropped (placement limits not met; 0 with placement.allow_drops), 2 bad input, "
                 "130 interrupted.", add_arguments, run, order=30, module=__name__))
