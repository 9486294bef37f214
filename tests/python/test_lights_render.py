"""End-to-end renders with the lights "envmap", "sky" and "spot" (cpp/light/*.cpp).

Every expectation is computed here with numpy, independently of the renderer:
* a constant environment map of radiance L: background pixels are exactly L, and a diffuse plane
  of albedo rho facing up has radiance rho L (irradiance pi L from the upper hemisphere);
  with visible=false the background is exactly 0 while the plane is bit-identical;
* a real HDR map (Blender's studio lights, package blender-data): the plane's radiance is
  rho E / pi with E integrated from the EXR in numpy, using the documented orientation
  (top row = +y, u = phi / 2 pi with direction (sin t sin phi, cos t, -sin t cos phi));
* the sky's ground below the horizon is a Lambertian ground of albedo ground_albedo lit by sky
  and sun, so a diffuse plane of the same albedo must look exactly like it;
* a spot light straight above a plane: radiance rho I / (pi h^2) on the axis, 0 outside the cone.
"""
from __future__ import annotations

import glob
import os

import numpy as np
import pytest

import synthgen as sg

RHO = 0.5


def plane(half: float, y: float = 0.0):
    """Square at height y facing +y (two triangles, counter-clockwise seen from above)."""
    p = np.array([[-half, y, -half], [half, y, -half], [half, y, half], [-half, y, half]], np.float32)
    return dict(positions=p, indices=np.array([[0, 2, 1], [0, 3, 2]], np.uint32),
                normals=np.tile(np.array([0, 1, 0], np.float32), (4, 1)))


def scene_with_plane(half: float, albedo: float = RHO) -> sg.Scene:
    s = sg.Scene()
    mat = s.add_material("diffuse", {"albedo": albedo})
    s.add_instance(s.add_mesh(**plane(half)), None, material_id=mat)
    return s


def camera(eye, target, up=(0.0, 1.0, 0.0), vfov=40.0, w=32, h=24) -> sg.PinholeCamera:
    return sg.PinholeCamera.from_fov(vfov, w, h, sg.PinholeCamera.look_at(eye, target, up))


def write_exr(path: str, rgb: np.ndarray) -> str:
    import OpenImageIO as oiio

    spec = oiio.ImageSpec(rgb.shape[1], rgb.shape[0], 3, oiio.FLOAT)
    out = oiio.ImageOutput.create(path)
    assert out is not None, oiio.geterror()
    assert out.open(path, spec), out.geterror()
    assert out.write_image(np.ascontiguousarray(rgb, dtype=np.float32)), out.geterror()
    out.close()
    return path


def test_envmap_visible_false_hides_it_from_the_camera_only(tmp_path):
    L = np.array([0.3, 0.6, 0.9], np.float32)
    path = write_exr(str(tmp_path / "constant.exr"), np.tile(L, (8, 16, 1)))
    renders = {}
    for visible in (True, False):
        s = scene_with_plane(2.0)
        s.add_light("envmap", {"filename": path, "visible": visible})
        s.set_camera(camera((0.0, 2.0, -4.0), (0.0, 0.0, 0.0)))
        renders[visible] = s.render(spp=64, max_depth=2, seed=5)
    shown, hidden = renders[True], renders[False]
    on_plane = shown.alpha == 1.0
    background = shown.alpha == 0.0
    assert on_plane.sum() > 50 and background.sum() > 50, "the view must show plane and background"
    np.testing.assert_array_equal(hidden.alpha, shown.alpha)
    # Background: exactly L when visible, exactly 0 when hidden.
    np.testing.assert_allclose(shown.rgb[background], np.broadcast_to(L, shown.rgb[background].shape), rtol=1e-6)
    assert np.all(hidden.rgb[background] == 0.0)
    # The plane is lit the same way (bit-identical: only camera rays that escape differ).
    np.testing.assert_array_equal(hidden.rgb[on_plane], shown.rgb[on_plane])
    mean = shown.rgb[on_plane].mean(axis=0)
    np.testing.assert_allclose(mean, RHO * L, rtol=0.01)


BLENDER_WORLDS = "/usr/share/blender/datafiles/studiolights/world"


