"""Failure mode: ray-cone texture filtering behind curved mirrors and glass (docs/failure_modes.md).

A fine checkerboard ground (checks of 6.25 cm, 0.1 / 0.9) under a sun, seen directly, in a
flat mirror, in a convex mirror (a perfect-mirror sphere, r = 0.6 m) and through a glass
sphere (ior 1.5, r = 0.6 m). The camera's ray cone grows along the path by its spread angle;
at a Dirac (delta) bounce synthgen adds no spread (integrator/ray_cone.h,
``bsdf_spread_angle``: the curvature term beta of Ray Tracing Gems ch. 20 is not implemented,
the triangles being flat). That is exact for a flat mirror; a convex mirror (or a ball lens,
past its focus) spreads the pixel's rays much more, so the cone, and the texture footprint
behind it, is too narrow: the lookups are made at too fine a mip level and the texture aliases.

Metric: residual aliasing, in the pixels where the checks are unresolved (the converged
reference equals the render of a uniform texture of the same mean, to 0.03): the RMS error of
a 1-spp filtered render against the reference, in excess of the error the same render has with
the uniform texture (sun shadow edges, glass lobe choice, silhouettes: the non-texture noise),
pooled over SEEDS renders. Unfiltered (point-sampled) 1-spp renders give the full aliasing.
"""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P

W, H = 128, 96
TEX, CHECKS = 256, 32  # a 2 m period of 32 checks: 6.25 cm checks
DARK, BRIGHT = 0.1, 0.9
REF_SPP, GREY_REF_SPP, SEEDS, MAX_DEPTH = 2048, 256, 6, 6
# Instance ids of the primary hit (instance index + 1).
REGIONS = {"direct": 1, "flat mirror": 2, "mirror sphere": 3, "glass sphere": 4}


