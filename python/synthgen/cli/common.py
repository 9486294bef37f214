"""Helpers shared by the commands: argument types, render options, progress output, the
render-and-write of ``synthgen render`` / ``synthgen demo``."""
from __future__ import annotations

import argparse
import os
import sys
import threading
from typing import Any, Callable, Dict, TypeVar

from ..schema.plugins import plugin_info

EXIT_OK = 0
EXIT_INPUT_ERROR = 2
EXIT_INTERRUPTED = 130
#: `synthgen run`: every frame written, but some objects were dropped (placement limits).
EXIT_DROPPED = 3


def positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {v}")
    return v


def nonnegative_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}") from None
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {v}")
    return v


def nonnegative_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative number, got {text!r}") from None
    if not v >= 0.0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a non-negative number, got {text}")
    return v


#: Command-line render options: (flag, declared render setting, metavar, argument type).
RENDER_OPTIONS = (("--spp", "spp", "N", positive_int), ("--max-depth", "max_depth", "D", positive_int),
                  ("--rr-depth", "rr_depth", "R", nonnegative_int), ("--threads", "threads", "T", nonnegative_int),
                  ("--seed", "seed", "S", nonnegative_int))


def add_render_options(p: argparse.ArgumentParser) -> None:
    """The render settings as options; their help (meaning and default) comes from the
    settings' declaration (plugin ("render", "path_tracer"))."""
    g = p.add_argument_group("render settings (override the scene's 'render' section)")
    declared = {q["name"]: q for q in plugin_info("render", "path_tracer")["params"]}
    for flag, name, metavar, type_ in RENDER_OPTIONS:
        q = declared[name]
        g.add_argument(flag, type=type_, metavar=metavar, help=f"{q['doc']} (default: the scene's, else {q['default']})")


def resolution(text: str) -> list:
    w, sep, h = text.lower().partition("x")
    try:
        v = [int(w), int(h)]
    except ValueError:
        v = []
    if not sep or len(v) != 2 or min(v) < 1:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels (e.g. 640x480), got {text!r}")
    return v


def add_scenario_overrides(p: argparse.ArgumentParser) -> None:
    """Options that change a scenario's values before validation (they become part of it: the
    run manifest refuses to resume a directory made with other values)."""
    g = p.add_argument_group("scenario overrides (applied before validation, recorded in the run manifest)")
    declared = {q["name"]: q for q in plugin_info("render", "path_tracer")["params"]}
    for flag, name, metavar, type_ in RENDER_OPTIONS:
        if name == "seed":
            continue
        q = declared[name]
        g.add_argument(flag, type=type_, metavar=metavar, help=f"render.{name}: {q['doc']}")
    g.add_argument("--resolution", type=resolution, metavar="WxH", help="resolution: image size in pixels")
    g.add_argument("--seed", type=nonnegative_int, metavar="S", help="seed: the scenario's seed")
    g.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="any scenario key, VALUE in YAML, e.g. --set objects[0].count=3 --set "
                        "'camera.fov_y={uniform: [40, 60]}' (repeatable)")


def scenario_overrides(args: argparse.Namespace) -> list:
    """(key path, value) pairs of the scenario override options, in order: --set last."""
    from ..scenario.load import parse_override

    out: list = []
    for flag, name, _, _ in RENDER_OPTIONS:
        v = getattr(args, name, None)
        if name != "seed" and v is not None:
            out.append((f"render.{name}", v))
    if getattr(args, "resolution", None) is not None:
        out.append(("resolution", args.resolution))
    if getattr(args, "seed", None) is not None:
        out.append(("seed", args.seed))
    out.extend(parse_override(t) for t in getattr(args, "set", []) or [])
    return out


def debug_option(p: argparse.ArgumentParser, top: bool) -> None:
    # On sub-commands the default is SUPPRESS so that `synthgen --debug render ...` is
    # not overwritten by the sub-command's default.
    p.add_argument("--debug", action="store_true", default=False if top else argparse.SUPPRESS,
                   help="show the full traceback on errors")


def overrides(args: argparse.Namespace) -> Dict[str, Any]:
    keys = ("spp", "max_depth", "rr_depth", "threads", "seed")
    return {k: getattr(args, k) for k in keys if getattr(args, k, None) is not None}


def fmt_rate(x: float) -> str:
    for unit, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if x >= scale:
            return f"{x / scale:.2f} {unit}"
    return f"{x:.0f} "


