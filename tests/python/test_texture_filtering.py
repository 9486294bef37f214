"""Texture filtering from ray cones (trilinear mip-mapping) and the per-scene texture cache.

The aliasing test renders a high-frequency checkerboard on a ground plane seen at a grazing
angle. The reference is the pixel integral itself: 1024 jittered samples per pixel of the
*unfiltered* (point-sampled) texture, box-filtered by the film. One sample per pixel of the
filtered texture must be close to it; one unfiltered sample per pixel must not (aliasing).
The sun irradiance is pi and the sun is at the zenith, so rgb equals the albedo exactly
(Lambertian: albedo / pi * E * cos 0) and there is no other light: no noise besides the
texture.
"""
from __future__ import annotations

import os

import numpy as np
import pytest

import synthgen as sg

W, H = 96, 64
PLANE = 60.0          # metres, the plane spans x in [-30, 30], z in [0, 60]
UV_SCALE = 30.0       # mesh uvs span [0, 1]; one texture period = 2 m
TEX, CHECKS = 128, 16  # 16 x 16 checks of 8 texels: check size 0.125 m
DARK, BRIGHT = 0.1, 0.9


def write_checkerboard(path: str) -> None:
    import OpenImageIO as oiio

    i, j = np.mgrid[0:TEX, 0:TEX]
    check = ((i // (TEX // CHECKS) + j // (TEX // CHECKS)) % 2).astype(np.float32)
    px = np.repeat((DARK + (BRIGHT - DARK) * check)[:, :, None], 3, axis=2)
    out = oiio.ImageOutput.create(path)
    assert out.open(path, oiio.ImageSpec(TEX, TEX, 3, oiio.FLOAT)), oiio.geterror()
    out.write_image(px)
    out.close()


def ground_scene(texture_path: str) -> sg.Scene:
    s = sg.Scene()
    h = 0.5 * PLANE
    # y = 0, normal +y (counter-clockwise seen from above), uvs [0, 1]^2.
    p = np.array([[-h, 0, 0], [h, 0, 0], [h, 0, PLANE], [-h, 0, PLANE]], np.float32)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    mesh = s.add_mesh(p, np.array([[0, 2, 1], [0, 3, 2]], np.uint32), uvs=uv)
    tex = s.add_texture("image", {"filename": texture_path, "uv_scale": [UV_SCALE, UV_SCALE]})
    mat = s.add_material("diffuse", {"albedo": sg.TextureRef(tex)})
    s.add_instance(mesh, None, material_id=mat)
    s.add_light("sun", {"direction": [0.0, 1.0, 0.0], "irradiance": float(np.pi), "angular_diameter": 0.0})
    # Eye 1 m above the ground looking 10 m ahead: the plane recedes to 1 degree below the horizon.
    pose = sg.PinholeCamera.look_at((0.0, 1.0, 0.0), (0.0, 0.0, 10.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(40.0, W, H, pose))
    return s


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("tex") / "checker.exr")
    write_checkerboard(path)
    s = ground_scene(path)
    kw = dict(max_depth=2, seed=7)
    ref = s.render(spp=1024, texture_filtering=False, **kw)
    filt = s.render(spp=1, texture_filtering=True, **kw)
    unfilt = s.render(spp=1, texture_filtering=False, **kw)
    mask = (ref.alpha == 1.0) & (filt.alpha == 1.0) & (unfilt.alpha == 1.0)
    return ref, filt, unfilt, mask


def rmse(a, b, mask):
    return float(np.sqrt(np.mean((np.asarray(a)[mask] - np.asarray(b)[mask]) ** 2)))


def check_size_px() -> tuple[np.ndarray, np.ndarray]:
    """Projected size in pixels of one check (2 m / 16) per image row, across the image and
    along the depth direction (smaller by the sine of the grazing angle), from the camera
    set-up alone: eye 1 m above the ground, pitched down by atan(1/10), vertical fov 40."""
    fy = 0.5 * H / np.tan(np.radians(20.0))
    rows = np.arange(H) + 0.5
    below_axis = np.arctan((rows - 0.5 * H) / fy)
    below_horizon = np.maximum(np.arctan(0.1) + below_axis, 0.0)
    dist = 1.0 / np.maximum(np.sin(below_horizon), 1e-12)
    across = fy * (2.0 / CHECKS) / (dist * np.cos(below_axis))
    return across, across * np.sin(below_horizon)


def far_rows() -> np.ndarray:
    """Rows where the checks are unresolved: a pixel spans over 3 check periods in depth
    (a check under 1/6 pixel) and a check is at most ~1.3 pixels across."""
    across, depth = check_size_px()
    return (depth < 1.0 / 6.0) & (across < 1.35)


def test_set_up_spans_resolved_and_unresolved_checks(renders):
    ref, filt, unfilt, mask = renders
    assert mask.sum() > 0.6 * W * H, "the plane covers most of the image"
    across, _ = check_size_px()
    rows = np.where(mask.all(axis=1))[0]
    near, far = rows[across[rows] > 4.0], rows[far_rows()[rows]]
    assert len(near) >= 4 and len(far) >= 8
    # Near the camera the reference resolves the checks (nearly full contrast); far away it
    # is grey: the checks average out.
    assert ref.rgb[near, :, 0].max() > 0.8 and ref.rgb[near, :, 0].min() < 0.2
    assert np.abs(ref.rgb[far, :, 0] - 0.5 * (DARK + BRIGHT)).max() < 0.08
    # Unfiltered single samples of the far field hit one check or the other: full contrast.
    assert np.abs(unfilt.rgb[far, :, 0] - 0.5).max() > 0.35


def test_filtered_albedo_label_does_not_alias(renders):
    """The albedo label comes from one ray through the pixel centre (no jitter). Filtered over
    the pixel's cone footprint (anisotropically, see docs/architecture.md) it approximates the
    pixel average of the albedo, which the reference rgb is (rgb = albedo here).

    Threshold 0.05: the reference has a noise of at most sigma / sqrt(1024) = 0.4 / 32 =
    0.0125 (sigma = 0.4 for a 0.1 / 0.9 checkerboard; measured 0.01), and the filter kernel
    (mip-mapped box probes over the cone's ellipse) is not exactly the pixel's projected
    box: about 0.03 more where checks are 1-4 pixels wide (measured total 0.025). Point
    samples alias: 0.28 (each unresolved pixel is one of the two colours, error sigma)."""
    ref, filt, unfilt, mask = renders
    e_filt = rmse(filt.albedo, ref.rgb, mask)
    e_unfilt = rmse(unfilt.albedo, ref.rgb, mask)
    assert e_filt < 0.05, e_filt
    assert e_unfilt > 5.0 * e_filt, (e_unfilt, e_filt)


def test_filtered_one_sample_rgb_does_not_alias(renders):
    """One jittered sample per pixel. Where the checks are unresolved (far_rows) the filtered sample is the local average, close to the reference (threshold 0.04: the
    reference noise of 0.0125 plus the residual moire the reference still has there, measured
    0.012-0.03), while a point sample is one of the two colours (error 0.4: aliasing).
    Where the checks are resolved, one sample at a random position in the pixel is noisy at
    check edges whether filtered or not (the pixel integral estimated from one sample); over
    the whole plane the filtered error (measured 0.12) must still be well below the
    unfiltered one (0.31)."""
    ref, filt, unfilt, mask = renders
    far = mask & far_rows()[:, None]
    e_far_filt, e_far_unfilt = rmse(filt.rgb, ref.rgb, far), rmse(unfilt.rgb, ref.rgb, far)
    assert e_far_filt < 0.04, e_far_filt
    assert e_far_unfilt > 0.3, e_far_unfilt
    e_filt, e_unfilt = rmse(filt.rgb, ref.rgb, mask), rmse(unfilt.rgb, ref.rgb, mask)
    assert e_filt < 0.5 * e_unfilt, (e_filt, e_unfilt)


def test_filtering_keeps_magnified_texels_and_converges_with_spp(renders, tmp_path):
    """Without minification nothing is blurred: a camera close to the plane sees texels larger
    than pixels, where the filtered lookups are the point (bilinear) lookups. And the camera
    cone shrinks with spp (1/sqrt(spp), at least 1/8 pixel), so a filtered high-spp render
    converges to the unfiltered one."""
    path = str(tmp_path / "checker.exr")
    write_checkerboard(path)
    s = ground_scene(path)
    # Looking straight down from 10 cm: a texel (2 m / 128) spans 5 pixels.
    pose = sg.PinholeCamera.look_at((0.0, 0.1, 1.0), (0.0, 0.0, 1.0), (0.0, 0.0, 1.0))
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 32, 24, pose))
    a = s.render(spp=1, texture_filtering=True, max_depth=2, seed=3)
    b = s.render(spp=1, texture_filtering=False, max_depth=2, seed=3)
    np.testing.assert_allclose(a.albedo, b.albedo, atol=1e-6)
    np.testing.assert_allclose(a.rgb, b.rgb, atol=1e-6)
    ref, _, _, mask = renders
    s2 = ground_scene(path)
    hi = s2.render(spp=256, texture_filtering=True, max_depth=2, seed=7)
    assert rmse(hi.rgb, ref.rgb, mask) < 0.02


