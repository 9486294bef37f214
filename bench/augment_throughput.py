#!/usr/bin/env python3
"""Throughput and camera matching of augmented photos (a script that prints figures, not a test).

Runs scenarios/augmented_road.yaml (vehicles inserted into dlib's road photos, 928 x 478, the
first photo's size) with `synthgen run` (all outputs written, 1 worker: the render uses both
cores), prints frames/s and the mean seconds per stage (scene update, layout, path tracing with
the catcher, compositing + camera matching + labels, writing). Then, per inserted object, how
well its camera matches the photo's, measured on the written frame in a ring around the object:
its noise sigma (second differences, inside its mask where its albedo and normal are flat:
noise, not texture) against the photo's fitted noise at the same level, and the sharpness of
the ring (the object's edges and the photo around) against the
photo's; medians over the objects. The last line is exactly
``augmented_frames_per_second=<float>``.

    .venv/bin/python bench/augment_throughput.py [--frames 8] [--set KEY=VALUE ...]
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "python"))

import numpy as np  # noqa: E402

from synthgen import read_dataset  # noqa: E402
from synthgen.cli import main as cli  # noqa: E402
from synthgen.post.photo.measure import flat_mask, ring_statistics, srgb  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=8, help="frames (default 8)")
    ap.add_argument("--scenario", default=os.path.join(REPO, "scenarios", "augmented_road.yaml"))
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a scenario override passed to synthgen run (e.g. to switch wear off and see "
                         "what dirt's texture does to the noise measure)")
    args = ap.parse_args(argv)
    tmp = tempfile.mkdtemp(prefix="synthgen-augment-")
    try:
        out = os.path.join(tmp, "out")
        # Fetch the assets and read the photos before timing.
        assert cli(["validate", args.scenario]) == 0
        t0 = time.perf_counter()
        rc = cli(["run", args.scenario, "-o", out, "-n", str(args.frames), "--workers", "1", "--no-progress",
                  "--set", "outputs=[rgb, depth, instance, semantic, coco, yolo, kitti, albedo, normal]"] +
                 [a for kv in args.set for a in ("--set", kv)])
        wall = time.perf_counter() - t0
        if rc != 0:
            print(f"synthgen run failed (exit status {rc})")
            return 1
        summary = json.load(open(os.path.join(out, "run_summary.json")))
        stages = ", ".join(f"{k[:-2]} {v:.2f}" for k, v in summary["stage_s"].items())
        print(f"{args.frames} frames of {os.path.basename(args.scenario)} at 928 x 478, 1 worker: {wall:.1f} s "
              f"({args.frames / wall:.3f} frames/s); mean seconds per frame by stage: {stages}")
        ds = read_dataset(out)
        noise, sharp = [], []
        for f in ds:
            bg = f.meta["background"]
            cm = bg["camera_match"]
            img = srgb(f.rgb)
            for o in f.objects:
                x, y, w, h = o["bbox"]
                if o["visible_pixels"] < 400:
                    continue
                st = ring_statistics(img, flat_mask(f.mask(o["instance_id"]), f.albedo, f.normal), (x, y, x + w, y + h), cm["noise"])
                r_sharp = st["ring_sharpness"] / cm["photo_sharpness"]
                if np.isfinite(st["noise_ratio"]):
                    noise.append(st["noise_ratio"])
                if np.isfinite(r_sharp):
                    sharp.append(r_sharp)
                print(f"  frame {f.index} object {o['instance_id']} ({o['class']}, {o['visible_pixels']} px): noise "
                      f"{st['noise']:.4f} vs photo {st['photo_noise']:.4f} (ratio {st['noise_ratio']:.2f}); ring "
                      f"sharpness {st['ring_sharpness']:.3f} vs photo {cm['photo_sharpness']:.3f} (ratio "
                      f"{r_sharp:.2f}); blur {cm.get('blur_per_object', {}).get(str(o['instance_id']), 0.0):.2f} px "
                      f"(< 0: sharpened), JPEG q {cm.get('jpeg_quality', 0):.0f}")
        noise, sharp = np.array(noise), np.array(sharp)
        print(f"ring noise ratio (object / photo): median {np.median(noise):.3f} over {len(noise)} objects, "
              f"{int((np.abs(noise - 1) <= 0.2).sum())} within 20%; ring sharpness ratio: median "
              f"{np.median(sharp):.3f} over {len(sharp)} objects, {int((np.abs(sharp - 1) <= 0.2).sum())} within 20%")
        print(f"augmented_frames_per_second={args.frames / wall:.4f}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
