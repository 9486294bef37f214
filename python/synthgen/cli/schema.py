"""``synthgen schema [--scenario | --calibration]``: every key of the scene-file (or scenario,
or photo calibration) format."""
from __future__ import annotations

import argparse

from . import Command, register
from .common import EXIT_OK


def add_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--scenario", action="store_true", help="the scenario format of `synthgen run`")
    g.add_argument("--calibration", action="store_true",
                   help="the calibration file of a photo (background photos; docs/augmented_photos.md)")


def run(args: argparse.Namespace) -> int:
    from ..schema.reference import format_schema

    if getattr(args, "scenario", False):
        from ..scenario.schema import format_scenario_schema

        print(format_scenario_schema())
    elif getattr(args, "calibration", False):
        from ..background.sidecar import CALIBRATION_SCHEMA

        print(format_schema(CALIBRATION_SCHEMA))
    else:
        from ..scene.scene_file import SCENE_SCHEMA

        print(format_schema(SCENE_SCHEMA))
    return EXIT_OK


register(Command("schema", "describe the scene file (or scenario, or photo calibration) format",
                 "Print every key of the scene file format (or, with --scenario, of the scenario format; with "
                 "--calibration, of a photo's calibration file) with its type, default, range and meaning.", add_arguments, run, order=80, module=__name__))
