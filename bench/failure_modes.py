#!/usr/bin/env python3
"""Scenes where synthgen's methods fail, shared by the failure-mode tests
(tests/python/test_failure_*.py) and docs/failure_modes.md, and the script that renders the
document's images and the one reference they need:

    .venv/bin/python bench/failure_modes.py --reference   # tests/python/references/quality/caustic.exr
    .venv/bin/python bench/failure_modes.py --images      # docs/failure_denoiser.png, failure_adaptive.png, failure_mix.png

- ``detail_scene('plate' | 'scratches')``: fine detail for the denoiser;
- ``caustic_scene()``: a glass ball's sun caustic on the ground, for adaptive sampling;
- ``mirror_rust_scene(stochastic)``: a rusty box on a mirror floor, for the stochastic mix."""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(REPO, "python"))
sys.path.insert(0, HERE)

import synthgen as sg  # noqa: E402
from synthgen import primitives as P  # noqa: E402
from synthgen.scene import plates, wear  # noqa: E402

LUMA = np.array([0.2126, 0.7152, 0.0722])
SIZE = (128, 96)
CAUSTIC_DEPTH = 8
CAUSTIC_REF = os.path.join(REPO, "tests", "python", "references", "quality", "caustic.exr")
CAUSTIC_REF_SEED = 918273


def _ground(s: "sg.Scene", material: int) -> None:
    g = P.ground()
    s.add_instance(s.add_mesh(g["positions"], g["indices"], normals=g["normals"]), np.eye(4), material_id=material)


