"""Procedural textures ("noise", "cellular", "strokes") in renders: footprint band-limiting, mappings.

Band-limiting: a plane covered with fine world-space fBm (the kind of mask rust and dirt use)
seen at a grazing angle, lit so that rgb = albedo exactly (sun at the zenith with irradiance
pi, max_depth 2: no noise but the texture's). The reference is the pixel integral: 256
jittered samples per pixel of the *unfiltered* texture (band_limit false). One sample per pixel
of the band-limited texture must be close to it; one unfiltered sample per pixel must not.
"""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg

W, H = 96, 64
PLANE = 80.0


def scene(band_limit: bool, texture: dict) -> sg.Scene:
    s = sg.Scene()
    h = 0.5 * PLANE
    p = np.array([[-h, 0, 0], [h, 0, 0], [h, 0, PLANE], [-h, 0, PLANE]], np.float32)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    mesh = s.add_mesh(p, np.array([[0, 2, 1], [0, 3, 2]], np.uint32), uvs=uv)
    tex = s.add_texture(texture["type"], dict(texture["params"], band_limit=band_limit))
    mat = s.add_material("diffuse", {"albedo": sg.TextureRef(tex)})
    s.add_instance(mesh, None, material_id=mat)
    s.add_light("sun", {"direction": [0.0, 1.0, 0.0], "irradiance": float(np.pi), "angular_diameter": 0.0})
    pose = sg.PinholeCamera.look_at((0.0, 1.0, 0.0), (0.0, 0.0, 10.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(40.0, W, H, pose))
    return s


RUST_MASK = {"type": "noise", "params": {"pattern": "fbm", "octaves": 6, "mapping": "world", "scale": 8.0,
                                         "ramp_positions": [0.0, 1.0], "ramp_colors": [0.1, 0.1, 0.1, 0.9, 0.9, 0.9]}}
CRACKS = {"type": "cellular", "params": {"output": "edge", "mapping": "world", "scale": 6.0, "remap": [0.0, 0.15]}}
# Scratches as the wear presets draw them: beyond a footprint of a cell the texture is its mean.
SCRATCHES = {"type": "strokes", "params": {"mapping": "world", "scale": 8.0, "width": 0.08, "density": 4}}


@pytest.mark.parametrize("texture", [RUST_MASK, CRACKS, SCRATCHES], ids=["fbm", "cellular", "strokes"])
def test_band_limited_procedural_texture_does_not_alias(texture):
    """Aliasing energy = the variance an image has beyond the reference's: detail finer than
    a pixel folds into spurious pixel-to-pixel variation. Measured per image row on the
    distant half of the plane (where the texture is finer than the pixels), as
    mean(max(0, var(row) - var(reference row)))."""
    ref = scene(False, texture).render(spp=256, max_depth=2, seed=1).rgb[..., 0].astype(np.float64)
    filt = scene(True, texture).render(spp=1, max_depth=2, seed=2).rgb[..., 0].astype(np.float64)
    raw = scene(False, texture).render(spp=1, max_depth=2, seed=2).rgb[..., 0].astype(np.float64)
    ground = (ref > 0).all(axis=1)
    rows = np.where(ground)[0]
    far = rows[2: max(3, len(rows) // 2)]  # skip the horizon rows (partial coverage, not texture)
    excess = lambda img: float(np.mean(np.maximum(0.0, img[far].var(axis=1) - ref[far].var(axis=1))))  # noqa: E731
    rms = lambda img: float(np.sqrt(np.mean((img[far] - ref[far]) ** 2)))  # noqa: E731
    signal = float(np.mean(ref[far].var(axis=1))) + 1e-12
    e_f, e_r = excess(filt), excess(raw)
    print(f"\n[{texture['type']}] far field: aliasing energy band-limited 1 spp {e_f:.2e}, unfiltered 1 spp {e_r:.2e} "
          f"(reference variance {signal:.2e}); rms error {rms(filt):.4f} vs {rms(raw):.4f}")
    assert e_r > 10.0 * signal, "the unfiltered texture should alias here (test set-up)"
    assert e_f < 0.1 * e_r, "band-limiting left aliasing energy"
    assert e_f < 1.0 * signal + 1e-4, "band-limited image has more than twice the reference's variance"
    assert rms(filt) < rms(raw)


def test_object_mapping_moves_with_the_object():
    def render(offset):
        s = sg.Scene()
        from synthgen import primitives as P

        b = P.box((1.0, 1.0, 1.0))
        m = s.add_mesh(b["positions"], b["indices"])
        t = s.add_texture("noise", {"mapping": "object", "scale": 4.0})
        mat = s.add_material("diffuse", {"albedo": sg.TextureRef(t)})
        s.add_instance(m, P.translate([offset, 0.0, 0.0]), material_id=mat)
        s.add_light("environment", {"radiance": 1.0})
        pose = sg.PinholeCamera.look_at((offset, 0.0, -3.0), (offset, 0.0, 0.0), (0.0, 1.0, 0.0))
        s.set_camera(sg.PinholeCamera.from_fov(30.0, 48, 48, pose))
        return s.render(spp=1, max_depth=1, labels_only=True).albedo

    a, b = render(0.0), render(5.0)
    np.testing.assert_allclose(a, b, atol=1e-4)


def test_distant_rusty_plane_does_not_alias():
    """The wear issue's test: a distant rusty plane (synthgen.wear.rust: mask, colour ramp and
    bump) at 1 spp against a 256-spp supersampled reference: the aliasing energy (row variance
    beyond the reference's, far half of the plane) stays below a fifth of the reference's own
    variance. (The unfiltered counterpart is measured by the fBm and cellular mask test above.)"""
    from synthgen import wear

    def rusty(spp, seed, scale):
        s = sg.Scene()
        h = 0.5 * PLANE
        p = np.array([[-h, 0, 0], [h, 0, 0], [h, 0, PLANE], [-h, 0, PLANE]], np.float32)
        mesh = s.add_mesh(p, np.array([[0, 2, 1], [0, 3, 2]], np.uint32))
        base = s.add_material("diffuse", {"albedo": [0.2, 0.3, 0.6]})
        mat = wear.rust(s, base, amount=0.5, scale=scale, bottom_bias=0.0, seed=4)
        s.add_instance(mesh, None, material_id=mat)
        s.add_light("sun", {"direction": [0.0, 1.0, 0.0], "irradiance": float(np.pi), "angular_diameter": 0.0})
        pose = sg.PinholeCamera.look_at((0.0, 1.0, 0.0), (0.0, 0.0, 10.0), (0.0, 1.0, 0.0))
        s.set_camera(sg.PinholeCamera.from_fov(40.0, W, H, pose))
        return s.render(spp=spp, max_depth=2, seed=seed).rgb[..., 2].astype(np.float64)

    ref = rusty(256, 1, 60.0)
    one = rusty(1, 2, 60.0)
    ground = (ref > 0).all(axis=1)
    rows = np.where(ground)[0]
    far = rows[2: max(3, len(rows) // 2)]
    excess = float(np.mean(np.maximum(0.0, one[far].var(axis=1) - ref[far].var(axis=1))))
    signal = float(np.mean(ref[far].var(axis=1))) + 1e-12
    rms = float(np.sqrt(np.mean((one[far] - ref[far]) ** 2)))
    print(f"\n[rust] far field: aliasing energy at 1 spp {excess:.2e} (reference variance {signal:.2e}), "
          f"rms error {rms:.4f}")
    assert excess < 0.2 * signal + 1e-5