def say(text: str) -> None:
    """Prints progress to stdout; a closed pipe (`synthgen ... | head`) silences the
    output instead of aborting the render."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)


T = TypeVar("T")


def interruptible(fn: Callable[[], T]) -> T:
    """``fn()`` (a render, a scene's building) in a thread, while this, the main thread, waits
    for it: Ctrl-C ends the process within a second (exit 130; nothing has been written yet),
    where native code would have finished first -- a render releases the GIL and does not look
    at signals, a loop in a C extension never ends.

    NOTE: a thread in native code cannot be stopped from Python; os._exit ends the process
    with it (the interpreter's clean-up would wait for the thread, or crash under it)."""
    box: Dict[str, Any] = {}

    def target() -> None:
        try:
            box["value"] = fn()
        except BaseException as e:  # noqa: BLE001 -- raised again in the main thread
            box["error"] = e

    t = threading.Thread(target=target, name="synthgen-native", daemon=True)
    t.start()
    try:
        while t.is_alive():
            t.join(0.25)
    except KeyboardInterrupt:
        print("synthgen: interrupted; nothing was written", file=sys.stderr, flush=True)
        try:
            sys.stdout.flush()
        finally:
            os._exit(EXIT_INTERRUPTED)
    if "error" in box:
        raise box["error"]
    return box["value"]


def render_and_write(scene: Any, settings: Dict[str, Any], scene_meta: Dict[str, Any], out_dir: str,
                      label: str, expose: bool = False) -> int:
    """Renders ``scene`` with ``settings`` and writes every file of ``synthgen render``;
    ``expose``: the image written is the render times its ``exposure`` setting (a replayed
    frame's exposure, as the frame's image was), meta ``exposure`` says by how much."""
    from ..outputs.render import make_meta, write_outputs
    from ..scene.scene_file import validate_render_settings

    settings = validate_render_settings(settings, "command line")
    cam = scene.camera
    n_obj, n_light = len(scene_meta.get("objects", [])), len(scene_meta.get("lights", []))
    say(f"{label}: {n_obj} object{'s' if n_obj != 1 else ''}, {n_light} light{'s' if n_light != 1 else ''}, "
         f"{cam.width}x{cam.height}, {settings['spp']} spp, max depth {settings['max_depth']}, "
         f"seed {settings['seed']}")
    result = interruptible(lambda: scene.render(**settings))
    stats = result.stats
    say(f"rendered in {stats['wall_time_s']:.2f} s: {fmt_rate(stats['samples_per_s'])}samples/s, "
         f"{fmt_rate(stats['rays_per_s'])}rays/s ({stats['threads']} threads)")
    if stats.get("nan_samples"):
        print(f"warning: {stats['nan_samples']} NaN/infinite samples were discarded", file=sys.stderr)
    meta = make_meta(camera=cam, settings=settings, stats=stats, scene=scene_meta)
    factor = float(settings.get("exposure", 1.0))
    if expose and factor != 1.0:
        import numpy as np

        say(f"exposure: the image x {factor:.9g} (the render's recorded exposure)")
        meta["exposure"] = {"factor": factor, "from": "the render's exposure setting"}
        arrays = {k: np.asarray(getattr(result, k)) for k in ("depth", "normal", "albedo", "instance_id", "class_id")}
        arrays["rgb"] = (np.asarray(result.rgb, np.float32) * np.float32(factor)).astype(np.float32)
        result = arrays
    paths = write_outputs(out_dir, result, meta)
    for path in paths.values():
        say(f"wrote {path}")
    return EXIT_OK


def error_text(e: BaseException) -> str:
    """An error's message as printed after ``synthgen: error:``: its lines as they are (a C
    compiler's ``FILE:LINE:COLUMN: error: ...`` diagnostics one per line, as it printed them),
    trailing blanks dropped."""
    lines = [line.rstrip() for line in str(e).strip().splitlines()]
    return "\n".join(lines) or type(e).__name__


def add_extension_option(p: argparse.ArgumentParser) -> None:
    """``--allow-extensions``: the user's consent to compile and run the C files a scene file
    or scenario lists under ``extensions`` (the file must say ``allow_extensions: true``)."""
    p.add_argument("--allow-extensions", action="store_true",
                   help="let the file compile and run the C extensions it lists (it must say allow_extensions: true "
                        "too); extensions run with your rights (docs/extensions.md)")
