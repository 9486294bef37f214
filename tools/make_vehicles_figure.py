#!/usr/bin/env python3
"""docs/vehicles.png: a strip of four frames of scenarios/vehicles.yaml (library vehicles with
plates, paint and road dirt on a two-lane road) at half size, as `synthgen run` renders them;
with --scenario scenarios/vehicles_night.yaml, docs/vehicles_night.png (the same at night, lit
by the vehicles' lamps and street lamps).

    .venv/bin/python tools/make_vehicles_figure.py [--scenario S] [--frames 0,1,2,3] [-o PNG]
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
    ap.add_argument("--scenario", default=os.path.join(REPO, "scenarios", "vehicles.yaml"))
    ap.add_argument("--frames", default="0,1,2,3")
    ap.add_argument("-o", "--output", default=None, help="default: docs/<scenario name>.png")
    args = ap.parse_args(argv)
    if args.output is None:
        args.output = os.path.join(REPO, "docs", os.path.splitext(os.path.basename(args.scenario))[0] + ".png")
    sc = load_scenario(args.scenario)
    check_inputs(sc)
    fr = FrameRenderer(sc)
    tiles = []
    for k in (int(v) for v in args.frames.split(",")):
        arrays, _, _ = fr.render(k)
        tiles += [arrays["rgb"][::2, ::2], np.ones((arrays["rgb"].shape[0] // 2, 4, 3), np.float32)]
    img = np.concatenate(tiles[:-1], axis=1)
    write_srgb_png(args.output, img)
    print(f"wrote {args.output} ({img.shape[1]} x {img.shape[0]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
