#!/usr/bin/env python3
"""Texture memory and image quality of the texture resolution estimate (docs/texture_lod.md):
the first frames of scenarios/vehicles.yaml (textured TORCS cars, generated plates, the road)
rendered with every texture at full resolution and with the levels the estimate keeps
(render.texture_lod, memory budget 0: nothing kept beyond the frame's needs), the same seed,
at high spp. Prints per frame the texel memory of the image textures (every level, and
resident as rendered), the render times and the PSNR of the estimated render against the full
one (displayed image, clipped to [0, 1]); the last two lines are exactly

    texture_memory_ratio=<float>     (sum over frames of full / resident memory)
    texture_lod_psnr_db=<float>      (PSNR of all frames' pixels together)

Needs the TORCS assets (`synthgen assets fetch mesh/torcs-p406 mesh/torcs-155-DTM
mesh/torcs-baja-bug`).

    .venv/bin/python bench/texture_lod.py [--frames 8] [--spp 256] [--margin 0]
"""
from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(REPO, "python"))

SCENARIO = os.path.join(REPO, "scenarios", "vehicles.yaml")


def main(argv=None) -> int:
    from synthgen.frame.renderer import FrameRenderer
    from synthgen.scenario import check_inputs, load_scenario

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--margin", type=int, default=0, help="render.texture_lod_margin")
    args = ap.parse_args(argv)

    def renderer(lod: bool) -> FrameRenderer:
        sc = load_scenario(SCENARIO, overrides=[("render.spp", args.spp), ("render.texture_lod", lod),
                                                ("render.texture_lod_margin", args.margin),
                                                ("render.texture_budget_mib", 0.0)])
        check_inputs(sc)
        return FrameRenderer(sc)

    full, est = renderer(False), renderer(True)
    print(f"scenario: {os.path.relpath(SCENARIO, REPO)} frames 0..{args.frames - 1}, 640x480, {args.spp} spp, "
          f"texture_lod_margin {args.margin}")
    mem_full = mem_resident = 0
    sq_err, n = 0.0, 0
    for k in range(args.frames):
        a, meta_a, t_a = full.render(k)
        b, meta_b, t_b = est.render(k)
        fm, em = meta_a["texture_memory"], meta_b["texture_memory"]
        assert fm["full_bytes"] == em["full_bytes"], "the two renders hold different textures"
        mem_full += em["full_bytes"]
        mem_resident += em["resident_bytes"]
        x, y = np.clip(a["rgb"], 0, 1), np.clip(b["rgb"], 0, 1)
        e = float(np.sum((x - y) ** 2))
        sq_err += e
        n += x.size
        psnr = 10 * math.log10(x.size / e) if e > 0 else math.inf
        print(f"frame {k}: texture memory {em['full_bytes'] / 2**20:.2f} MiB full, "
              f"{em['resident_bytes'] / 2**20:.2f} MiB resident; render {t_a['render_s']:.2f} s full, "
              f"{t_b['render_s']:.2f} s estimated (estimate {t_b['texture_lod_s']:.3f} s); PSNR {psnr:.2f} dB",
              flush=True)
    print(f"texture memory over {args.frames} frames: {mem_full / 2**20:.2f} MiB full, "
          f"{mem_resident / 2**20:.2f} MiB resident")
    print(f"texture_memory_ratio={mem_full / mem_resident:.2f}")
    print(f"texture_lod_psnr_db={10 * math.log10(n / sq_err) if sq_err > 0 else math.inf:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
