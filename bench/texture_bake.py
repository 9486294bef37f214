#!/usr/bin/env python3
"""Procedural textures baked at the resolution the camera needs (`bake: auto`,
docs/texture_lod.md) against evaluating them per lookup: a wall (6 x 3 m, 8 m away) with a uv-mapped
fbm noise of 8 octaves as its albedo and a cellular pattern as its roughness, seen from a car's
height at 640 x 480. Renders each way in turn (the same seed), then prints the median frame
times -- the baked one including the estimate and the bake, which happen every frame -- the
baked image sizes and the PSNR of the baked render against the evaluated one (both scaled so
that the evaluated image's 99th percentile is white). Then the same for
a road (a 40 m plane of the same textures, from 1.5 m): its nearest pixels need texels so fine
that one image of the whole road seen would exceed 4096 texels a side, so it is not baked
(docs/texture_lod.md). The last two lines are exactly, for the wall,

    bake_time_ratio=<float>   (median baked frame time / median evaluated frame time)
    bake_psnr_db=<float>

    .venv/bin/python bench/texture_bake.py [--spp 16] [--repeats 3]
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(REPO, "python"))


def scene(bake: str, kind: str):
    """The wall or the road, with both textures baked (bake: auto) or evaluated (off)."""
    from synthgen._core import PinholeCamera, Scene, TextureRef
    from synthgen.scene import primitives as P

    s = Scene()
    k = 10.0 if kind == "road" else 1.0  # texture scale per uv: the road's uvs span 40 m
    albedo = s.add_texture("noise", {"pattern": "fbm", "octaves": 8, "mapping": "uv", "scale": 40.0 * k,
                                     "bake": bake, "ramp_positions": [0.0, 1.0],
                                     "ramp_colors": [0.05, 0.05, 0.055, 0.45, 0.4, 0.35]})
    rough = s.add_texture("cellular", {"mapping": "uv", "scale": 60.0 * k, "bake": bake, "remap": [0.0, 1.5]})
    m = s.add_material("principled", {"base_color": TextureRef(albedo), "roughness": TextureRef(rough)})
    if kind == "road":
        pl = P.plane(40.0, 40.0)
        world = np.eye(4)
        eye, target = (0, 1.5, -15), (0, 0, 5)
    else:
        pl = P.plane(6.0, 3.0)
        world = P.translate([0.0, 1.5, 8.0]) @ P.rotate([1.0, 0.0, 0.0], -90.0)
        eye, target = (0, 1.5, 0), (0, 1.5, 8)
    mesh = s.add_mesh(pl["positions"], pl["indices"], normals=pl["normals"], uvs=pl["uvs"])
    s.add_instance(mesh, world, class_id=1, material_id=m)
    s.add_light("sky", {"elevation": 35.0})
    s.set_camera(PinholeCamera.from_fov(45.0, 640, 480, PinholeCamera.look_at(eye, target, (0, 1, 0))))
    s.commit()
    return s


def compare(kind: str, spp: int, repeats: int):
    """(median evaluated s, median baked s, PSNR dB, baked bytes, estimate-and-bake s)."""
    evaluated, baked = scene("off", kind), scene("auto", kind)
    times = {"evaluated": [], "baked": []}
    images = {}
    for _ in range(repeats):
        for name, sc in (("evaluated", evaluated), ("baked", baked)):
            r = sc.render(spp=spp, max_depth=4, seed=3, texture_lod=name == "baked")
            st = r.stats
            times[name].append(st["wall_time_s"] + st["texture_lod_time_s"])
            images[name] = (np.asarray(r.rgb), st)
    # Displayed: both scaled so that the evaluated image's 99th percentile is white (the sky's
    # radiance is in physical units), then clipped to [0, 1].
    a, b = images["evaluated"][0], images["baked"][0]
    white = float(np.percentile(a, 99))
    x, y = np.clip(a / white, 0, 1), np.clip(b / white, 0, 1)
    err = float(np.sum((x - y) ** 2))
    psnr = 10 * math.log10(x.size / err) if err > 0 else math.inf
    st = images["baked"][1]
    return (statistics.median(times["evaluated"]), statistics.median(times["baked"]), psnr,
            st["texture_baked_bytes"], st["texture_lod_time_s"])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    lines = {}
    for kind in ("road", "wall"):
        te, tb, psnr, nbytes, tl = compare(kind, args.spp, args.repeats)
        lines[kind] = (te, tb, psnr)
        print(f"{kind} 640x480, {args.spp} spp, {args.repeats} repeats each: median frame time evaluated {te:.2f} s, "
              f"baked {tb:.2f} s (estimate and bake {tl:.2f} s of it); baked images {nbytes / 2**20:.2f} MiB; "
              f"PSNR {psnr:.2f} dB", flush=True)
    te, tb, psnr = lines["wall"]
    print(f"bake_time_ratio={tb / te:.3f}")
    print(f"bake_psnr_db={psnr:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
