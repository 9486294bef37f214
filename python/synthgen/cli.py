"""The ``synthgen`` command line.

    synthgen render SCENE.yaml -o DIR [--spp N] [--max-depth D] [--rr-depth R]
                                      [--threads T] [--seed S]
    synthgen demo [-o DIR] [--spp N] [--width W] [--height H] [...]
    synthgen schema            # every scene-file key with type, default and range
    synthgen --version

Options given on the command line override the scene file's ``render`` settings.
Input errors (bad YAML, missing files, invalid values) print one line to stderr and exit
with status 2; ``--debug`` shows the full traceback instead.
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import Any, Dict, Optional, Sequence

from ._core import SynthgenError, __version__

EXIT_OK = 0
EXIT_INPUT_ERROR = 2
EXIT_INTERRUPTED = 130

__all__ = ["main", "build_parser", "EXIT_OK", "EXIT_INPUT_ERROR"]


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {v}")
    return v


def _nonnegative_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}") from None
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {v}")
    return v


def _add_render_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("render settings (override the scene's 'render' section)")
    g.add_argument("--spp", type=_positive_int, metavar="N", help="samples per pixel")
    g.add_argument("--max-depth", type=_positive_int, metavar="D",
                   help="maximum ray segments from the camera (1: emitters seen directly)")
    g.add_argument("--rr-depth", type=_nonnegative_int, metavar="R", help="path length at which Russian roulette starts")
    g.add_argument("--threads", type=_nonnegative_int, metavar="T", help="worker threads (0: all cores)")
    g.add_argument("--seed", type=_nonnegative_int, metavar="S", help="random seed")


def _debug_option(p: argparse.ArgumentParser, top: bool) -> None:
    # On sub-commands the default is SUPPRESS so that `synthgen --debug render ...` is
    # not overwritten by the sub-command's default.
    p.add_argument("--debug", action="store_true", default=False if top else argparse.SUPPRESS,
                   help="show the full traceback on errors")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``synthgen`` command (sub-commands render, demo, schema)."""
    parser = argparse.ArgumentParser(
        prog="synthgen",
        description="Photoreal synthetic training data for computer vision: renders a scene to "
                    "linear/sRGB colour, depth, normals, albedo, instance and class ids.",
    )
    parser.add_argument("--version", action="version", version=f"synthgen {__version__}")
    _debug_option(parser, top=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("render", help="render a YAML scene file",
                       description="Render a YAML scene file and write rgb.exr, rgb.png, depth.exr, normal.exr, "
                                   "albedo.exr, instance.png, class.png and meta.json into the output directory.")
    p.add_argument("scene", metavar="SCENE.yaml", help="scene file (see `synthgen schema`)")
    p.add_argument("-o", "--output", metavar="DIR",
                   help="output directory (default: out/<scene file name without extension>)")
    _add_render_options(p)
    _debug_option(p, top=False)
    p.set_defaults(func=_cmd_render)

    p = sub.add_parser("demo", help="render the built-in demo scene",
                       description="Render the built-in demo scene (procedural spheres and boxes on a ground "
                                   "plane, sun and sky; no files needed).")
    p.add_argument("-o", "--output", metavar="DIR", default=os.path.join("out", "demo"),
                   help="output directory (default: out/demo)")
    p.add_argument("--width", type=_positive_int, metavar="W", help="image width (default 640)")
    p.add_argument("--height", type=_positive_int, metavar="H", help="image height (default 480)")
    _add_render_options(p)
    _debug_option(p, top=False)
    p.set_defaults(func=_cmd_demo)

    p = sub.add_parser("run", help="render a scenario into a labelled dataset",
                       description="Render the frames of a scenario file into a dataset: images, depth, instance "
                                   "and semantic masks, COCO / YOLO / KITTI labels, per-frame metadata.")
    p.add_argument("scenario", metavar="SCENARIO.yaml", help="scenario file (see scenarios/default.yaml)")
    p.add_argument("-o", "--output", metavar="DIR", required=True, help="output directory")
    p.add_argument("-n", "--count", type=_positive_int, metavar="N", help="frames (default: the scenario's count)")
    p.add_argument("--workers", type=_positive_int, default=1, metavar="N",
                   help="worker processes on this machine (default 1)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address (tcp://host:8786): run there")
    p.add_argument("--resume", action="store_true", help="render only the frames missing from DIR")
    p.add_argument("--only", type=int, nargs="+", metavar="K", help="(re-)render just these frames")
    p.add_argument("--recycle", type=_positive_int, default=200, metavar="N",
                   help="replace a worker process after N frames (default 200)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    _debug_option(p, top=False)
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("verify", help="check that a dataset's labels agree with its masks",
                       description="Check every complete frame of a dataset written by `synthgen run`: COCO RLE "
                                   "masks, boxes and areas against instance/*.png, semantic classes, YOLO and KITTI.")
    p.add_argument("dataset", metavar="DIR")
    _debug_option(p, top=False)
    p.set_defaults(func=_cmd_verify)

    p = sub.add_parser("validate", help="check a scenario file without rendering",
                       description="Validate a scenario file: every error names file, line, column and key.")
    p.add_argument("scenario", metavar="SCENARIO.yaml")
    _debug_option(p, top=False)
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("assets", help="list or fetch assets of the manifest",
                       description="List the assets of assets_manifest/*.yaml, or fetch them into the cache "
                                   "($SYNTHGEN_CACHE or ~/.cache/synthgen), verifying checksums.")
    asub = p.add_subparsers(dest="assets_command", metavar="ACTION", required=True)
    q = asub.add_parser("list", help="list asset ids")
    q.set_defaults(func=_cmd_assets_list)
    q = asub.add_parser("fetch", help="fetch assets (default: all) into the cache")
    q.add_argument("ids", nargs="*", metavar="ID")
    q.set_defaults(func=_cmd_assets_fetch)
    _debug_option(p, top=False)

    p = sub.add_parser("gallery", help="render the wear gallery",
                       description="Render every wear effect on a sign, a car body panel and a sphere, with the "
                                   "parameters under each tile.")
    p.add_argument("-o", "--output", metavar="FILE.png", default=os.path.join("out", "gallery.png"))
    p.add_argument("--spp", type=_positive_int, default=32, help="samples per pixel (default 32)")
    _debug_option(p, top=False)
    p.set_defaults(func=_cmd_gallery)

    p = sub.add_parser("schema", help="describe the scene file (or scenario) format",
                       description="Print every key of the scene file format (or, with --scenario, of the scenario "
                                   "format) with its type, default, range and meaning.")
    p.add_argument("--scenario", action="store_true", help="the scenario format of `synthgen run`")
    _debug_option(p, top=False)
    p.set_defaults(func=_cmd_schema)
    return parser


def _overrides(args: argparse.Namespace) -> Dict[str, Any]:
    keys = ("spp", "max_depth", "rr_depth", "threads", "seed")
    return {k: getattr(args, k) for k in keys if getattr(args, k, None) is not None}


def _fmt_rate(x: float) -> str:
    for unit, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if x >= scale:
            return f"{x / scale:.2f} {unit}"
    return f"{x:.0f} "


def _say(text: str) -> None:
    """Prints progress to stdout; a closed pipe (`synthgen ... | head`) silences the
    output instead of aborting the render."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)


def _render_and_write(scene: Any, settings: Dict[str, Any], scene_meta: Dict[str, Any], out_dir: str,
                      label: str) -> int:
    from .scene_file import validate_render_settings
    from .writers import make_meta, write_outputs

    settings = validate_render_settings(settings, "command line")
    cam = scene.camera
    n_obj, n_light = len(scene_meta.get("objects", [])), len(scene_meta.get("lights", []))
    _say(f"{label}: {n_obj} object{'s' if n_obj != 1 else ''}, {n_light} light{'s' if n_light != 1 else ''}, "
         f"{cam.width}x{cam.height}, {settings['spp']} spp, max depth {settings['max_depth']}, "
         f"seed {settings['seed']}")
    result = scene.render(**settings)
    stats = result.stats
    _say(f"rendered in {stats['wall_time_s']:.2f} s: {_fmt_rate(stats['samples_per_s'])}samples/s, "
         f"{_fmt_rate(stats['rays_per_s'])}rays/s ({stats['threads']} threads)")
    if stats.get("nan_samples"):
        print(f"warning: {stats['nan_samples']} NaN/infinite samples were discarded", file=sys.stderr)
    meta = make_meta(camera=cam, settings=settings, stats=stats, scene=scene_meta)
    paths = write_outputs(out_dir, result, meta)
    for path in paths.values():
        _say(f"wrote {path}")
    return EXIT_OK


def _cmd_render(args: argparse.Namespace) -> int:
    from .scene_file import load_scene

    scene, settings, meta = load_scene(args.scene)
    settings.update(_overrides(args))
    out_dir = args.output or os.path.join("out", os.path.splitext(os.path.basename(args.scene))[0])
    return _render_and_write(scene, settings, meta, out_dir, args.scene)


def _cmd_demo(args: argparse.Namespace) -> int:
    from .demo import build_demo_scene

    scene, settings, meta = build_demo_scene(args.width, args.height, **_overrides(args))
    return _render_and_write(scene, settings, meta, args.output, "demo")


def _cmd_gallery(args: argparse.Namespace) -> int:
    from . import gallery

    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    print(gallery.write_gallery(args.output, spp=args.spp))
    return EXIT_OK


def _cmd_schema(args: argparse.Namespace) -> int:
    from .scene_file import format_schema

    if getattr(args, "scenario", False):
        from .scenario import SCENARIO_SCHEMA

        print(format_schema(SCENARIO_SCHEMA))
    else:
        print(format_schema())
    return EXIT_OK


def _cmd_run(args: argparse.Namespace) -> int:
    from . import runner

    summary = runner.run(args.scenario, args.output, count=args.count, workers=args.workers,
                         scheduler=args.scheduler, resume=args.resume, only=args.only, recycle=args.recycle,
                         progress=not args.no_progress)
    print(summary.text())
    if summary["interrupted"]:
        return EXIT_INTERRUPTED
    return 0 if not summary["failures"] else 1


def _cmd_verify(args: argparse.Namespace) -> int:
    from . import runner

    r = runner.verify_dataset(args.dataset)
    print(f"{args.dataset}: ok: {r['frames']} frames, {r['annotations']} objects; COCO, YOLO and KITTI agree "
          f"with the masks (classes: {', '.join(r['categories'])})")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from . import scenario

    sc = scenario.load_scenario(args.scenario)
    print(f"{args.scenario}: ok ({sc.count} frames, {sc.resolution[0]}x{sc.resolution[1]}, "
          f"classes: {', '.join(sc.class_names)})")
    return 0


def _cmd_assets_list(args: argparse.Namespace) -> int:
    from . import assets

    print("\n".join(assets.list_assets()))
    return 0


def _cmd_assets_fetch(args: argparse.Namespace) -> int:
    from . import assets

    for i, p in assets.fetch(args.ids or None).items():
        print(f"{i}: {p}")
    return 0


def _one_line(e: BaseException) -> str:
    text = str(e).strip() or type(e).__name__
    return " ".join(text.split("\n"))


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of the ``synthgen`` console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_INPUT_ERROR
    debug = getattr(args, "debug", False)
    try:
        return args.func(args)
    except BrokenPipeError:
        # stdout was closed early (e.g. `synthgen demo | head`): stop quietly.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except KeyboardInterrupt:
        if debug:
            raise
        print("synthgen: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except (SynthgenError, OSError) as e:  # SceneFileError is a SynthgenError
        if debug:
            raise
        print(f"synthgen: error: {_one_line(e)}", file=sys.stderr)
        return EXIT_INPUT_ERROR


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
