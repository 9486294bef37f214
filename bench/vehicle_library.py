#!/usr/bin/env python3
"""Every vehicle of the asset library, the optional ones too (the TORCS cars: Debian torcs-data,
333 MB, downloaded once), rendered once each (a front three-quarter view, with plates where
the model has mounts and a palette colour where it names its paint), with what CI cannot
cover: each model's measured size (its labelled 3D box, length x width x height), triangle
count, and the seconds its first frame took (import, wheels, BVH, render). A script that
prints figures, not a test; writes a contact sheet with --sheet.

    .venv/bin/python bench/vehicle_library.py [--sheet out/vehicles.png]
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

from synthgen import run as runner  # noqa: E402
from synthgen.scene import assets  # noqa: E402

CLASSES = ("car", "van", "truck", "bus", "motorcycle")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sheet", help="write a contact sheet (PNG) of the renders here")
    args = ap.parse_args(argv)
    m = assets.load_manifest()
    ids = sorted(k for k, e in m.items() if e["kind"] == "mesh" and e.get("class") in CLASSES)
    tmp = tempfile.mkdtemp(prefix="synthgen-vehicles-")
    tiles = []
    try:
        for aid in ids:
            e = m[aid]
            assets.resolve(aid)  # fetch first: not timed
            extra = ""
            if e.get("plates"):
                extra += ", plates: {country: ru}"
            if "paint" in (e.get("materials") or {}).values():
                extra += ", paint: {palette: cars}"
            scen = os.path.join(tmp, "s.yaml")
            with open(scen, "w") as f:
                f.write(f"""
seed: 3
resolution: [640, 480]
camera: {{fov_y: 30, pose: {{type: orbit, target: [0, 0.7, 0], distance: 11, elevation: 10, azimuth: 55}}}}
lights: [{{type: sky, elevation: 40, azimuth: 120, turbidity: 3, strength: 0.02}}]
ground: {{material: {{type: diffuse, albedo: 0.3}}}}
objects: [{{class: {e['class']}, asset: {aid}, yaw: 0{extra}}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 32, max_depth: 5}}
outputs: [rgb, instance, kitti]
""")
            out = os.path.join(tmp, aid.replace("/", "_"))
            t0 = time.perf_counter()
            s = runner.run(scen, out, count=1, progress=False)
            dt = time.perf_counter() - t0
            if s["failures"]:
                print(f"{aid}: failed: {s.text()}")
                continue
            meta = json.load(open(os.path.join(out, "meta", "000000.json")))
            o = meta["objects"][0]
            h, w, l = o["dimensions_hwl"]
            from synthgen._core import Scene

            sc = Scene()
            tris = len(sc.mesh_arrays(sc.load_mesh_file(assets.resolve(aid))["mesh_id"])["indices"])
            plates = o.get("plates", {}).get("text", "-")
            paint = o.get("paint", {}).get("colour", "own")
            print(f"{aid}: {e['class']}, {l:.2f} x {w:.2f} x {h:.2f} m (l x w x h), {tris} triangles (model), "
                  f"licence {e['licence']}; plates {plates}, paint {paint}; first frame {dt:.1f} s")
            if args.sheet:
                import OpenImageIO as oiio

                tiles.append(oiio.ImageBuf(os.path.join(out, "images", "000000.png")).get_pixels(oiio.FLOAT))
        print(f"vehicle_models={len(ids)}")
        if args.sheet and tiles:
            import OpenImageIO as oiio

            while len(tiles) % 3:
                tiles.append(np.zeros_like(tiles[0]))
            rows = [np.concatenate(tiles[i:i + 3], 1) for i in range(0, len(tiles), 3)]
            img = np.ascontiguousarray(np.concatenate(rows, 0)[::2, ::2])
            b = oiio.ImageBuf(oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.FLOAT))
            b.set_pixels(oiio.ROI(), img)
            os.makedirs(os.path.dirname(os.path.abspath(args.sheet)), exist_ok=True)
            b.write(args.sheet)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
