"""Failure mode: the catcher ratio at object rims (docs/failure_modes.md).

Scene: a red diffuse box and a grey diffuse sphere on a ground with a checkerboard (0.1 / 0.6,
checks of 6.25 cm: 2-4 pixels), sun and sky. The "photo" is the scene rendered without the
objects (converged); the ground truth a converged render with them. The objects are inserted
by the shadow catcher (post/photo/composite.py, mode ``ratio``: O + P W / (Wo + B)) with the
catcher material the augmented-photo pipeline uses, a uniform albedo (here the texture's
mean), and, for comparison, with the true textured material.

The ratio W / (Wo + B) is the share of the pixel's light the objects leave, computed from
the catcher material. In a rim pixel (the object covers a fraction a) it is about (1 - a) x
shadow, so the composite scales the photo's *whole-pixel* value, which still holds the ground
the object now hides: the hidden part of a textured ground leaks into the rim (a fringe of the
wrong brightness). The error is a bias (it does not go with spp) and vanishes only if the
catcher reproduces the photo's texture below the pixel scale (then Wo + B = P in expectation
and P / (Wo + B) cancels). Shadows and the ground ring next to the objects are unaffected: the
ratio is taken per pixel, so the ground albedo cancels there.

Pixel classes (from the composite's render): rim 0 < synthetic_alpha < 1, ring: ground within
3 pixels of an object, interior: synthetic_alpha == 1, elsewhere: the other pixels the objects
change (shadows). Error: MSE against the ground truth, as a multiple of a direct render's MSE
at the same spp (seed and spp equal: the same noise level).
"""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P
from synthgen.post.photo.composite import composite

W, H = 128, 96
SPP, REF_SPP, MAX_DEPTH = 64, 512, 3
TEX, CHECKS, DARK, BRIGHT = 64, 8, 0.1, 0.6  # uv_scale 16 on an 8 m plane: 6.25 cm checks


