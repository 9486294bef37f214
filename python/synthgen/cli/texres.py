"""``synthgen texres SCENE_OR_SCENARIO [--frame K]``: which resolution each texture needs."""
from __future__ import annotations

import argparse

from . import Command, register
from .common import add_extension_option, nonnegative_int, positive_int


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="SCENE_OR_SCENARIO.yaml",
                   help="a scene file (see `synthgen schema`) or a scenario (then the frame's scene)")
    p.add_argument("--frame", type=nonnegative_int, default=0, metavar="K",
                   help="the scenario's frame whose camera and scene are estimated (default 0)")
    p.add_argument("--max-depth", type=nonnegative_int, default=4, metavar="D",
                   help="sharp reflections and refractions followed after the camera hit (default 4)")
    p.add_argument("--threads", type=positive_int, default=None, metavar="T", help="threads (default: all cores)")
    add_extension_option(p)


def scene_kind(data: object) -> str:
    """"scene" or "scenario" for a YAML document: by the top-level keys only one of the two
    schemas has (a scenario when neither decides)."""
    from ..scenario.schema import SCENARIO_SCHEMA
    from ..scene.scene_file import SCENE_SCHEMA

    keys = set(data) if isinstance(data, dict) else set()
    scene_only = set(SCENE_SCHEMA.fields) - set(SCENARIO_SCHEMA.fields)
    return "scene" if keys & scene_only else "scenario"


def run(args: argparse.Namespace) -> int:
    from ..scene.texture_lod import texture_table
    from ..schema.yaml_io import read_yaml

    threads = args.threads or 0
    if scene_kind(read_yaml(args.file)) == "scene":
        from ..scene.scene_file import load_scene

        scene = load_scene(args.file, allow_extensions=args.allow_extensions)[0]
        what = args.file
    else:
        from ..frame.renderer import FrameRenderer
        from ..scenario import check_inputs, load_scenario

        sc = load_scenario(args.file, allow_extensions=args.allow_extensions)
        check_inputs(sc)
        fr = FrameRenderer(sc, threads=threads)
        fr.prepare(args.frame)
        scene = fr.scene
        what = f"{args.file} frame {args.frame}"
    cam = scene.camera
    est = scene.estimate_texture_resolution(max_depth=args.max_depth, threads=threads)
    print(f"{what}: {cam.width}x{cam.height}, texture resolution for at least one texel per pixel")
    print(texture_table(est))
    return 0


register(Command("texres", "which resolution each texture needs for a frame's camera",
                 "Estimate, for the camera of a scene file or of a scenario's frame, which mip level of every "
                 "image texture keeps at least one texel per pixel (camera rays with ray differentials, followed "
                 "through mirrors, glass and car paint), and print per texture its full and needed resolution "
                 "and the memory before and after (docs/texture_lod.md).", add_arguments, run, order=48,
                 module=__name__))