def write_texture(path: str, uniform: bool = False) -> None:
    import OpenImageIO as oiio

    i, j = np.mgrid[0:TEX, 0:TEX]
    check = ((i // (TEX // CHECKS) + j // (TEX // CHECKS)) % 2).astype(np.float32)
    v = np.full_like(check, 0.5 * (DARK + BRIGHT)) if uniform else DARK + (BRIGHT - DARK) * check
    out = oiio.ImageOutput.create(path)
    assert out.open(path, oiio.ImageSpec(TEX, TEX, 3, oiio.FLOAT)), oiio.geterror()
    out.write_image(np.repeat(v[:, :, None], 3, axis=2))
    out.close()


def mirror_scene(texture_path: str) -> sg.Scene:
    s = sg.Scene()
    g = P.plane(60.0, 60.0)
    tex = s.add_texture("image", {"filename": texture_path, "uv_scale": [30.0, 30.0]})
    s.add_instance(s.add_mesh(g["positions"], g["indices"], g["normals"], uvs=g["uvs"]), np.eye(4, dtype=np.float32),
                   material_id=s.add_material("diffuse", {"albedo": sg.TextureRef(tex)}))
    mirror = s.add_material("conductor", {"metal": "none", "roughness": 0.0})
    q = P.plane(1.0, 1.3)  # turned upright, facing the camera (-z), yawed by 20 degrees
    pose = P.translate([-1.55, 0.75, 0.0]) @ P.rotate([0, 1, 0], 20.0) @ P.rotate([1, 0, 0], -90.0)
    s.add_instance(s.add_mesh(q["positions"], q["indices"], q["normals"]), pose.astype(np.float32), material_id=mirror)
    sp = P.uv_sphere(0.6, 128, 64)
    ball = s.add_mesh(sp["positions"], sp["indices"], sp["normals"])
    s.add_instance(ball, P.translate([0.0, 0.6, 0.0]).astype(np.float32), material_id=mirror)
    s.add_instance(ball, P.translate([1.55, 0.6, 0.0]).astype(np.float32),
                   material_id=s.add_material("dielectric", {"ior": 1.5}))
    # Sun behind the camera: the objects' shadows fall behind them.
    s.add_light("sun", {"direction": [0.0, 1.0, -1.0], "irradiance": float(np.pi), "angular_diameter": 0.0})
    cam = sg.PinholeCamera.look_at((0.0, 1.1, -3.3), (0.0, 0.45, 0.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(50.0, W, H, cam))
    return s


def _erode(m: np.ndarray, n: int) -> np.ndarray:
    for _ in range(n):
        m = m.copy()
        m[1:] &= m[:-1].copy()
        m[:-1] &= m[1:].copy()
        m[:, 1:] &= m[:, :-1].copy()
        m[:, :-1] &= m[:, 1:].copy()
    return m


def render_set(texture_path: str, ref_spp: int) -> dict:
    s = mirror_scene(texture_path)
    out = {"ref": np.asarray(s.render(spp=ref_spp, texture_filtering=False, seed=101, max_depth=MAX_DEPTH).rgb)[..., 0]}
    for key, filtering in (("filtered", True), ("point", False)):
        out[key] = np.stack([np.asarray(s.render(spp=1, texture_filtering=filtering, seed=sd,
                                                 max_depth=MAX_DEPTH).rgb)[..., 0] for sd in range(SEEDS)])
    out["instance_id"] = np.asarray(s.render(spp=1, seed=0, max_depth=MAX_DEPTH).instance_id)
    return out


def measure(checker: dict, grey: dict) -> dict:
    """Per region: unresolved pixel count, residual aliasing of the filtered and the point-sampled
    1-spp renders (RMS error over the uniform texture's), and the fraction filtering leaves."""
    unresolved = np.abs(checker["ref"] - grey["ref"]) < 0.03
    out = {}
    for name, iid in REGIONS.items():
        m = _erode(checker["instance_id"] == iid, 2) & unresolved  # no silhouette pixels
        floor = float(np.mean((grey["filtered"][:, m] - grey["ref"][m]) ** 2))

        def excess(x):
            return float(np.sqrt(max(np.mean((x[:, m] - checker["ref"][m]) ** 2) - floor, 0.0)))

        f, p = excess(checker["filtered"]), excess(checker["point"])
        out[name] = {"n": int(m.sum()), "filtered": f, "point": p, "kept": f / p, "floor": float(np.sqrt(floor))}
    return out


@pytest.fixture(scope="module")
def figures(tmp_path_factory):
    d = tmp_path_factory.mktemp("cones")
    write_texture(str(d / "checker.exr"))
    write_texture(str(d / "grey.exr"), uniform=True)
    res = measure(render_set(str(d / "checker.exr"), REF_SPP), render_set(str(d / "grey.exr"), GREY_REF_SPP))
    print()
    for name, r in res.items():
        print(f"ray cones {name:13s}: unresolved px {r['n']:4d}, residual aliasing filtered {r['filtered']:.4f} "
              f"point {r['point']:.4f} (kept {r['kept']:.3f}), non-texture floor {r['floor']:.4f}")
    print(f"ray cones ratio to the flat mirror: mirror sphere {res['mirror sphere']['filtered'] / res['flat mirror']['filtered']:.2f}, "
          f"glass sphere {res['glass sphere']['filtered'] / res['flat mirror']['filtered']:.2f}")
    return res


def test_regions_are_measurable(figures):
    """Every region has enough unresolved pixels, and point sampling aliases in all of them
    (the reference is grey there, a point sample one check colour: about 0.4 x sun cosine)."""
    for name, r in figures.items():
        assert r["n"] >= 300, (name, r["n"])
        assert r["point"] > 0.12, (name, r["point"])


def test_flat_mirror_filters_like_a_direct_view(figures):
    """A flat mirror adds no spread, exactly: the cone is right and filtering removes most of the
    aliasing. Measured over 4 seed sets: it keeps 6.6-7.0 % of it behind the flat mirror and
    28-29 % on the directly seen ground, whose unresolved pixels lie at the grazing horizon
    (anisotropic footprints, the ellipse approximated by mip-mapped probes). Bounds 0.2 / 0.45:
    about 3x / 1.5x the measured values; they fail if texture filtering regresses on planar
    surfaces."""
    assert figures["flat mirror"]["kept"] < 0.2, figures["flat mirror"]
    assert figures["direct"]["kept"] < 0.45, figures["direct"]


def test_curved_specular_cone_is_too_narrow(figures):
    """The documented failure. Behind the convex mirror the residual aliasing is several times
    the flat mirror's (measured 4.0-4.5x over 4 seed sets): a sphere of radius r turns the
    normal by w / r across a cone of width w, so the reflected rays spread by about 2 w / r =
    0.1 rad (w ~ 3 cm where the cone meets the 0.6 m sphere), ten times the camera cone's
    0.01 rad, which synthgen keeps. Through the ball lens it is milder (2.0-2.4x: past the focus
    f = n r / (2 (n - 1)) = 0.9 m the rays spread by about w / f = 0.035 rad, 3.5x the cone's).
    The lower bounds (2.5x and 1.3x) fail if the effect disappears (with a curvature term the
    sphere's residual would be near the flat mirror's); the upper bounds on the fraction of the
    point-sampled aliasing that remains (measured 0.36-0.39 behind the mirror sphere, 0.16-0.18
    behind the glass; bounds 0.65 and 0.4) fail if it grows towards point sampling, i.e. if
    filtering stops working behind curved specular surfaces."""
    flat = figures["flat mirror"]["filtered"]
    ms, gl = figures["mirror sphere"], figures["glass sphere"]
    assert ms["filtered"] > 2.5 * flat, (ms, flat)
    assert gl["filtered"] > 1.3 * flat, (gl, flat)
    assert ms["kept"] < 0.65, ms
    assert gl["kept"] < 0.4, gl