def upper_hemisphere_irradiance(rgb: np.ndarray) -> np.ndarray:
    """E on a surface facing +y from an equirectangular map (nearest-pixel radiance): each
    pixel of row iy spans theta in [t0, t1] and 2 pi / W of phi, and contributes
    L * (2 pi / W) * integral of cos(t) sin(t) dt = L * (2 pi / W) * (sin^2 t1 - sin^2 t0) / 2."""
    h, w, _ = rgb.shape
    t = np.pi * np.arange(h + 1) / h
    weight = (2 * np.pi / w) * 0.5 * (np.sin(t[1:]) ** 2 - np.sin(t[:-1]) ** 2)
    weight[h // 2:] = 0.0  # below the horizon
    return np.einsum("y,yxc->c", weight, rgb.astype(np.float64))


@pytest.mark.skipif(not glob.glob(os.path.join(BLENDER_WORLDS, "*.exr")),
                    reason="Blender's studio light HDRs are not installed (Debian package blender-data)")
@pytest.mark.parametrize("name", ["city", "courtyard"])
def test_real_hdr_map_lights_a_plane(name):
    import OpenImageIO as oiio

    path = os.path.join(BLENDER_WORLDS, f"{name}.exr")
    rgb = oiio.ImageBuf(path).get_pixels(oiio.FLOAT)[:, :, :3]
    expected = RHO * upper_hemisphere_irradiance(rgb) / np.pi
    s = scene_with_plane(100.0)
    s.add_light("envmap", {"filename": path})
    s.set_camera(camera((0.0, 1.0, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), w=24, h=24))
    r = s.render(spp=64, max_depth=2, seed=6)
    assert np.all(r.alpha == 1.0)
    assert r.stats["nan_samples"] == 0
    mean = r.rgb.reshape(-1, 3).mean(axis=0)
    np.testing.assert_allclose(mean, expected, rtol=0.03)


def test_sky_ground_matches_a_plane_of_the_same_albedo():
    albedo = 0.3
    s = scene_with_plane(1.5, albedo)
    s.add_light("sky", {"elevation": 35.0, "azimuth": 120.0, "turbidity": 3.0, "ground_albedo": albedo})
    # Looking down at 45 degrees with a 40 degree field of view: every ray that misses the
    # plane goes below the horizon and sees the sky's ground.
    s.set_camera(camera((0.0, 3.0, -3.0), (0.0, 0.0, 0.0)))
    r = s.render(spp=128, max_depth=2, seed=7)
    assert r.stats["nan_samples"] == 0
    on_plane, background = r.alpha == 1.0, r.alpha == 0.0
    assert on_plane.sum() > 100 and background.sum() > 50
    ground = r.rgb[background]
    np.testing.assert_allclose(ground, np.broadcast_to(ground[0], ground.shape), rtol=1e-6)  # constant
    np.testing.assert_allclose(r.rgb[on_plane].mean(axis=0), ground[0], rtol=0.01)


def test_sky_is_blue_above_and_hidden_when_invisible():
    s = scene_with_plane(0.5)
    s.add_light("sky", {"elevation": 50.0, "turbidity": 2.5, "sun": False})
    s.set_camera(camera((0.0, 0.5, -3.0), (0.0, 2.0, 0.0), vfov=50.0))  # looking up at the sky
    r = s.render(spp=4, max_depth=1, seed=8)
    sky = r.rgb[r.alpha == 0.0]
    assert len(sky) > 100
    assert np.all(sky[:, 2] > sky[:, 0]), "a clear sky is blue"
    s.update_light(0, "sky", {"elevation": 50.0, "turbidity": 2.5, "sun": False, "visible": False})
    assert np.all(s.render(spp=4, max_depth=1, seed=8).rgb[r.alpha == 0.0] == 0.0)


def test_spot_light_on_a_plane():
    h, intensity = 2.0, 8.0
    s = scene_with_plane(10.0)
    s.add_light("spot", {"position": [0.0, h, 0.0], "direction": [0.0, -1.0, 0.0], "intensity": intensity,
                         "cone_angle": 30.0, "falloff_start": 20.0})
    # Camera straight above (through the light, which is a point and not in the image).
    w = 41
    s.set_camera(camera((0.0, 4.0, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), vfov=60.0, w=w, h=w))
    r = s.render(spp=16, max_depth=2, seed=9)
    centre = r.rgb[w // 2, w // 2]
    np.testing.assert_allclose(centre, RHO * intensity / (np.pi * h * h), rtol=2e-3)
    # Plane points beyond the cone (theta > 30 degrees: radius > h tan 30 = 1.15) are black;
    # the image spans +-4 tan 30 = 2.3 on the plane, so its corners are outside.
    assert np.all(r.rgb[:3, :3] == 0.0) and np.all(r.rgb[-3:, -3:] == 0.0)
    # The light reaches the plane only inside the cone: radius on the plane of each pixel
    # centre vs lit, with a margin of one pixel (pixels average over their footprint).
    pixel = 2 * 4.0 * np.tan(np.radians(30.0)) / w
    ii, jj = np.mgrid[0:w, 0:w]
    radius = np.hypot(ii + 0.5 - w / 2, jj + 0.5 - w / 2) * pixel
    edge = h * np.tan(np.radians(30.0))
    lit = r.rgb[..., 0] > 0
    assert np.all(lit[radius < edge - pixel])
    assert not np.any(lit[radius > edge + pixel])
