"""``synthgen inspect DIR``: a contact sheet of frames with their boxes, classes and ids, and
the dataset's statistics (objects per class, box sizes, occlusion) as text and plots."""
from __future__ import annotations

import argparse

from . import Command, register
from .common import positive_int


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("dataset", metavar="DIR")
    p.add_argument("-o", "--output", metavar="OUT", help="where to write the PNGs (default: DIR/inspect)")
    p.add_argument("-n", "--count", type=positive_int, default=16, metavar="N",
                   help="frames on the contact sheet (default 16)")
    p.add_argument("--columns", type=positive_int, default=4, metavar="C", help="contact sheet columns (default 4)")
    p.add_argument("--split", choices=("train", "val", "test"), help="only the frames of this split")


def run(args: argparse.Namespace) -> int:
    from ..outputs.inspect import format_statistics, inspect

    st = inspect(args.dataset, args.output, args.count, args.split, args.columns)
    print(format_statistics(st))
    print(f"contact sheet: {st['contact_sheet']}\nplots: {st['plots']}")
    return 0


register(Command("inspect", "look at a dataset: contact sheet and statistics",
                 "Draw the first frames of a dataset with every labelled object's box, class and instance id "
                 "(contact_sheet.png), and plot objects per class, box heights, occlusion and truncation, objects "
                 "per frame (statistics.png); print the same figures.", add_arguments, run, order=45,
                 module=__name__))
