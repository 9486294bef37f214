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

MODELS = "/usr/share/doc/embree3/models"


def build_scene(light: str):
    scene = sg.Scene()
    imported = scene.load_mesh_file(f"{MODELS}/cornell_box.obj")
    scene.add_instance(imported["mesh_id"])
    if light == "point":
        # -pointlight 213 300 227 100000 100000 100000
        scene.add_light("point", {"position": [213.0, 300.0, 227.0], "intensity": [1e5, 1e5, 1e5]})
    else:
        # The box's own luminaire quad (y = 548, x 213..343, z 227..332) as an area light
        # emitting downwards, with the same total power as the point light (4 pi I = pi L A).
        area = 130.0 * 105.0
        radiance = 4.0 * 1e5 / area
        light_mat = scene.add_material("emissive", {"radiance": [radiance] * 3, "two_sided": True})
        p = np.array([[213, 547.9, 227], [343, 547.9, 227], [343, 547.9, 332], [213, 547.9, 332]], np.float32)
        mesh = scene.add_mesh(p, np.array([[0, 1, 2], [0, 2, 3]], np.uint32), name="luminaire")
        scene.add_instance(mesh, material_id=light_mat)
    world_from_camera = sg.PinholeCamera.look_at([278, 273, -800], [278, 273, 0], [0, 1, 0])
    return scene, world_from_camera


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
