#!/usr/bin/env python3
"""Cost of one procedural texture lookup (a script that prints figures, not a test).

Evaluates the noise textures the wear presets use at 2^20 random object-space points through
``Scene.texture_values`` (one call per texture: the Python overhead is amortized), best of
--runs, one thread of the calling process. Prints nanoseconds per lookup.

    .venv/bin/python bench/noise_lookup.py [--runs 5]
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))

import synthgen as sg  # noqa: E402

TEXTURES = {
    "fbm_4_octaves": ("noise", {"pattern": "fbm", "octaves": 4, "mapping": "object", "scale": 3.0}),
    "turbulence_3_octaves": ("noise", {"pattern": "turbulence", "octaves": 3, "mapping": "object", "scale": 3.0}),
    "cellular_f2_minus_f1": ("cellular", {"output": "f2_minus_f1", "mapping": "object", "scale": 8.0}),
    "cellular_edge": ("cellular", {"output": "edge", "mapping": "object", "scale": 8.0}),
}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args(argv)
    s = sg.Scene()
    pts = (np.random.default_rng(1).random((1 << 20, 3)) * 10.0).astype(np.float32)
    for name, (kind, params) in TEXTURES.items():
        t = s.add_texture(kind, params)
        best = float("inf")
        for _ in range(args.runs):
            t0 = time.perf_counter()
            s.texture_values(t, pts)
            best = min(best, time.perf_counter() - t0)
        print(f"{name}_ns_per_lookup={1e9 * best / len(pts):.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
