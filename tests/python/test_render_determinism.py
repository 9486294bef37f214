"""Renders are a pure function of (scene, settings, seed): independent of the thread count and
the tile size, bit for bit, for every output."""
from __future__ import annotations

import hashlib
import os

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P

OUTPUTS = ("rgb", "alpha", "depth", "distance", "normal", "albedo", "instance_id", "class_id")
SETTINGS = dict(spp=6, max_depth=6, rr_depth=3)


def _write_checker_png(path: str) -> None:
    import OpenImageIO as oiio

    n = 32
    yy, xx = np.mgrid[0:n, 0:n]
    img = np.zeros((n, n, 3), dtype=np.uint8)
    img[..., 0] = np.where((xx // 4 + yy // 4) % 2 == 0, 230, 40)
    img[..., 1] = (xx * 255 // (n - 1)).astype(np.uint8)
    img[..., 2] = (yy * 255 // (n - 1)).astype(np.uint8)
    buf = oiio.ImageBuf(oiio.ImageSpec(n, n, 3, oiio.UINT8))
    buf.set_pixels(oiio.ROI(0, n, 0, n), img)
    assert buf.write(path), buf.geterror()


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    png = str(tmp_path_factory.mktemp("tex") / "checker.png")
    _write_checker_png(png)
    s = sg.Scene()
    tex = s.add_texture("image", {"filename": png})
    textured = s.add_material("diffuse", {"albedo": sg.TextureRef(tex)})
    red = s.add_material("diffuse", {"albedo": [0.8, 0.2, 0.1]})
    lamp = s.add_material("emissive", {"radiance": [6.0, 5.5, 4.0], "two_sided": True})
    sphere, box, plane = s.add_mesh(**P.uv_sphere(0.6, 48, 24)), s.add_mesh(**P.box((0.8, 1.2, 0.8))), s.add_mesh(**P.plane(1, 1))
    s.add_instance(plane, P.scale(8.0), class_id=1, material_id=textured)
    s.add_instance(sphere, P.translate([-0.8, 0.6, 0.3]), class_id=2, material_id=red)
    s.add_instance(box, P.translate([0.9, 0.6, -0.2]) @ P.rotate([0, 1, 0], 30), class_id=3, material_id=textured)
    s.add_instance(sphere, P.translate([0.2, 0.35, -1.2]) @ P.scale(0.5), class_id=2)
    s.add_instance(plane, P.translate([0, 2.5, 0]) @ P.rotate([1, 0, 0], 180), class_id=4, material_id=lamp)
    s.add_light("sun", {"direction": [0.4, 1.0, -0.3], "irradiance": 2.0})
    s.add_light("environment", {"radiance": [0.2, 0.3, 0.45]})
    s.set_camera(sg.PinholeCamera.from_fov(50, 64, 48, sg.PinholeCamera.look_at([0.5, 2.0, -4.5], [0, 0.5, 0])))
    return s


def _digests(r) -> dict:
    return {name: hashlib.sha256(np.ascontiguousarray(getattr(r, name)).tobytes()).hexdigest() for name in OUTPUTS}


@pytest.fixture(scope="module")
def reference_render(scene):
    return scene.render(seed=5, threads=1, **SETTINGS)


def test_scene_is_nontrivial(reference_render):
    """The determinism checks below compare renders with real content: several labelled
    objects, light from several sources, noisy path-traced colour."""
    r = reference_render
    assert set(np.unique(r.class_id)) >= {1, 2, 3, 4}
    assert len(np.unique(r.instance_id)) >= 5
    assert np.isfinite(r.rgb).all() and r.rgb.max() > 0.1
    assert len(np.unique(r.albedo.reshape(-1, 3), axis=0)) > 10  # textured albedo varies
    assert r.stats["nan_samples"] == 0


@pytest.mark.parametrize("threads", [2, 4])
def test_thread_count_does_not_change_any_output(scene, reference_render, threads):
    r = scene.render(seed=5, threads=threads, **SETTINGS)
    # More threads than hardware threads are clamped to the hardware.
    assert r.stats["threads"] == min(threads, len(os.sched_getaffinity(0)))
    assert _digests(r) == _digests(reference_render)


@pytest.mark.parametrize("tile_size", [1, 7, 64])
def test_tile_size_does_not_change_any_output(scene, reference_render, tile_size):
    r = scene.render(seed=5, threads=2, tile_size=tile_size, **SETTINGS)
    assert _digests(r) == _digests(reference_render)


def test_seed_changes_rgb_but_not_labels(scene, reference_render):
    r = scene.render(seed=6, threads=2, **SETTINGS)
    a, b = _digests(r), _digests(reference_render)
    assert a["rgb"] != b["rgb"]
    # Noise differs almost everywhere, not just in a few pixels.
    assert np.mean(np.any(r.rgb != reference_render.rgb, axis=-1)) > 0.5
    # Labels come from the pixel-centre ray, which does not depend on the seed.
    for name in ("depth", "distance", "normal", "albedo", "instance_id", "class_id"):
        assert a[name] == b[name], name