def detail_scene(kind: str, width: int = SIZE[0], height: int = SIZE[1]) -> "sg.Scene":
    """`plate`: a Russian licence plate (image texture, principled) seen from 1.1 m, characters
    about 20 pixels tall; `scratches`: a glossy red coated panel with 1-2 pixel wide grooved
    aluminium scratches (wear.scratches, depth 1 mm), from above at 45 degrees. Both under a
    physical sky on a grey ground. Committed."""
    s = sg.Scene()
    _ground(s, s.add_material("diffuse", {"albedo": 0.25}))
    if kind == "plate":
        p = P.plane(0.52, 0.112)
        mesh = s.add_mesh(p["positions"], p["indices"], normals=p["normals"], uvs=p["uvs"])
        tex = plates.render_plate(plates.random_registration("ru", np.random.default_rng(4)), px_per_mm=4.0)
        rgb = np.ascontiguousarray(np.asarray(tex["rgb"], np.float32)[:, ::-1])  # the plane's u runs leftwards here
        col = s.add_image_texture(rgb, {"wrap": "clamp", "colorspace": "linear"})
        mat = s.add_material("principled", {"base_color": sg.TextureRef(col), "roughness": 0.35})
        T = np.array(P.rotate([1, 0, 0], -90.0), float)
        T[1, 3] = 0.4
        s.add_instance(mesh, T, class_id=1, instance_id=1, material_id=mat)
        pose = sg.PinholeCamera.look_at((0.15, 0.5, -1.1), (0.0, 0.4, 0.0), (0.0, 1.0, 0.0))
        fov = 24.0
    elif kind == "scratches":
        p = P.plane(1.0, 1.0)
        mesh = s.add_mesh(p["positions"], p["indices"], normals=p["normals"], uvs=p["uvs"])
        paint = s.add_material("coated", {"albedo": [0.5, 0.05, 0.05], "roughness": 0.1, "ior": 1.5})
        mat = wear.scratches(s, paint, density=6.0, width=0.02, seed=3, roughness=0.2, depth=0.001)
        T = np.eye(4)
        T[1, 3] = 0.01
        s.add_instance(mesh, T, class_id=1, instance_id=1, material_id=mat)
        pose = sg.PinholeCamera.look_at((0.0, 1.2, -1.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
        fov = 40.0
    else:
        raise ValueError(f"detail_scene: unknown kind {kind!r} (plate, scratches)")
    s.add_light("sky", {"elevation": 35.0, "azimuth": 150.0, "turbidity": 3.0, "strength": 0.02})
    s.set_camera(sg.PinholeCamera.from_fov(fov, width, height, pose))
    s.commit()
    return s


def caustic_scene(width: int = SIZE[0], height: int = SIZE[1]) -> "sg.Scene":
    """A smooth glass ball (radius 0.3 m, ior 1.5) on a grey diffuse ground under the sun (0.53
    degrees, irradiance 3) and a dim uniform sky (0.3): the ball focuses the sun into a small
    caustic inside its shadow, found only by paths that leave the ground in the right direction
    and hit the sun through the glass (next-event estimation cannot see the sun through glass).
    Committed; render with max_depth CAUSTIC_DEPTH."""
    s = sg.Scene()
    _ground(s, s.add_material("diffuse", {"albedo": 0.5}))
    sp = P.uv_sphere(0.3)
    s.add_instance(s.add_mesh(sp["positions"], sp["indices"], normals=sp["normals"]), P.translate([0, 0.3, 0]),
                   class_id=1, instance_id=1, material_id=s.add_material("dielectric", {"ior": 1.5, "roughness": 0.0}))
    s.add_light("sun", {"direction": [0.5, 1.0, 0.3], "irradiance": 3.0, "angular_diameter": 0.53})
    s.add_light("environment", {"radiance": 0.3})
    pose = sg.PinholeCamera.look_at((0.0, 1.4, -1.6), (-0.15, 0.1, 0.1), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(20.0, width, height, pose))
    s.commit()
    return s


def caustic_pixels(ref: np.ndarray) -> np.ndarray:
    """The caustic in a converged render of caustic_scene: pixels of luminance > 2 (the lit
    ground is about 0.6, the shadow 0.15) with at least two such neighbours (isolated bright
    pixels are the reference's own remaining fireflies)."""
    hot = (ref @ LUMA) > 2.0
    h, w = hot.shape
    p = np.pad(hot, 1)
    neighbours = sum(p[1 + dy:1 + dy + h, 1 + dx:1 + dx + w].astype(int)
                     for dy in (-1, 0, 1) for dx in (-1, 0, 1)) - hot
    return hot & (neighbours >= 2)


def mirror_rust_scene(stochastic: bool, glossy_paint: bool = False, width: int = SIZE[0], height: int = SIZE[1]) -> "sg.Scene":
    """A 1 m box, blue paint (diffuse, or coated with ``glossy_paint``) with the rust preset
    (amount 0.5) on a mirror floor (smooth silver: a puddle, a wet road), sun and a dim sky;
    the camera sees the box and its reflection. The rust's mix is ``stochastic`` (the preset's
    default) or the exact blend. Committed."""
    s = sg.Scene()
    _ground(s, s.add_material("conductor", {"metal": "silver", "roughness": 0.0}))
    if glossy_paint:
        paint = s.add_material("coated", {"albedo": [0.2, 0.35, 0.6], "roughness": 0.1, "ior": 1.5})
    else:
        paint = s.add_material("diffuse", {"albedo": [0.2, 0.35, 0.6]})
    mat = wear.rust(s, paint, seed=2, amount=0.5, scale=2.0, stochastic=stochastic)
    b = P.box((1.0, 1.0, 1.0))
    s.add_instance(s.add_mesh(b["positions"], b["indices"], normals=b["normals"], uvs=b.get("uvs")),
                   P.translate([0, 0.5, 0]) @ P.rotate([0, 1, 0], 30), class_id=1, instance_id=1, material_id=mat)
    s.add_light("sun", {"direction": [-0.6, 0.8, -0.4], "irradiance": 3.0, "angular_diameter": 0.53})
    s.add_light("environment", {"radiance": 0.2})
    pose = sg.PinholeCamera.look_at((1.4, 0.7, -3.4), (0.0, 0.1, 0.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(45.0, width, height, pose))
    s.commit()
    return s


def mirror_pixels(scene: "sg.Scene"):
    """(the box seen directly, its reflection in the floor) of mirror_rust_scene, as pixel masks:
    the box from the class label; the reflection as the floor's pixels (label normal up) whose
    64-spp luminance differs by more than 20% from the floor's median (the sky reflected) and
    is below 1 (not the sun's disc, reflected)."""
    lab = scene.render(spp=1, labels_only=True)
    box = np.asarray(lab.class_id) == 1
    floor = ~box & (np.asarray(lab.normal)[..., 1] > 0.9)
    y = np.asarray(scene.render(spp=64, max_depth=4, seed=1).rgb, np.float64) @ LUMA
    med = float(np.median(y[floor]))
    return box, floor & (np.abs(y - med) > 0.2 * med) & (y < 1.0)


def read_exr(path: str) -> np.ndarray:
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise RuntimeError(f"{path}: {buf.geterror()}")
    return buf.get_pixels(oiio.FLOAT)[..., :3]


def _display(img: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """Linear RGB -> 8-bit sRGB-ish (gamma 2.2) for the document's images."""
    return (np.clip(np.asarray(img, np.float64) * scale, 0.0, 1.0) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)


def _zoom(img: np.ndarray, k: int) -> np.ndarray:
    return np.repeat(np.repeat(img, k, axis=0), k, axis=1)


def _write_png(path: str, rows) -> None:
    """Tiles (lists of equal-height uint8 images, with a 4-pixel white gap) to a PNG."""
    import OpenImageIO as oiio

    def hcat(tiles):
        gap = np.full((tiles[0].shape[0], 4, 3), 255, np.uint8)
        out = [tiles[0]]
        for t in tiles[1:]:
            out += [gap, t]
        return np.concatenate(out, axis=1)

    lines = [hcat(r) for r in rows]
    width = max(x.shape[1] for x in lines)
    lines = [np.pad(x, ((0, 4), (0, width - x.shape[1]), (0, 0)), constant_values=255) for x in lines]
    img = np.ascontiguousarray(np.concatenate(lines, axis=0)[:-4])
    buf = oiio.ImageBuf(oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.UINT8))
    buf.set_pixels(oiio.ROI(), img)
    if not buf.write(path):
        raise RuntimeError(f"cannot write {path}: {buf.geterror()}")
    print(f"wrote {path}")


def images(out_dir: str) -> None:
    """docs/failure_denoiser.png: per detail scene, reference | raw 16 spp | denoised 16 spp
    (crops, 3x); docs/failure_adaptive.png: caustic reference | adaptive (threshold 0.01,
    min_spp 16) | its sample counts | min_spp 256; docs/failure_mix.png: the mirror floor's
    reflection at 16 spp (clamp_indirect 3), exact | stochastic, and below each its error x 10
    against 1024 spp."""
    rows = []
    for kind, crop in (("plate", (slice(20, 76), slice(0, 128))), ("scratches", (slice(36, 92), slice(16, 88)))):
        s = detail_scene(kind)
        ref = np.asarray(s.render(spp=1024, max_depth=4, seed=9).rgb)
        scale = 0.18 / float(np.median(ref @ LUMA))
        r = s.render(spp=16, max_depth=4, seed=72, denoise=True)
        rows.append([_zoom(_display(x, scale)[crop], 3) for x in (ref, np.asarray(r.rgb_noisy), np.asarray(r.rgb))])
    _write_png(os.path.join(out_dir, "failure_denoiser.png"), rows)

    s = caustic_scene()
    ref = read_exr(CAUSTIC_REF)
    crop = (slice(40, 96), slice(8, 104))
    a = s.render(spp=1024, max_depth=CAUSTIC_DEPTH, seed=71, noise_threshold=0.01, min_spp=16)
    b = s.render(spp=1024, max_depth=CAUSTIC_DEPTH, seed=71, noise_threshold=0.01, min_spp=256)
    counts = np.log2(np.asarray(a.sample_count, np.float64)) / 10.0  # 1 .. 1024 spp -> 0 .. 1
    heat = np.stack([counts, counts, counts], axis=-1) ** 2.2
    _write_png(os.path.join(out_dir, "failure_adaptive.png"),
               [[_zoom(_display(x)[crop], 3) for x in (ref, np.asarray(a.rgb), heat, np.asarray(b.rgb))]])

    crop = (slice(54, 96), slice(36, 92))
    ref = np.asarray(mirror_rust_scene(False).render(spp=1024, max_depth=4, seed=5, clamp_indirect=3.0).rgb)
    shots, errors = [], []
    for stochastic in (False, True):
        r = np.asarray(mirror_rust_scene(stochastic).render(spp=16, max_depth=4, seed=71, clamp_indirect=3.0).rgb)
        shots.append(_zoom(_display(r, 2.5)[crop], 4))
        err = np.abs(r - ref).mean(axis=-1, keepdims=True) * 10.0  # x 10 (before the display's gamma)
        errors.append(_zoom(_display(np.repeat(err, 3, axis=-1))[crop], 4))
    _write_png(os.path.join(out_dir, "failure_mix.png"), [shots, errors])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reference", action="store_true", help=f"render {CAUSTIC_REF}")
    ap.add_argument("--spp", type=int, default=8192, help="the reference's samples per pixel")
    ap.add_argument("--images", action="store_true", help="render the document's images")
    ap.add_argument("--out", default=os.path.join(REPO, "docs"), help="where --images writes")
    args = ap.parse_args(argv)
    if not (args.reference or args.images):
        ap.error("nothing to do: --reference and/or --images")
    if args.reference:
        from quality_references import write_exr

        t0 = time.perf_counter()
        res = caustic_scene().render(spp=args.spp, max_depth=CAUSTIC_DEPTH, seed=CAUSTIC_REF_SEED)
        write_exr(CAUSTIC_REF, np.asarray(res.rgb), {"spp": args.spp, "seed": CAUSTIC_REF_SEED, "max_depth": CAUSTIC_DEPTH})
        print(f"caustic: {args.spp} spp in {time.perf_counter() - t0:.1f} s, "
              f"{int(caustic_pixels(np.asarray(res.rgb)).sum())} caustic pixels -> {CAUSTIC_REF}")
    if args.images:
        images(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
