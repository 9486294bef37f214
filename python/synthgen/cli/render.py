"""``synthgen render SCENE.yaml -o DIR``: render a scene file, every channel."""
from __future__ import annotations

import argparse
import os

from . import Command, register
from .common import add_extension_option, add_render_options, interruptible, overrides, render_and_write


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", metavar="SCENE.yaml", help="scene file (see `synthgen schema`)")
    p.add_argument("-o", "--output", metavar="DIR",
                   help="output directory (default: out/<scene file name without extension>)")
    add_render_options(p)
    add_extension_option(p)


def run(args: argparse.Namespace) -> int:
    from ..scene.scene_file import load_scene

    # (building the scene evaluates textures: a C extension's code)
    scene, settings, meta = interruptible(lambda: load_scene(args.scene, allow_extensions=args.allow_extensions))
    settings.update(overrides(args))
    out_dir = args.output or os.path.join("out", os.path.splitext(os.path.basename(args.scene))[0])
    return render_and_write(scene, settings, meta, out_dir, args.scene)


register(Command("render", "render a YAML scene file",
                 "Render a YAML scene file and write rgb.exr, rgb.png, depth.exr, normal.exr, albedo.exr, "
                 "instance.png, class.png and meta.json into the output directory.", add_arguments, run, order=10,
                 module=__name__))
