#!/usr/bin/env python3
"""Cost of wear effects (a script that prints figures, not a test).

The seed's Table 3 experiment: the render time of a scene with a grey diffuse model against
the same scene with the model rusted, and with it scratched (synthgen.wear presets), measured
in one run (interleaved, best of --runs). The scene: the Kenney truck (../shared/assets/kenney,
a glTF model without usable uvs for wear: the presets use object / relative-local mappings)
scaled to 4 m, on a ground plane under a physical sky, 640x480, 32 spp, max_depth 6, the
model covering about a quarter of the image; all threads. The last lines are exactly
``rust_overhead_pct=<float>`` and ``scratches_overhead_pct=<float>``.

    .venv/bin/python bench/wear_overhead.py [--runs 3] [--spp 32]
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "python"))

import synthgen as sg  # noqa: E402
from synthgen import primitives as P, wear  # noqa: E402

TRUCK = os.path.join(REPO, "..", "shared", "assets", "kenney", "vehicle-truck-red.glb")


def build(effect: str, width: int, height: int) -> tuple:
    s = sg.Scene()
    g = P.plane(60.0, 60.0)
    s.add_instance(s.add_mesh(g["positions"], g["indices"], normals=g["normals"]), np.eye(4),
                   material_id=s.add_material("diffuse", {"albedo": 0.3}))
    if os.path.isfile(TRUCK):
        r = s.load_mesh_file(TRUCK)
        pos = np.asarray(s.mesh_arrays(r["mesh_id"])["positions"])
        ext = pos.max(axis=0) - pos.min(axis=0)
        k = 4.0 / float(ext.max())
        world = P.translate([0.0, -pos.min(axis=0)[1] * k, 0.0]) @ P.rotate([0, 1, 0], 35.0) @ P.scale(k)
        mesh, what = r["mesh_id"], "Kenney truck (glTF)"
    else:
        b = P.box((1.8, 1.5, 4.0))
        mesh, what = s.add_mesh(b["positions"], b["indices"], normals=b["normals"]), "box 1.8 x 1.5 x 4 m (../shared absent)"
        world = P.translate([0.0, 0.75, 0.0]) @ P.rotate([0, 1, 0], 35.0)
    grey = s.add_material("diffuse", {"albedo": 0.5})
    mat = grey if effect == "grey" else getattr(wear, effect)(s, grey, seed=1)
    s.add_instance(mesh, world, class_id=1, material_id=mat)
    s.add_light("sky", {"elevation": 40.0, "azimuth": 130.0, "turbidity": 3.0, "strength": 0.02})
    pose = sg.PinholeCamera.look_at((3.0, 2.2, -4.8), (0.0, 0.9, 0.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(40.0, width, height, pose))
    s.commit()
    return s, what


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    args = ap.parse_args(argv)
    sg.load_image_plugin()
    scenes = {}
    for e in ("grey", "rust", "scratches"):
        scenes[e], what = build(e, args.width, args.height)
    cover = float((scenes["grey"].render(spp=1, labels_only=True).instance_id == 2).mean())
    print(f"scene: {what} on a ground plane under a sky, {args.width}x{args.height}, {args.spp} spp, max_depth 6, "
          f"model covers {100 * cover:.1f}% of the image; best of {args.runs} interleaved runs")
    best = {e: float("inf") for e in scenes}
    for _ in range(args.runs):
        for e, s in scenes.items():
            t = s.render(spp=args.spp, max_depth=6, seed=1).stats["wall_time_s"]
            best[e] = min(best[e], t)
    for e in scenes:
        print(f"{e}_render_s={best[e]:.3f}")
    print(f"rust_overhead_pct={100.0 * (best['rust'] / best['grey'] - 1.0):.1f}")
    print(f"scratches_overhead_pct={100.0 * (best['scratches'] / best['grey'] - 1.0):.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
