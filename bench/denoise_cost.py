#!/usr/bin/env python3
"""Cost of the denoiser (synthgen.post.denoise) next to the render it cleans: a 16-spp render of
frame 0 of scenarios/default.yaml at 640 x 480 and of the five regression scenes at 128 x 96
(bench/quality_references.py). Per scene, in key=value lines: the render's seconds (median of
3), the denoiser's (median of 5), their ratio (target: denoise <= 0.2 x render), and the
denoiser's CPU-core seconds per megapixel (threads x seconds / megapixels), next to Intel Open
Image Denoise's published ~2.2 core-s/MP. Render and denoise alternate in one run, so the
ratio holds when another process shares the cores.

    PYTHONPATH=python .venv/bin/python bench/denoise_cost.py [--scenes default640,cbox,...]"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(REPO, "python"))
sys.path.insert(0, HERE)

OIDN_CORE_S_PER_MP = 2.2
SCENES = ("default640", "cbox", "materials", "sunlit", "default", "road_signs")


def scene_of(name: str):
    from quality_references import regression_scene

    if name == "default640":
        return regression_scene("default", 640, 480)
    return regression_scene(name)


def main(argv=None) -> int:
    from synthgen.post.denoise import denoise

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--spp", type=int, default=16)
    args = ap.parse_args(argv)
    for name in args.scenes.split(","):
        try:
            scene, depth, _scale, _owner = scene_of(name)
        except Exception as e:  # noqa: BLE001 - a missing asset
            print(f"scene={name} skipped={e!r}")
            continue
        render_s, denoise_s = [], []
        res = None
        for i in range(5):
            if i < 3:
                t = time.perf_counter()
                res = scene.render(spp=args.spp, max_depth=depth, seed=71 + i)
                render_s.append(time.perf_counter() - t)
            # What render(..., denoise=True) runs: the halves and the features' means over all
            # samples (cpp/film/film.cpp denoise_film; equal halves here: spp even).
            bufs = [np.asarray(res.rgb_even), np.asarray(res.rgb_odd)] + [
                0.5 * (np.asarray(getattr(res, f"{k}_even")) + np.asarray(getattr(res, f"{k}_odd")))
                for k in ("albedo", "normal", "depth")]
            t = time.perf_counter()
            denoise(*bufs)
            denoise_s.append(time.perf_counter() - t)
        threads = int(res.stats["threads"])
        h, w = np.asarray(res.rgb).shape[:2]
        mp = w * h / 1e6
        r, d = statistics.median(render_s), statistics.median(denoise_s)
        print(f"scene={name} width={w} height={h} spp={args.spp} threads={threads} render_s={r:.4f} "
              f"denoise_s={d:.4f} ratio={d / r:.3f} target_ratio=0.2 core_s_per_mp={threads * d / mp:.2f} "
              f"oidn_core_s_per_mp={OIDN_CORE_S_PER_MP}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