def write_checker(path: str) -> None:
    import OpenImageIO as oiio

    i, j = np.mgrid[0:TEX, 0:TEX]
    check = ((i // (TEX // CHECKS) + j // (TEX // CHECKS)) % 2).astype(np.float32)
    out = oiio.ImageOutput.create(path)
    assert out.open(path, oiio.ImageSpec(TEX, TEX, 3, oiio.FLOAT)), oiio.geterror()
    out.write_image(np.repeat((DARK + (BRIGHT - DARK) * check)[:, :, None], 3, axis=2))
    out.close()


def rim_scene(texture_path: str, catcher: bool = False, textured: bool = True):
    s = sg.Scene()
    g = P.plane(8.0, 8.0)
    if textured:
        tex = s.add_texture("image", {"filename": texture_path, "uv_scale": [16.0, 16.0]})
        ground_mat = s.add_material("diffuse", {"albedo": sg.TextureRef(tex)})
    else:
        ground_mat = s.add_material("diffuse", {"albedo": 0.5 * (DARK + BRIGHT)})
    ground = s.add_instance(s.add_mesh(g["positions"], g["indices"], g["normals"], uvs=g["uvs"]),
                            np.eye(4, dtype=np.float32), material_id=ground_mat)
    b = P.box((0.8, 0.8, 0.8))
    objects = [s.add_instance(s.add_mesh(b["positions"], b["indices"]),
                              (P.translate([-0.6, 0.4, 0.0]) @ P.rotate([0, 1, 0], 30.0)).astype(np.float32),
                              class_id=1, material_id=s.add_material("diffuse", {"albedo": [0.7, 0.1, 0.05]}))]
    sp = P.uv_sphere(0.4)
    objects.append(s.add_instance(s.add_mesh(sp["positions"], sp["indices"], sp["normals"]),
                                  P.translate([0.7, 0.4, 0.3]).astype(np.float32), class_id=2,
                                  material_id=s.add_material("diffuse", {"albedo": [0.6, 0.6, 0.6]})))
    s.add_light("sun", {"elevation": 40.0, "azimuth": 60.0, "irradiance": 3.0})
    s.add_light("sky", {})
    if catcher:
        s.set_instance_catcher(ground, True)
    s.set_camera(sg.PinholeCamera.from_fov(40.0, W, H, sg.PinholeCamera.look_at([0.3, 2.0, 4.0], [0.0, 0.3, 0.0])))
    return s, objects


def _dilate(m: np.ndarray, n: int) -> np.ndarray:
    for _ in range(n):
        m = m.copy()
        m[1:] |= m[:-1].copy()
        m[:-1] |= m[1:].copy()
        m[:, 1:] |= m[:, :-1].copy()
        m[:, :-1] |= m[:, 1:].copy()
    return m


def render_all(texture_path: str) -> dict:
    kw = dict(max_depth=MAX_DEPTH)
    full, objects = rim_scene(texture_path)
    out = {"truth": np.asarray(full.render(spp=REF_SPP, seed=101, **kw).rgb),
           "direct": np.asarray(full.render(spp=SPP, seed=7, **kw).rgb)}
    for o in objects:
        full.set_instance_visible(o, False)
    out["photo"] = np.asarray(full.render(spp=REF_SPP, seed=202, **kw).rgb)
    out["uniform"] = rim_scene(texture_path, catcher=True, textured=False)[0].render(spp=SPP, seed=7, **kw)
    out["textured"] = rim_scene(texture_path, catcher=True, textured=True)[0].render(spp=SPP, seed=7, **kw)
    return out


def classes(r: dict) -> dict:
    a = np.asarray(r["uniform"].synthetic_alpha)
    obj = a > 0
    near = _dilate(obj, 3)
    changed = np.abs(r["truth"] - r["photo"]).max(axis=2) > 0.02 * float(r["photo"].max())
    return {"rim": (a > 0) & (a < 1), "ring": near & ~obj, "interior": a == 1, "elsewhere": changed & ~near}


def measure(r: dict) -> dict:
    """MSE of each composite and of the direct render against the truth, per pixel class."""
    truth = r["truth"]

    def mse(x, m):
        return float(np.mean((x[m] - truth[m]) ** 2))

    comps = {k: composite(r["photo"], r[k], "ratio") for k in ("uniform", "textured")}
    out = {}
    for name, m in classes(r).items():
        d = mse(r["direct"], m)
        out[name] = {"n": int(m.sum()), "direct": d, "level": float(np.mean(truth[m])),
                     **{k: mse(c, m) / d for k, c in comps.items()}}
    return out


@pytest.fixture(scope="module")
def figures(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("rims") / "checker.exr")
    write_checker(path)
    res = measure(render_all(path))
    print()
    for name, r in res.items():
        rel = 100.0 * np.sqrt(r["direct"]) / r["level"]
        print(f"catcher rims {name:9s}: px {r['n']:4d}, direct RMS error {rel:.2f}% of the mean; composite MSE / "
              f"direct MSE: uniform catcher {r['uniform']:.2f}, textured catcher {r['textured']:.2f}")
    return res


def test_classes_are_populated(figures):
    assert figures["rim"]["n"] >= 100 and figures["ring"]["n"] >= 300 and figures["elsewhere"]["n"] >= 500, figures


def test_composite_is_no_worse_than_a_direct_render_off_the_rims(figures):
    """Ring, shadows, object interiors: the composite is within 1.2x a direct render's MSE (the
    bound of test_composite_exactness) with either catcher; measured 0.26-0.29 (ring), 0.60-0.80
    (elsewhere), 1.00 (interior: the object's own samples, identical) over 4 seed sets, below 1
    on the ground because the converged photo supplies the ground's level."""
    for name in ("ring", "elsewhere", "interior"):
        for k in ("uniform", "textured"):
            assert figures[name][k] <= 1.2, (name, k, figures[name])


def test_rims_leak_the_hidden_ground(figures):
    """The documented failure. With the uniform catcher the rim pixels' MSE is a multiple of a
    direct render's at the same spp (measured 3.0-3.9x over 4 seed sets; it is a bias: converged,
    bench/failure_modes_cones_rims.py, the rims' mean absolute error stays 4.4 % against 0.6 % with the
    textured catcher). Bound 5x: the measured range with margin for seeds (the leak scales with
    the ground's contrast under the rim, 0.1 / 0.6 here). It must exceed 2x, and 2x the ring's
    and shadows' ratios (the failure is real and specific to rims), and with the textured
    catcher, which removes the cause, the rims must be back within 1.2x (measured 0.73-0.83)."""
    rim = figures["rim"]
    assert 2.0 < rim["uniform"] <= 5.0, rim
    assert rim["textured"] <= 1.2, rim
    assert rim["uniform"] > 2.0 * max(figures[k]["uniform"] for k in ("ring", "elsewhere")), figures
