"""``bench/vs_cycles.py --check``: the camera, light and bounce conversions between synthgen and
Cycles, verified numerically on small scenes rendered by both."""

import math
import os
import tempfile

import numpy as np

from vs_cycles_common import _fmt, mean_diff_pct
from vs_cycles_scenes import (CBOX_DIR, HDR_DIR, _camera_entry, _mesh_entry, _rows, _sg, available_plugins, build_spec,
    envmap_params, synthgen_render)
from synthgen.bench.peers import run_cycles  # (vs_cycles_scenes puts python/ on sys.path)

# ---------------------------------------------------------------------------------------------
# --check: conversions verified numerically


def _quad_facing(centre, normal, size, a=None) -> dict:
    """Square of side `size` centred at `centre`, front face (counter-clockwise) towards `normal`,
    one edge along `a` (any perpendicular direction if None)."""
    c = np.asarray(centre, np.float64)
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    if a is None:
        a = np.cross(n, [0.0, 1.0, 0.0] if abs(n[1]) < 0.9 else [1.0, 0.0, 0.0])
    a = np.asarray(a, np.float64) - n * np.dot(a, n)
    a /= np.linalg.norm(a)
    b = np.cross(n, a)  # (a, b, n) right-handed: counter-clockwise seen from +n
    h = 0.5 * size
    p = [c - h * a - h * b, c + h * a - h * b, c + h * a + h * b, c - h * a + h * b]
    return {"positions": np.array(p), "indices": np.array([[0, 1, 2], [0, 2, 3]]), "normals": None}


def _check_spec(name, width, height, camera, meshes, materials, instances, lights, max_depth):
    return {"name": name, "width": width, "height": height, "max_depth": max_depth, "camera": _camera_entry(camera),
            "meshes": meshes, "materials": materials, "instances": instances, "lights": lights}


