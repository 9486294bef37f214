#!/usr/bin/env python3
"""Cost of the C extension mechanism (a script that prints figures, not a test).

Hydra Render measured its extensions against built-in code (rust +21% render time, scratches
+15% over grey diffuse; Sanzharov 2023). Here, in one run (interleaved, median of --runs): the
scene of bench/wear_overhead.py (the Kenney truck on a ground plane under a sky) with the model
grey diffuse, rusted by the built-in preset (synthgen.wear.rust: a graph of noise, gradient,
edges and blend textures) and rusted by the same preset on the example extension rust.c
(synthgen.scene.wear_ext.rust: three C functions calling synthgen's noise). The last lines are
``psnr_extension_vs_builtin_db=<float>`` (the two rust renders) and
``extension_vs_builtin_overhead_pct=<float>`` (the extension rust's render time over the
built-in's, minus 1; target <= 10).

    .venv/bin/python bench/extension_overhead.py [--runs 3] [--spp 32]
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import synthgen as sg  # noqa: E402
from synthgen import wear  # noqa: E402
from synthgen.scene import wear_ext  # noqa: E402
from wear_overhead import build  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    args = ap.parse_args(argv)
    sg.load_image_plugin()
    wear.rust_extension = wear_ext.rust  # build() looks presets up by name in synthgen.wear
    scenes = {}
    for e in ("grey", "rust", "rust_extension"):
        scenes[e], what = build(e, args.width, args.height)
    print(f"scene: {what}, {args.width}x{args.height}, {args.spp} spp, max_depth 6; median of {args.runs} "
          "interleaved runs")
    times = {e: [] for e in scenes}
    images = {}
    for _ in range(args.runs):
        for e, s in scenes.items():
            r = s.render(spp=args.spp, max_depth=6, seed=1)
            times[e].append(r.stats["wall_time_s"])
            images[e] = r.rgb
    med = {e: statistics.median(v) for e, v in times.items()}
    for e in scenes:
        print(f"{e}_render_s={med[e]:.3f}")
    a, b = images["rust"].astype(np.float64), images["rust_extension"].astype(np.float64)
    mse = float(np.mean((a - b) ** 2))
    psnr = float("inf") if mse == 0.0 else 10.0 * np.log10(float(a.max()) ** 2 / mse)
    print(f"builtin_rust_vs_grey_overhead_pct={100.0 * (med['rust'] / med['grey'] - 1.0):.1f}")
    print(f"extension_rust_vs_grey_overhead_pct={100.0 * (med['rust_extension'] / med['grey'] - 1.0):.1f}")
    print(f"psnr_extension_vs_builtin_db={psnr:.2f}")
    print(f"extension_vs_builtin_overhead_pct={100.0 * (med['rust_extension'] / med['rust'] - 1.0):.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