def write_png(path: str, value: float) -> None:
    import OpenImageIO as oiio

    out = oiio.ImageOutput.create(path)
    assert out.open(path, oiio.ImageSpec(4, 4, 3, oiio.UINT8)), oiio.geterror()
    out.write_image(np.full((4, 4, 3), value, np.float32))
    out.close()


def test_same_file_is_loaded_once_per_scene(tmp_path):
    write_png(str(tmp_path / "c.png"), 0.5)
    (tmp_path / "sub").mkdir()
    s = sg.Scene()
    assert s.commit_stats["image_loads"] == 0
    t1 = s.add_texture("image", {"filename": str(tmp_path / "c.png")})
    t2 = s.add_texture("image", {"filename": os.path.join(str(tmp_path), "sub", "..", "c.png"),
                                 "wrap": "clamp", "uv_scale": 2.0})
    assert t1 != t2, "ids differ, the pixels are shared"
    assert s.commit_stats["image_loads"] == 1
    assert s.commit_stats["image_cache_hits"] == 1
    s.add_texture("image", {"filename": str(tmp_path / "c.png"), "colorspace": "linear"})
    assert s.commit_stats["image_loads"] == 2, "another colour space is another decoding"
    # Each scene has its own cache.
    s2 = sg.Scene()
    s2.add_texture("image", {"filename": str(tmp_path / "c.png")})
    assert s2.commit_stats["image_loads"] == 1 and s.commit_stats["image_loads"] == 2