def run_check(args, blender: str) -> int:
    sg = _sg()
    from synthgen import primitives as P

    spp, ok_all = 64, True
    eye4 = _rows(np.eye(4))

    def both(spec, tag, n=None, **cy_extra):
        n = n or spp
        s = dict(spec, spp=n, seed=3, threads=args.threads)
        sg_img, _ = synthgen_render(s, n, seed=3, threads=args.threads)
        cy_img, _ = run_cycles(dict(s, output=os.path.join(work, f"{tag}.exr"), **cy_extra), work, tag, blender)
        return sg_img.astype(np.float64), cy_img.astype(np.float64)

    def verdict(ok):
        nonlocal ok_all
        ok_all &= bool(ok)
        return "ok" if ok else "FAIL"

    with tempfile.TemporaryDirectory(prefix="vs_cycles_check_") as work:
        # 1. Camera: three small one-sided emitters (R, G, B) seen directly on a landscape (96x64)
        #    and a portrait (64x96) image with an off-centre principal point and a tilted pose; the
        #    radiance centroid of each channel must be the exact centroid of the emitter's
        #    box-filtered projection (OpenCV convention, pixel centres at +0.5) up to the sampling
        #    noise of the edge pixels (~0.01 px at 1024 spp).
        def overlap(lo, hi, n):
            k = np.arange(n, dtype=np.float64)
            return np.clip(np.minimum(hi, k + 1) - np.maximum(lo, k), 0.0, None)

        for W, H, cx, cy in ((96, 64, 41.3, 36.7), (64, 96, 36.7, 41.3)):
            eye = np.array([0.4, 1.1, -3.0])
            wfc = sg.PinholeCamera.look_at(eye.tolist(), [0.1, 0.3, 0.5], [0.15, 1.0, 0.0])
            cam = sg.PinholeCamera(70.0, 70.0, cx, cy, W, H, wfc)
            pts = [np.array(wfc[:3, :3] @ v + wfc[:3, 3], np.float64)
                   for v in ([-0.55, -0.3, 3.0], [0.45, 0.2, 2.6], [0.05, 0.32, 3.4])]
            # Parallel to the image plane (facing the camera's -z) with edges along the camera's x
            # and y, so each projects to an axis-aligned square [u0, u1] x [v0, v1] whose exact pixel
            # coverage gives the expected centroid of the box-filtered image.
            side = 0.12
            meshes = [_mesh_entry(f"q{i}", _quad_facing(p, -wfc[:3, 2], side, a=wfc[:3, 0])) for i, p in enumerate(pts)]
            mats = [{"type": "emissive", "params": {"radiance": c}} for c in ([1, 0, 0], [0, 1, 0], [0, 0, 1])]
            inst = [{"mesh": i, "material": i, "world_from_object": eye4} for i in range(3)]
            sgi, cyi = both(_check_spec("check_camera", W, H, cam, meshes, mats, inst, [], 1), "camera", n=1024)
            yy, xx = np.mgrid[0:H, 0:W] + 0.5
            areas = []
            for ch, p in enumerate(pts):
                u, v = cam.project(p.tolist())
                z = float(np.dot(p - wfc[:3, 3], wfc[:3, 2]))
                hu, hv = 0.5 * side * cam.fx / z, 0.5 * side * cam.fy / z
                cov = np.outer(overlap(v - hv, v + hv, H), overlap(u - hu, u + hu, W))
                areas.append(cov.sum())
                u, v = float((cov * xx).sum() / cov.sum()), float((cov * yy).sum() / cov.sum())
                cs = [(float((img[..., ch] * xx).sum() / img[..., ch].sum()),
                       float((img[..., ch] * yy).sum() / img[..., ch].sum())) for img in (sgi, cyi)]
                err = max(math.hypot(c[0] - u, c[1] - v) for c in cs)
                print(f"check camera {W}x{H} emitter {'RGB'[ch]}: exact ({u:.3f}, {v:.3f})  synthgen centroid "
                      f"({cs[0][0]:.3f}, {cs[0][1]:.3f})  Cycles centroid ({cs[1][0]:.3f}, {cs[1][1]:.3f})  "
                      f"max err {err:.3f} px {verdict(err < 0.03)}")
            # Emitted radiance seen directly (radiance 1 per channel): image sum = projected area in pixels.
            rel = [img.sum(axis=(0, 1)) / np.array(areas) - 1.0 for img in (sgi, cyi)]
            print(f"check camera {W}x{H} emitter radiance x area: synthgen/exact - 1 = {_fmt(100 * rel[0])} %  "
                  f"Cycles/exact - 1 = {_fmt(100 * rel[1])} % {verdict(all(np.all(np.abs(r) < 0.01) for r in rel))}")

        # 2. Sun: white-ish Lambertian plane facing the sun, E = 2 W/m^2 -> L = rho E / pi.
        d = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
        Rm = np.eye(4)
        y = d
        x = np.cross(y, [0, 0, 1.0]); x /= np.linalg.norm(x)
        z = np.cross(x, y)
        Rm[:3, :3] = np.stack([x, y, z], axis=1)
        rho, E = 0.8, 2.0
        cam2 = sg.PinholeCamera.from_fov(20.0, 32, 32, sg.PinholeCamera.look_at((3.0 * d + 0.4 * x).tolist(), [0, 0, 0],
                                                                                z.tolist()))
        spec = _check_spec("check_sun", 32, 32, cam2, [_mesh_entry("plane", P.plane(20, 20))],
                           [{"type": "diffuse", "params": {"albedo": [rho] * 3}}],
                           [{"mesh": 0, "material": 0, "world_from_object": _rows(Rm)}],
                           [{"type": "sun", "params": {"direction": d.tolist(), "irradiance": E, "angular_diameter": 0.53}}], 2)
        sgi, cyi = both(spec, "sun")
        want = rho * E / math.pi
        r = [img.mean() / want for img in (sgi, cyi)]
        print(f"check sun: rho E / pi = {want:.5f}  synthgen/expected = {r[0]:.5f}  Cycles/expected = {r[1]:.5f} "
              f"{verdict(all(abs(x - 1) < 0.005 for x in r))}")

        # 3. Point light: intensity I [W/sr] 2 m above a Lambertian plane; per pixel
        #    L = rho/pi * I cos(theta) / r^2 at the point the pixel centre sees.
        I, h = 5.0, 2.0
        wfc3 = sg.PinholeCamera.look_at([0.0, 3.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
        cam3 = sg.PinholeCamera.from_fov(30.0, 32, 32, wfc3)
        spec = _check_spec("check_point", 32, 32, cam3, [_mesh_entry("plane", P.plane(20, 20))],
                           [{"type": "diffuse", "params": {"albedo": [rho] * 3}}],
                           [{"mesh": 0, "material": 0, "world_from_object": eye4}],
                           [{"type": "point", "params": {"position": [0.0, h, 0.0], "intensity": I}}], 2)
        sgi, cyi = both(spec, "point")
        exp = np.zeros((32, 32))
        for j in range(32):
            for i in range(32):
                o, dr = cam3.generate_ray(i + 0.5, j + 0.5)
                t = -o[1] / dr[1]
                q = np.array(o) + t * np.array(dr)
                dl = np.array([0.0, h, 0.0]) - q
                r2 = dl @ dl
                exp[j, i] = rho / math.pi * I * (dl[1] / math.sqrt(r2)) / r2
        r = [img[..., 0].mean() / exp.mean() for img in (sgi, cyi)]
        print(f"check point light (Blender power = 4 pi I): synthgen/expected = {r[0]:.5f}  Cycles/expected = {r[1]:.5f} "
              f"{verdict(all(abs(x - 1) < 0.005 for x in r))}")

        # 4. Constant environment: an upward plane under a uniform sky of radiance Le: L = rho Le;
        #    the sky seen directly is Le.
        Le = [0.5, 0.4, 0.3]
        cam4 = sg.PinholeCamera.from_fov(40.0, 32, 32, sg.PinholeCamera.look_at([0.0, 2.0, -6.0], [0.0, 0.0, 6.0], [0, 1, 0]))
        spec = _check_spec("check_env", 32, 32, cam4, [_mesh_entry("plane", P.plane(1000, 1000))],
                           [{"type": "diffuse", "params": {"albedo": [rho] * 3}}],
                           [{"mesh": 0, "material": 0, "world_from_object": eye4}],
                           [{"type": "environment", "params": {"radiance": Le}}], 2)
        sgi, cyi = both(spec, "env")
        ground = slice(20, 32)  # rows below the horizon see the plane near the camera
        sky = slice(0, 4)
        for what, rows, want in (("plane", ground, rho * np.array(Le)), ("sky", sky, np.array(Le))):
            r = [img[rows].mean(axis=(0, 1)) / want for img in (sgi, cyi)]
            print(f"check environment {what}: synthgen/expected = {_fmt(r[0])}  Cycles/expected = {_fmt(r[1])} "
                  f"{verdict(all(np.all(np.abs(x - 1) < 0.005) for x in r))}")

        # 5. Environment map orientation: the map seen directly (max_depth 1) by a tilted wide-angle
        #    camera, with a non-zero rotation; the images must agree pixel by pixel up to noise
        #    (both read the nearest map pixel), and a sphere lit only by the map must agree in mean.
        plugins = available_plugins()
        if "envmap" in plugins["light"]:
            hdr = os.path.join(HDR_DIR, "courtyard.exr")
            lt = [{"type": "envmap", "params": envmap_params({"filename": hdr, "rotation": 40.0})}]
            for k, (target, up) in enumerate((([1.0, 0.3, 0.4], [0, 1, 0]), ([-0.3, -0.2, -1.0], [0.2, 1, 0]))):
                cam5 = sg.PinholeCamera.from_fov(90.0, 64, 48, sg.PinholeCamera.look_at([0, 0, 0], target, up))
                far = _quad_facing([0, 0, -1e4], [0, 0, 1], 1.0)  # out of view: the scene needs an instance
                spec = _check_spec("check_envmap", 64, 48, cam5, [_mesh_entry("far", far)],
                                   [{"type": "diffuse", "params": {"albedo": [0.5] * 3}}],
                                   [{"mesh": 0, "material": 0, "world_from_object": eye4}], lt, 1)
                sgi, cyi = both(spec, f"envmap{k}", n=256)
                rel = float(np.abs(cyi - sgi).mean() / sgi.mean())
                mirrored = float(np.abs(cyi[:, ::-1] - sgi).mean() / sgi.mean())
                print(f"check envmap seen directly, view {k}: mean |Cycles - synthgen| / mean = {100 * rel:.2f} % "
                      f"(mirrored image: {100 * mirrored:.1f} %) {verdict(rel < 0.02 and mirrored > 5 * rel)}")
            cam6 = sg.PinholeCamera.from_fov(30.0, 48, 48, sg.PinholeCamera.look_at([0, 0.5, -4], [0, 0.5, 0], [0, 1, 0]))
            spec = _check_spec("check_envmap_lit", 48, 48, cam6, [_mesh_entry("sphere", P.uv_sphere(0.5, 64, 32))],
                               [{"type": "diffuse", "params": {"albedo": [0.8] * 3}}],
                               [{"mesh": 0, "material": 0, "world_from_object": _rows(P.translate([0, 0.5, 0]))}],
                               [{"type": "envmap", "params": envmap_params({"filename": hdr, "rotation": 40.0,
                                                                              "visible": False})}], 2)
            sgi, cyi = both(spec, "envmap_lit", n=2048)
            d = mean_diff_pct(cyi, sgi)
            print(f"check envmap lighting a Lambertian sphere (map hidden from the camera): Cycles vs synthgen "
                  f"{_fmt(d)} % {verdict(np.all(np.abs(d) < 1.0))}")

        # 6. Path length: Cornell box at max_depth 3 and 4; Cycles max_bounces = max_depth - 2 must
        #    match, max_depth - 1 (one bounce more) must not.
        if os.path.isdir(CBOX_DIR):
            for depth in (3, 4):
                spec = dict(build_spec("cbox", 128, 128), max_depth=depth)
                s = dict(spec, spp=256, seed=3, threads=args.threads)
                sgi, _ = synthgen_render(s, 256, seed=3, threads=args.threads)
                cy_a, _ = run_cycles(dict(s, output=os.path.join(work, "cb_a.exr")), work, "cb_a", blender)
                cy_b, _ = run_cycles(dict(s, output=os.path.join(work, "cb_b.exr"), cycles_max_bounces=depth - 1),
                                     work, "cb_b", blender)
                da, db = mean_diff_pct(cy_a, sgi), mean_diff_pct(cy_b, sgi)
                print(f"check cbox max_depth {depth}: Cycles max_bounces {depth - 2} vs synthgen {_fmt(da)} %, "
                      f"max_bounces {depth - 1}: {_fmt(db)} % {verdict(np.all(np.abs(da) < 1.0) and np.abs(db).min() > 3 * np.abs(da).max())}")
    print(f"check_ok={int(ok_all)}")
    return 0 if ok_all else 1


