"""The ``synthgen`` command line: one module per command.

Each command module registers a :class:`Command` (name, help, arguments, function);
:func:`build_parser` adds them in ``order``. Input errors (bad YAML, missing files, invalid
values) print one line to stderr and exit with status 2; ``--debug`` shows the full
traceback instead. Adding a command is one module here (found by :func:`discover`) plus its
test.
"""
from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional, Sequence

from .._core import SynthgenError, __version__
from .common import EXIT_INPUT_ERROR, EXIT_INTERRUPTED, EXIT_OK, debug_option, error_text

__all__ = ["main", "build_parser", "Command", "register", "commands", "EXIT_OK", "EXIT_INPUT_ERROR"]


@dataclass(frozen=True)
class Command:
    name: str
    help: str
    description: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Optional[Callable[[argparse.Namespace], int]]
    order: int
    module: str = ""


_COMMANDS: Dict[str, Command] = {}

#: Modules of this package that are not commands.
INFRASTRUCTURE = ("common",)


def register(c: Command) -> Command:
    if c.name in _COMMANDS:
        raise SynthgenError(f"command '{c.name}' is registered twice")
    _COMMANDS[c.name] = c
    return c


def commands() -> List[Command]:
    return sorted(_COMMANDS.values(), key=lambda c: c.order)


def command_modules() -> List[str]:
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if m.name not in INFRASTRUCTURE)


def discover() -> None:
    for name in command_modules():
        importlib.import_module(f"{__name__}.{name}")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``synthgen`` command, with every registered command."""
    parser = argparse.ArgumentParser(
        prog="synthgen",
        description="Photoreal synthetic training data for computer vision: renders a scene to "
                    "linear/sRGB colour, depth, normals, albedo, instance and class ids.",
    )
    parser.add_argument("--version", action="version", version=f"synthgen {__version__}")
    debug_option(parser, top=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for c in commands():
        p = sub.add_parser(c.name, help=c.help, description=c.description)
        c.add_arguments(p)
        debug_option(p, top=False)
        if c.run is not None:
            p.set_defaults(func=c.run)
    return parser


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
        print(f"synthgen: error: {error_text(e)}", file=sys.stderr)
        return EXIT_INPUT_ERROR


discover()
