"""The "mix" and "coated" materials through the Python API.

* A plane with a mix material shows the blended albedo in the albedo output (exactly, for
  weight 0.5 where the blend is exact in float32; to rounding for a texture mask).
* Coated spheres under a uniform environment render finite images without NaN samples, and,
  since a white base under a clear coat is lossless, a white coated convex object in a uniform
  environment of radiance 1 renders as 1 (a white furnace through the whole renderer).
"""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P

A = np.float32([0.3, 0.6, 0.9])
B = np.float32([0.8, 0.2, 0.1])


def plane_scene(weight) -> tuple[sg.Scene, int]:
    s = sg.Scene()
    a = s.add_material("diffuse", {"albedo": A.tolist()})
    b = s.add_material("coated", {"albedo": B.tolist(), "roughness": 0.3, "ior": 1.5})
    mix = s.add_material("mix", {"material_a": a, "material_b": b, "weight": weight})
    s.add_instance(s.add_mesh(**P.plane(1, 1)), P.scale(10.0), material_id=mix)
    s.set_camera(sg.PinholeCamera.from_fov(40, 24, 16, sg.PinholeCamera.look_at([0, 3, -2], [0, 0, 0])))
    return s, mix


def test_mix_albedo_output_is_the_blend():
    s, _ = plane_scene(0.5)
    r = s.render(spp=1, max_depth=1)
    assert np.all(r.alpha == 1.0), "the plane covers the image"
    expected = np.float32(0.5) * A + np.float32(0.5) * B
    assert np.array_equal(r.albedo, np.broadcast_to(expected, r.albedo.shape))


def test_mix_with_texture_mask_albedo():
    s = sg.Scene()
    mask = s.add_texture("constant", {"value": 0.25})
    a = s.add_material("diffuse", {"albedo": A.tolist()})
    b = s.add_material("coated", {"albedo": B.tolist()})
    mix = s.add_material("mix", {"material_a": a, "material_b": b, "weight": sg.TextureRef(mask)})
    s.add_instance(s.add_mesh(**P.plane(1, 1)), P.scale(10.0), material_id=mix)
    s.set_camera(sg.PinholeCamera.from_fov(40, 24, 16, sg.PinholeCamera.look_at([0, 3, -2], [0, 0, 0])))
    r = s.render(spp=1, max_depth=1)
    np.testing.assert_allclose(r.albedo, np.broadcast_to(0.75 * A + 0.25 * B, r.albedo.shape), rtol=0, atol=1e-7)


def test_mix_bad_parameters_raise():
    s = sg.Scene()
    a = s.add_material("diffuse", {})
    with pytest.raises(sg.SynthgenError, match="material_b"):
        s.add_material("mix", {"material_a": a, "material_b": 42})
    with pytest.raises(sg.SynthgenError, match="weight"):
        s.add_material("mix", {"material_a": a, "material_b": a, "weight": 1.5})


def sphere_in_environment(material: str, params: dict, spp: int, seed: int = 1):
    s = sg.Scene()
    sphere = P.uv_sphere(1.0, 48, 24)
    # Flat shading (no vertex normals): shading normal == geometric normal, so the white
    # furnace is exact for a convex object.
    mesh = s.add_mesh(positions=sphere["positions"], indices=sphere["indices"])
    s.add_instance(mesh, None, material_id=s.add_material(material, params))
    s.add_light("environment", {"radiance": 1.0})
    s.set_camera(sg.PinholeCamera.from_fov(40, 32, 32, sg.PinholeCamera.look_at([0, 0.5, -4], [0, 0, 0])))
    return s.render(spp=spp, max_depth=6, seed=seed)


@pytest.mark.parametrize("roughness", [0.0, 0.3, 1.0])
def test_coated_sphere_renders_finite(roughness):
    r = sphere_in_environment("coated", {"albedo": [0.7, 0.3, 0.1], "roughness": roughness}, spp=8)
    assert r.stats["nan_samples"] == 0
    assert np.all(np.isfinite(r.rgb))
    on = r.alpha == 1.0
    assert on.sum() > 100
    # Under a uniform white environment of radiance 1 a pixel is the directional albedo:
    # non-negative, below 1 (the base absorbs), and the base colour shows (red > blue).
    assert np.all(r.rgb[on] >= 0) and r.rgb[on].mean() < 1.0
    assert r.rgb[on][:, 0].mean() > r.rgb[on][:, 2].mean()


@pytest.mark.parametrize("material,params", [
    ("coated", {"albedo": 1.0, "roughness": 0.0}),
    ("coated", {"albedo": 1.0, "roughness": 0.5}),
])
def test_white_coated_sphere_is_a_white_furnace(material, params):
    r = sphere_in_environment(material, params, spp=64)
    assert r.stats["nan_samples"] == 0
    on = r.alpha == 1.0
    # Each sphere pixel converges to 1; the mean over ~400 pixels x 64 spp is within 1%.
    assert abs(r.rgb[on].mean() - 1.0) < 0.01, r.rgb[on].mean()
    np.testing.assert_allclose(r.rgb[r.alpha == 0.0], 1.0, rtol=0, atol=1e-6)


def test_mix_follows_updates_of_its_components_and_replays(tmp_path):
    """Updating a component of a mix re-creates the mix (no stale component), and the
    saved scene replays bit-identically; a material may not refer to a later id."""
    import synthgen as sg
    from synthgen import primitives as P

    scene = sg.Scene()
    plane = scene.add_mesh(**P.plane(4, 4))
    a = scene.add_material("diffuse", {"albedo": 0.2})
    b = scene.add_material("diffuse", {"albedo": 0.6})
    mix = scene.add_material("mix", {"material_a": a, "material_b": b, "weight": 0.5})
    scene.add_instance(plane, material_id=mix)
    scene.add_light("environment", {"radiance": 1.0})
    scene.set_camera(sg.PinholeCamera.from_fov(40, 16, 16, sg.PinholeCamera.look_at([0, 3, 0.01], [0, 0, 0], [0, 1, 0])))
    assert np.allclose(scene.render(spp=1).albedo, 0.4)
    scene.update_material(b, "diffuse", {"albedo": 1.0})
    r = scene.render(spp=4, seed=3)
    assert np.allclose(r.albedo, 0.6)
    path = str(tmp_path / "scene.xml")
    scene.save(path)
    replay = sg.Scene.load(path).render(spp=4, seed=3)
    assert np.array_equal(replay.rgb, r.rgb) and np.array_equal(replay.albedo, r.albedo)
    with pytest.raises(sg.SynthgenError, match="smaller ids"):
        scene.update_material(a, "mix", {"material_a": b, "material_b": mix})
