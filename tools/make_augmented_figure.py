#!/usr/bin/env python3
"""docs/augmented.png: photo / frame pairs of scenarios/augmented_road.yaml (the photo crop a
frame uses, left; the frame, right), three frames, half size.

    .venv/bin/python tools/make_augmented_figure.py [--frames 0,1,3] [-o docs/augmented.png]
"""
from __future__ import annotations

import argparse
import os
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "python"))

import numpy as np  # noqa: E402


def main(argv=None) -> int:
    from synthgen.frame.renderer import FrameRenderer
    from synthgen.outputs.files import write_srgb_png
    from synthgen.scenario import check_inputs, load_scenario

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", default="0,1,3")
    ap.add_argument("-o", "--output", default=os.path.join(REPO, "docs", "augmented.png"))
    args = ap.parse_args(argv)
    sc = load_scenario(os.path.join(REPO, "scenarios", "augmented_road.yaml"))
    check_inputs(sc)
    fr = FrameRenderer(sc)
    rows = []
    for k in (int(v) for v in args.frames.split(",")):
        arrays, meta, _ = fr.render(k)
        pair = np.concatenate([fr.last_photo.pixels, np.ones((arrays["rgb"].shape[0], 8, 3), np.float32),
                               arrays["rgb"]], axis=1)
        rows += [pair[::2, ::2], np.ones((4, pair.shape[1] // 2, 3), np.float32)]
    img = np.concatenate(rows[:-1], axis=0)
    write_srgb_png(args.output, img)
    print(f"wrote {args.output} ({img.shape[1]} x {img.shape[0]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
