"""Renders Embree's tutorial Cornell box (embree-tools) with synthgen.

Used by bench/pt_vs_embree.sh. Mirrors `pathtracer -c cornell_box.ecs`: the OBJ with
its MTL diffuse colours (Kd), the point light of the .ecs file, the camera
(-vp 278 273 -800 -vi 278 273 0 -vu 0 1 0 -fov 37, vertical field of view).
Embree's --max-path-length L counts surface interactions (1 = primary + shadow ray);
synthgen's max_depth counts ray segments, so max_depth = L + 1 gives the same paths.

Prints one line of key=value figures; the whole-process time is measured outside.
"""
import argparse
import json
import sys
import time

import numpy as np

import synthgen as sg


def build_scene(light: str):
    """The scene and world_from_camera (shared with ``synthgen bench``: synthgen.bench.peers)."""
    from synthgen.bench.peers import embree_cbox_scene

    return embree_cbox_scene(light)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--max-path-length", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--light", choices=["point", "area"], default="point")
    ap.add_argument("-o", "--output", default="")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    scene, wfc = build_scene(args.light)
    scene.set_camera(sg.PinholeCamera.from_fov(37.0, args.size, args.size, wfc))
    scene.commit()
    t1 = time.perf_counter()
    result = scene.render(spp=args.spp, max_depth=args.max_path_length + 1, threads=args.threads)
    t2 = time.perf_counter()
    if args.output:
        # Binary PPM, 8-bit, clamped like Embree's own `-o file.ppm` output.
        rgb = (np.clip(result.rgb, 0.0, 1.0) * 255.0).astype(np.uint8)
        with open(args.output, "wb") as f:
            f.write(b"P6\n%d %d\n255\n" % (args.size, args.size))
            f.write(rgb.tobytes())
    st = result.stats
    print(json.dumps({"build_s": t1 - t0, "render_s": t2 - t1, "rays_per_s": st["rays_per_s"],
                      "samples_per_s": st["samples_per_s"], "mean": [float(x) for x in result.rgb.mean(axis=(0, 1))]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
