"""``synthgen schema [--scenario]``: every key of the scene-file (or scenario) format."""
from __future__ import annotations

import argparse

from . import Command, register
from .common import EXIT_OK


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scenario", action="store_true", help="the scenario format of `synthgen run`")


def run(args: argparse.Namespace) -> int:
    from ..schema.reference import format_scenario_schema, format_schema

    if getattr(args, "scenario", False):
        print(format_scenario_schema())
    else:
        from ..scene.scene_file import SCENE_SCHEMA

        print(format_schema(SCENE_SCHEMA))
    return EXIT_OK


register(Command("schema", "describe the scene file (or scenario) format",
                 "Print every key of the scene file format (or, with --scenario, of the scenario format) with its "
                 "type, default, range and meaning.", add_arguments, run, order=80, module=__name__))
