"""Alpha cut-outs (glTF alphaMode MASK): a hit with alpha < alpha_cutoff is no surface at all,
for camera rays, shadow rays and the label rays alike.

Expectations are analytic (numpy, float64), derived from the uv parameterization of the quads
and the texel layout of images written here: texture space has v up, image row 0 is the top
(t = 1 - v). The alpha test point-samples the full-resolution level (bilinear, footprint 0);
pixel centres sit on texel centres or well inside checks, so every expected alpha is exactly
0 or 1 (or a stripe's value).
"""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg

W = H = 64
F = 40.0  # focal length in pixels: a quad of side 2 m at z = 2 spans pixels [12, 52)


def write_image(path: str, px: np.ndarray) -> None:
    import OpenImageIO as oiio

    h, w, c = px.shape
    fmt = oiio.UINT8 if path.endswith(".png") else oiio.FLOAT
    out = oiio.ImageOutput.create(path)
    assert out.open(path, oiio.ImageSpec(w, h, c, fmt)), oiio.geterror()
    out.write_image(px.astype(np.float32))
    out.close()


def checker_rgba(n_checks: int, texels: int = 64) -> np.ndarray:
    """RGBA: grey colour, alpha 1 on checks with even (column + row) check index."""
    r, c = np.mgrid[0:texels, 0:texels]
    size = texels // n_checks
    alpha = ((r // size + c // size) % 2 == 0).astype(np.float32)
    px = np.full((texels, texels, 4), 0.5, np.float32)
    px[..., 3] = alpha
    return px


def checker_opaque(u: np.ndarray, v: np.ndarray, n_checks: int) -> np.ndarray:
    """The analytic pattern of checker_rgba at texture coordinates (u, v) in [0, 1)."""
    col = np.floor(n_checks * u)
    row = np.floor(n_checks * (1.0 - v))
    return (col + row) % 2 == 0


def quad_mesh(scene: sg.Scene, corners, normal) -> int:
    """Quad with corners p0..p3 (uvs (0,0), (1,0), (1,1), (0,1)), wound to face `normal`."""
    p = np.asarray(corners, np.float32)
    idx = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
    if np.dot(np.cross(p[1] - p[0], p[2] - p[0]), normal) < 0:
        idx = idx[:, ::-1].copy()
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    return scene.add_mesh(p, idx, uvs=uv)


def front_camera() -> sg.PinholeCamera:
    """At the origin looking along +z (camera frame = world frame: x right, y down)."""
    return sg.PinholeCamera(fx=F, fy=F, cx=W / 2, cy=H / 2, width=W, height=H, world_from_camera=np.eye(4))


def pixel_centres():
    j, i = np.mgrid[0:H, 0:W].astype(np.float64)
    return (i + 0.5 - W / 2) / F, (j + 0.5 - H / 2) / F  # x / z, y / z of the pixel-centre ray


QUAD_Z, BACK_Z = 2.0, 4.0
QUAD_ID, BACK_ID = 7, 9


def cutout_scene(tmp_path, alpha_param=None, wrap="clamp"):
    """A 2 m quad at z = 2 with a 4 x 4 checkerboard alpha (RGBA PNG) in front of a plane at
    z = 4 that covers only the left half of the image (x < 0): holes on the right show nothing."""
    path = str(tmp_path / "checker.png")
    write_image(path, checker_rgba(4))
    s = sg.Scene()
    tex = s.add_texture("image", {"filename": path, "wrap": wrap})
    q = quad_mesh(s, [[-1, -1, QUAD_Z], [1, -1, QUAD_Z], [1, 1, QUAD_Z], [-1, 1, QUAD_Z]], [0, 0, -1])
    back = quad_mesh(s, [[-10, -10, BACK_Z], [0, -10, BACK_Z], [0, 10, BACK_Z], [-10, 10, BACK_Z]], [0, 0, -1])
    params = {"albedo": [0.8, 0.2, 0.2], "alpha": sg.TextureRef(tex) if alpha_param is None else alpha_param}
    mat = s.add_material("diffuse", params)
    s.add_instance(q, None, class_id=1, instance_id=QUAD_ID, material_id=mat)
    s.add_instance(back, None, class_id=2, instance_id=BACK_ID)
    s.add_light("environment", {"radiance": 1.0})
    s.set_camera(front_camera())
    return s, mat


def expected_cutout_labels():
    x, y = pixel_centres()
    qx, qy = QUAD_Z * x, QUAD_Z * y  # where the pixel-centre ray crosses the quad's plane
    u, v = (qx + 1) / 2, (qy + 1) / 2
    on_quad = (np.abs(qx) < 1) & (np.abs(qy) < 1)
    quad = on_quad & checker_opaque(u, v, 4)
    back = ~quad & (BACK_Z * x < 0)
    ids = np.where(quad, QUAD_ID, np.where(back, BACK_ID, 0))
    depth = np.where(quad, QUAD_Z, np.where(back, BACK_Z, np.inf))
    return ids, depth, on_quad


@pytest.mark.parametrize("spp", [1, 16])  # single rays and 16-wide packets
def test_checkerboard_mask_is_exact(tmp_path, spp):
    s, _ = cutout_scene(tmp_path)
    r = s.render(spp=spp, max_depth=2, seed=3)
    ids, depth, on_quad = expected_cutout_labels()
    # The pattern is non-trivial: every class is present, holes show both backgrounds.
    assert (ids == QUAD_ID).sum() > 300 and (on_quad & (ids == BACK_ID)).sum() > 100
    assert (on_quad & (ids == 0)).sum() > 100
    np.testing.assert_array_equal(r.instance_id, ids)
    np.testing.assert_array_equal(r.class_id, np.select([ids == QUAD_ID, ids == BACK_ID], [1, 2], 0))
    finite = np.isfinite(depth)
    assert np.all(np.isinf(r.depth[~finite]))
    np.testing.assert_allclose(r.depth[finite], depth[finite], rtol=1e-5)
    # Pixel footprints align with the checks (check lines fall on pixel boundaries), so every
    # camera sample of a pixel agrees with its centre: film alpha is exactly 0 or 1.
    np.testing.assert_array_equal(r.alpha, (ids != 0).astype(np.float32))
    # Cut-out pixels are shaded as what is behind them: the environment (radiance 1), or the
    # grey plane.
    rgb_quad = r.rgb[ids == QUAD_ID]
    assert np.all(rgb_quad[:, 0] > 2 * rgb_quad[:, 1]), "opaque checks show the red quad"
    assert np.all(r.rgb[ids == 0] == 1.0), "holes with nothing behind them show the environment"
    rgb_back = r.rgb[on_quad & (ids == BACK_ID)]
    assert np.all(np.abs(rgb_back[:, 0] - rgb_back[:, 1]) <= 0.05 * rgb_back[:, 1]), "the grey plane shows"
    assert r.stats["alpha_test_calls"] > 0
    assert s.commit_stats["alpha_tested_meshes"] == 1


def test_grey_alpha_map_and_cutoff(tmp_path):
    """A one-channel image is used through its first channel. Five stripes of alpha
    0.1 .. 0.9 (8 texels each, one texel per pixel: centres sample texel centres, up to the
    rounding of the hit point; no cutoff equals a stripe value, which would be a knife edge)."""
    values = np.array([0.1, 0.3, 0.55, 0.7, 0.9], np.float32)
    img = np.repeat(values, 8)[None, :, None].repeat(4, axis=0)  # 4 x 40 x 1
    path = str(tmp_path / "stripes.exr")
    write_image(path, img)
    s = sg.Scene()
    tex = s.add_texture("image", {"filename": path, "wrap": "clamp"})
    q = quad_mesh(s, [[-1, -1, QUAD_Z], [1, -1, QUAD_Z], [1, 1, QUAD_Z], [-1, 1, QUAD_Z]], [0, 0, -1])
    mat = s.add_material("diffuse", {"alpha": sg.TextureRef(tex)})
    s.add_instance(q, None, instance_id=QUAD_ID, material_id=mat)
    s.set_camera(front_camera())
    x, y = pixel_centres()
    u = (QUAD_Z * x + 1) / 2
    on_quad = (np.abs(QUAD_Z * x) < 1) & (np.abs(QUAD_Z * y) < 1)
    stripe_alpha = values[np.clip(np.floor(5 * u), 0, 4).astype(int)]
    s.commit()
    builds = s.commit_stats["mesh_bvh_builds"]
    assert builds == 1
    for cutoff in [0.0, 0.4, 0.5, 0.6, 0.95, 1.0]:
        s.update_material(mat, "diffuse", {"alpha": sg.TextureRef(tex), "alpha_cutoff": cutoff})
        r = s.render(spp=1, max_depth=1)
        expected = np.where(on_quad & (stripe_alpha >= np.float32(cutoff)), QUAD_ID, 0)
        np.testing.assert_array_equal(r.instance_id, expected, err_msg=f"cutoff {cutoff}")
    # Changing the cutoff of a cut-out material keeps the mesh's filter: no BVH build.
    assert s.commit_stats["mesh_bvh_builds"] == builds
    # Default cutoff 0.5.
    s.update_material(mat, "diffuse", {"alpha": sg.TextureRef(tex)})
    r = s.render(spp=1, max_depth=1)
    np.testing.assert_array_equal(r.instance_id, np.where(on_quad & (stripe_alpha >= 0.5), QUAD_ID, 0))


def test_scalar_alpha(tmp_path):
    s, mat = cutout_scene(tmp_path, alpha_param=0.3)
    ids, _, on_quad = expected_cutout_labels()
    r = s.render(spp=1, max_depth=1)
    assert not np.any(r.instance_id == QUAD_ID), "alpha 0.3 < cutoff 0.5: the quad is invisible"
    np.testing.assert_array_equal(r.instance_id[on_quad & (ids == 0)], 0)
    assert s.commit_stats["alpha_tested_meshes"] == 1
    s.update_material(mat, "diffuse", {"alpha": 0.5})
    r = s.render(spp=1, max_depth=1)
    assert np.all(r.instance_id[on_quad] == QUAD_ID), "alpha 0.5 >= cutoff 0.5: an opaque quad"
    assert s.commit_stats["alpha_tested_meshes"] == 0, "a constant alpha above the cutoff is no cut-out"
    assert r.stats["alpha_test_calls"] == 0


def test_shadow_of_cutout_occluder(tmp_path):
    """Point light at (0, 2, 0), a checkerboard occluder at y = 1 (8 x 8 checks over
    x, z in [-1, 1]), a ground plane at y = 0 seen from below the occluder (camera at y = 0.9
    looking down), direct light only. A ground point (x, 0, z) sees the light through the
    occluder point (x/2, 1, z/2): fully shadowed pixels are exactly 0, fully lit ones equal
    albedo/pi * I * cos / r^2 = albedo/pi * 2 / r^3."""
    path = str(tmp_path / "checker8.png")
    write_image(path, checker_rgba(8))
    s = sg.Scene()
    tex = s.add_texture("image", {"filename": path, "wrap": "clamp"})
    occ = quad_mesh(s, [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]], [0, -1, 0])
    ground = quad_mesh(s, [[-20, 0, -20], [20, 0, -20], [20, 0, 20], [-20, 0, 20]], [0, 1, 0])
    s.add_instance(occ, None, material_id=s.add_material("diffuse", {"alpha": sg.TextureRef(tex)}))
    albedo = 0.5
    s.add_instance(ground, None, material_id=s.add_material("diffuse", {"albedo": albedo}))
    s.add_light("point", {"position": [0.0, 2.0, 0.0], "intensity": 1.0})
    eye_h = 0.9
    wfc = sg.PinholeCamera.look_at((0.0, eye_h, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    cam = sg.PinholeCamera(fx=32.0, fy=32.0, cx=W / 2, cy=H / 2, width=W, height=H, world_from_camera=wfc)
    s.set_camera(cam)
    R = np.asarray(cam.world_from_camera, np.float64)[:3, :3]

    def ground_point(px, py):
        d = np.stack([(px - W / 2) / 32.0, (py - H / 2) / 32.0, np.ones_like(px)], -1) @ R.T
        t = eye_h / -d[..., 1]
        return d[..., 0] * t, d[..., 2] * t

    def shadowed(px, py):
        gx, gz = ground_point(px, py)
        ox, oz = gx / 2, gz / 2  # the occluder point on the way to the light
        inside = (np.abs(ox) < 1) & (np.abs(oz) < 1)
        return inside & checker_opaque((ox + 1) / 2, (oz + 1) / 2, 8)

    j, i = np.mgrid[0:H, 0:W].astype(np.float64)
    probes = [shadowed(i + a, j + b) for a in (0.0, 0.5, 1.0) for b in (0.0, 0.5, 1.0)]
    dark = np.logical_and.reduce(probes)
    lit = ~np.logical_or.reduce(probes)
    assert dark.sum() > 300 and lit.sum() > 300
    gx, gz = ground_point(i + 0.5, j + 0.5)
    expected = albedo / np.pi * 2.0 / (gx**2 + 4.0 + gz**2) ** 1.5
    for spp in (16, 2):  # 16-wide packet shadow rays, then single shadow rays
        r = s.render(spp=spp, max_depth=2, seed=11)
        lum = r.rgb[..., 0].astype(np.float64)
        assert np.all(lum[dark] == 0.0), f"spp {spp}: fully shadowed pixels must be black"
        # The only variation inside a lit pixel is the smooth 1/r^3 falloff over the pixel.
        # Up to ~0.8% from the pixel centre to its corners: the mean of 16 jittered samples is
        # within 0.5%, of 2 samples within 1.5%.
        rtol = 5e-3 if spp == 16 else 1.5e-2
        np.testing.assert_allclose(lum[lit], expected[lit], rtol=rtol, err_msg=f"spp {spp}")


def quad_on_ground_scene(alpha_tex=None):
    s = sg.Scene()
    q = quad_mesh(s, [[-1, -1, QUAD_Z], [1, -1, QUAD_Z], [1, 1, QUAD_Z], [-1, 1, QUAD_Z]], [0, 0, -1])
    back = quad_mesh(s, [[-10, -10, BACK_Z], [10, -10, BACK_Z], [10, 10, BACK_Z], [-10, 10, BACK_Z]], [0, 0, -1])
    params = {"albedo": [0.7, 0.6, 0.2]}
    if alpha_tex is not None:
        params["alpha"] = sg.TextureRef(s.add_texture("image", {"filename": alpha_tex}))
    s.add_instance(q, None, material_id=s.add_material("diffuse", params))
    s.add_instance(back, None, material_id=s.add_material("diffuse", {"albedo": 0.5}))
    s.add_light("point", {"position": [0.5, -1.0, 0.5], "intensity": 3.0})
    s.add_light("environment", {"radiance": 0.2})
    s.set_camera(front_camera())
    return s


def test_opaque_scenes_run_no_filter_and_full_alpha_changes_nothing(tmp_path):
    """Without cut-out materials no mesh is alpha-tested and no test runs; an alpha map that is
    1 everywhere runs the test on every candidate hit yet renders bit-identically."""
    plain = quad_on_ground_scene()
    r0 = plain.render(spp=16, max_depth=4, seed=5)
    assert r0.stats["alpha_test_calls"] == 0
    assert plain.commit_stats["alpha_tested_meshes"] == 0
    path = str(tmp_path / "ones.png")
    write_image(path, np.ones((8, 8, 4), np.float32))
    full = quad_on_ground_scene(path)
    r1 = full.render(spp=16, max_depth=4, seed=5)
    assert r1.stats["alpha_test_calls"] > 0
    assert full.commit_stats["alpha_tested_meshes"] == 1
    for name in ("rgb", "alpha", "depth", "instance_id", "normal", "albedo"):
        np.testing.assert_array_equal(getattr(r1, name), getattr(r0, name), err_msg=name)


def test_bvh_builds_stay_honest(tmp_path):
    """Moving an instance or editing an opaque material builds no mesh BVH, with or without
    cut-outs; toggling a mesh's cut-out rebuilds exactly that mesh (Embree re-commits it)."""
    s, mat = cutout_scene(tmp_path)
    opaque = s.add_material("diffuse", {"albedo": 0.3})
    # A second instance of the cut-out quad's mesh with an opaque material stays solid.
    mesh_of_quad = 0
    behind = np.array([[2, 0, 0, 0], [0, 2, 0, 0], [0, 0, 1, 1.0], [0, 0, 0, 1]])  # z = 3, covers the holes
    twin = s.add_instance(mesh_of_quad, behind, material_id=opaque)
    r = s.render(spp=1, max_depth=1)
    ids, _, on_quad = expected_cutout_labels()
    np.testing.assert_array_equal(r.instance_id[ids == QUAD_ID], QUAD_ID)
    assert np.all(r.instance_id[on_quad & (ids != QUAD_ID)] == twin + 1), "the opaque twin fills the holes"

    def builds_after(edit):
        edit()
        s.commit()
        return s.commit_stats["mesh_bvh_builds_last_commit"]

    moved = behind.copy()
    moved[2, 3] = 1.5
    assert builds_after(lambda: s.set_instance_transform(twin, moved)) == 0
    assert builds_after(lambda: s.update_material(opaque, "diffuse", {"albedo": 0.9})) == 0
    assert builds_after(lambda: s.set_instance_labels(0, 3, 33)) == 0
    # The quad's material becomes opaque: its mesh loses the filter (one rebuild), and back.
    assert builds_after(lambda: s.update_material(mat, "diffuse", {"albedo": 0.5})) == 1
    assert s.commit_stats["alpha_tested_meshes"] == 0
    assert builds_after(lambda: s.set_instance_transform(twin, behind)) == 0
    tex = s.add_texture("image", {"filename": str(tmp_path / "checker.png")})
    assert builds_after(lambda: s.update_material(mat, "diffuse", {"alpha": sg.TextureRef(tex)})) == 1
    assert s.commit_stats["alpha_tested_meshes"] == 1


@pytest.mark.parametrize(
    "params, match",
    [
        ({"alpha_cutoff": -0.1}, "alpha_cutoff"),
        ({"alpha_cutoff": 1.5}, "alpha_cutoff"),
        ({"alpha_cutoff": float("nan")}, "alpha_cutoff"),
        ({"alpha": 2.0}, "alpha"),
        ({"alpha": -0.5}, "alpha"),
        ({"alpha": sg.TextureRef(99)}, "texture 99"),
        ({"alpha_cut": 0.5}, "alpha_cutoff"),  # unknown key: suggests the right one
    ],
)
def test_bad_alpha_parameters_raise(params, match):
    s = sg.Scene()
    with pytest.raises(sg.SynthgenError, match=match):
        s.add_material("diffuse", params)


def test_save_and_replay_keep_the_cutout(tmp_path):
    s, _ = cutout_scene(tmp_path)
    r0 = s.render(spp=4, max_depth=2, seed=2)
    path = str(tmp_path / "cutout.xml")
    s.save(path)
    loaded = sg.Scene.load(path)
    r1 = loaded.render(spp=4, max_depth=2, seed=2)
    assert loaded.commit_stats["alpha_tested_meshes"] == 1
    np.testing.assert_array_equal(r1.instance_id, expected_cutout_labels()[0])
    np.testing.assert_array_equal(r1.rgb, r0.rgb)


def test_cutouts_pass_through_a_mix(tmp_path):
    """A wear layer mixed over a cut-out material keeps the holes: labels identical to the
    base material's, for camera and shadow rays alike."""
    s, mat = cutout_scene(tmp_path)
    from synthgen import wear

    worn = wear.rust(s, mat, amount=0.5, seed=2)
    s.set_instance_material(0, worn)
    r = s.render(spp=1, max_depth=2, seed=3)
    ids, depth, on_quad = expected_cutout_labels()
    np.testing.assert_array_equal(r.instance_id, ids)
    mix_const = s.add_material("mix", {"material_a": mat, "material_b": s.add_material("diffuse", {}), "weight": 0.5})
    s.set_instance_material(0, mix_const)
    np.testing.assert_array_equal(s.render(spp=1, max_depth=2, seed=3).instance_id, ids)
