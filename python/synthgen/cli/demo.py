"""``synthgen demo``: render the built-in demo scene (no files needed)."""
from __future__ import annotations

import argparse
import os

from . import Command, register
from .common import add_render_options, overrides, positive_int, render_and_write


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("-o", "--output", metavar="DIR", default=os.path.join("out", "demo"),
                   help="output directory (default: out/demo)")
    p.add_argument("--width", type=positive_int, metavar="W", help="image width (default 640)")
    p.add_argument("--height", type=positive_int, metavar="H", help="image height (default 480)")
    add_render_options(p)


def run(args: argparse.Namespace) -> int:
    from ..scene.demo import build_demo_scene

    scene, settings, meta = build_demo_scene(args.width, args.height, **overrides(args))
    return render_and_write(scene, settings, meta, args.output, "demo")


register(Command("demo", "render the built-in demo scene",
                 "Render the built-in demo scene (procedural spheres and boxes on a ground plane, sun and sky; "
                 "no files needed).", add_arguments, run, order=20, module=__name__))
