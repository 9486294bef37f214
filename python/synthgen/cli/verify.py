"""``synthgen verify DIR``: check that a dataset's labels agree with its masks."""
from __future__ import annotations

import argparse

from . import Command, register


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("dataset", metavar="DIR")


def run(args: argparse.Namespace) -> int:
    from ..outputs.verify import verify_dataset

    r = verify_dataset(args.dataset)
    print(f"{args.dataset}: ok: {r['frames']} frames, {r['annotations']} objects ({r['inserted']} inserted, "
          f"{r['real']} real); COCO, YOLO and KITTI agree "
          f"with the masks (classes: {', '.join(r['categories'])})")
    return 0


register(Command("verify", "check that a dataset's labels agree with its masks",
                 "Check every complete frame of a dataset written by `synthgen run`: COCO RLE masks, boxes and "
                 "areas against instance/*.png, semantic classes, YOLO and KITTI.", add_arguments, run, order=40,
                 module=__name__))