def test_file_import_shares_the_texture_cache(tmp_path):
    write_png(str(tmp_path / "c.png"), 0.5)
    (tmp_path / "m.mtl").write_text("newmtl a\nKd 1 1 1\nmap_Kd c.png\n\nnewmtl b\nKd 0.5 0.5 0.5\nmap_Kd c.png\n")
    (tmp_path / "m.obj").write_text(
        "mtllib m.mtl\nv 0 0 3\nv 1 0 3\nv 0 1 3\nv 1 1 3\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
        "usemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 2/2 4/4 3/3\n")
    s = sg.Scene()
    s.add_texture("image", {"filename": str(tmp_path / "c.png"), "colorspace": "srgb"})
    res = s.load_mesh_file(str(tmp_path / "m.obj"))
    assert len(res["texture_ids"]) == 2, "two base-colour factors: two textures"
    assert s.commit_stats["image_loads"] == 1, "one image, decoded once for the scene"


def test_bad_uv_transform_parameters(tmp_path):
    write_png(str(tmp_path / "c.png"), 0.5)
    s = sg.Scene()
    with pytest.raises(sg.SynthgenError, match="uv_scale"):
        s.add_texture("image", {"filename": str(tmp_path / "c.png"), "uv_scale": [1.0, 0.0]})
    with pytest.raises(sg.SynthgenError, match="uv_offset"):
        s.add_texture("image", {"filename": str(tmp_path / "c.png"), "uv_offset": [1.0, 2.0, 3.0]})


