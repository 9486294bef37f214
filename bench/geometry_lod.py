#!/usr/bin/env python3
"""Levels of detail of library models (docs/geometry_lod.md): the first frames of
scenarios/vehicles.yaml (TORCS cars whose entries list coarser versions) rendered with every
model at its finest level (render.geometry_lod 0) and with the coarsest level whose geometric
error projects under half a pixel (0.5, the default), the same seed. Prints per frame the levels
chosen, the triangles and mesh bytes of the shown models, both render times, and each model's
mask IoU against the finest; then the totals, the last three lines exactly

    triangles_saved_pct=<float>   (share of the shown models' triangles the levels saved)
    render_time_ratio=<float>     (median over frames of render time with levels / finest)
    min_mask_iou=<float>          (lowest IoU of a model's instance mask against the finest's)

Needs the TORCS assets (`synthgen assets fetch mesh/torcs-p406 mesh/torcs-155-DTM
mesh/torcs-baja-bug`).

    .venv/bin/python bench/geometry_lod.py [--frames 16] [--spp 64]
"""
from __future__ import annotations

import argparse
import os
import statistics
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
    ap.add_argument("--frames", type=int, default=16)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--max-px", type=float, default=0.5, help="render.geometry_lod of the second render")
    args = ap.parse_args(argv)

    def renderer(max_px: float) -> FrameRenderer:
        sc = load_scenario(SCENARIO, overrides=[("render.spp", args.spp), ("render.geometry_lod", max_px)])
        check_inputs(sc)
        return FrameRenderer(sc)

    finest, lod = renderer(0.0), renderer(args.max_px)
    print(f"scenario: {os.path.relpath(SCENARIO, REPO)} frames 0..{args.frames - 1}, 640x480, {args.spp} spp, "
          f"geometry_lod 0 vs {args.max_px}")
    tri_finest = tri_used = bytes_finest = bytes_used = 0
    ratios, ious = [], []
    for k in range(args.frames):
        a, _, t_a = finest.render(k)
        b, meta, t_b = lod.render(k)
        g = meta.get("geometry_lod")
        if g is None:
            print(f"frame {k}: no model with levels of detail shown")
            continue
        tri_finest += g["triangles_finest"]
        tri_used += g["triangles"]
        bytes_finest += g["mesh_bytes_finest"]
        bytes_used += g["mesh_bytes"]
        ratios.append(t_b["render_s"] / t_a["render_s"])
        frame_ious = []
        for obj, level in sorted(g["levels"].items(), key=lambda kv: int(kv[0])):
            iid = int(obj) + 1
            ma, mb = a["instance_id"] == iid, b["instance_id"] == iid
            union = int(np.count_nonzero(ma | mb))
            if union == 0:
                continue
            iou = np.count_nonzero(ma & mb) / union
            frame_ious.append(f"{obj}:L{level} {iou:.4f} ({int(np.count_nonzero(ma))} px)")
            ious.append(iou)
        print(f"frame {k}: triangles {g['triangles_finest']} finest, {g['triangles']} used; "
              f"render {t_a['render_s']:.2f} s finest, {t_b['render_s']:.2f} s levels; mask IoU "
              f"{', '.join(frame_ious) or '-'}", flush=True)
    if not ratios:
        print("no frame showed a model with levels of detail")
        return 1
    print(f"shown models over {len(ratios)} frames: {tri_finest} triangles at the finest level, {tri_used} used; "
          f"mesh arrays {bytes_finest / 2**20:.2f} MiB finest, {bytes_used / 2**20:.2f} MiB used")
    print(f"triangles_saved_pct={100.0 * (1 - tri_used / tri_finest):.1f}")
    print(f"render_time_ratio={statistics.median(ratios):.3f}")
    print(f"min_mask_iou={min(ious):.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
