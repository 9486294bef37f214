"""``synthgen validate SCENARIO.yaml``: check a scenario without rendering."""
from __future__ import annotations

import argparse
import sys
from typing import List

from . import Command, register
from .common import add_extension_option, add_scenario_overrides, scenario_overrides


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", metavar="SCENARIO.yaml")
    add_scenario_overrides(p)
    add_extension_option(p)


def run(args: argparse.Namespace) -> int:
    from ..scenario import check_inputs, load_scenario

    sc = load_scenario(args.scenario, scenario_overrides(args), allow_extensions=args.allow_extensions)
    warnings: List[str] = []
    checked = check_inputs(sc, warnings)
    for w in warnings:  # suspicious, not wrong (a photo's geometry)
        print(f"warning: {w}", file=sys.stderr)
    plural = {"mesh": "meshes", "environment map": "environment maps"}

    def name(kind: str, n: int) -> str:
        return kind if n == 1 else plural.get(kind, kind + "s")

    files = ", ".join(f"{n} {name(k, n)}" for k, n in sorted(checked.items())) or "no input files"
    print(f"{args.scenario}: ok ({sc.count} frames, {sc.resolution[0]}x{sc.resolution[1]}, "
          f"classes: {', '.join(sc.class_names)}; loaded {files})")
    for w in sc.warnings:  # valid, but likely not meant (a sky nothing exposes)
        print(f"warning: {w}", file=sys.stderr)
    return 0


register(Command("validate", "check a scenario file without rendering",
                 "Validate a scenario file and load every file it names (meshes, images, environment maps, "
                 "assets, fonts) once: every error names file, line, column and key.", add_arguments, run,
                 order=50, module=__name__))