def test_uv_transform_survives_save_and_load(tmp_path):
    path = str(tmp_path / "checker.exr")
    write_checkerboard(path)
    s = ground_scene(path)
    s.add_texture("image", {"filename": path, "uv_scale": 2.5, "uv_offset": [0.1, 0.2], "uv_rotation": 30.0,
                            "wrap": "mirror"})
    s.save(str(tmp_path / "scene.xml"))
    s2 = sg.Scene.load(str(tmp_path / "scene.xml"))
    a = s.render(spp=2, max_depth=2, seed=1)
    b = s2.render(spp=2, max_depth=2, seed=1)
    np.testing.assert_array_equal(a.rgb, b.rgb)
    np.testing.assert_array_equal(a.albedo, b.albedo)


def test_diffuse_bounces_filter_indirectly_seen_textures(tmp_path):
    """After a diffuse bounce the cone spreads by up to pi/8 (integrator/ray_cone.h), so a
    fine checkerboard seen only indirectly (lighting a white floor) is looked up near its
    average: same mean, much less noise than point samples, which see black or white.
    Noise is measured from the difference of two seeds (the smooth signal cancels)."""
    path = str(tmp_path / "checker.png")
    import OpenImageIO as oiio

    i, j = np.mgrid[0:128, 0:128]
    px = np.repeat((((i // 32 + j // 32) % 2)[:, :, None]).astype(np.float32), 3, axis=2)
    out = oiio.ImageOutput.create(path)
    assert out.open(path, oiio.ImageSpec(128, 128, 3, oiio.FLOAT))
    out.write_image(px)
    out.close()
    s = sg.Scene()
    floor = s.add_mesh(np.array([[-5, 0, -2], [5, 0, -2], [5, 0, 1.5], [-5, 0, 1.5]], np.float32),
                       np.array([[0, 2, 1], [0, 3, 2]], np.uint32))
    # Wall at z = 1.5 facing -z (towards the floor and the sun), checks of 25 cm.
    wall = s.add_mesh(np.array([[-5, 0, 1.5], [5, 0, 1.5], [5, 3, 1.5], [-5, 3, 1.5]], np.float32),
                      np.array([[0, 2, 1], [0, 3, 2]], np.uint32),
                      uvs=np.array([[0, 0], [10, 0], [10, 3], [0, 3]], np.float32))
    tex = s.add_texture("image", {"filename": path, "colorspace": "linear"})
    s.add_instance(floor, None, material_id=s.add_material("diffuse", {"albedo": 0.8}))
    s.add_instance(wall, None, material_id=s.add_material("diffuse", {"albedo": sg.TextureRef(tex)}))
    s.add_light("sun", {"direction": [0.0, 0.5, -1.0], "irradiance": 3.0, "angular_diameter": 0.0})
    pose = sg.PinholeCamera.look_at((0.0, 1.0, -0.5), (0.0, 0.0, 0.7), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 48, 32, pose))

    def stats(filtering):
        a = s.render(spp=4, max_depth=3, seed=1, texture_filtering=filtering)
        b = s.render(spp=4, max_depth=3, seed=2, texture_filtering=filtering)
        floor_px = (a.instance_id == 1)
        assert floor_px.mean() > 0.5
        noise = np.std((a.rgb - b.rgb)[floor_px]) / np.sqrt(2.0)
        return noise, 0.5 * (a.rgb + b.rgb)[floor_px].mean()

    n_f, m_f = stats(True)
    n_u, m_u = stats(False)
    assert abs(m_f - m_u) < 0.03 * m_u, (m_f, m_u)
    # Measured 0.081 vs 0.123; without the bounce spread (pixel cone only) 0.112. The rest is
    # the noise of sampling the wall's solid angle, which filtering cannot remove.
    assert n_f < 0.75 * n_u, (n_f, n_u)
