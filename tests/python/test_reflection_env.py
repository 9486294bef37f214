"""envmap reflection_only: an environment that only glossy and specular bounces see (what objects
reflect: a photo's surroundings), never lighting the scene nor seen by camera rays."""
from __future__ import annotations

import numpy as np
import OpenImageIO as oiio

import synthgen as sg
from synthgen import primitives as P


def _scene(tmp_path, with_reflection: bool):
    path = str(tmp_path / "red.exr")
    b = oiio.ImageBuf(oiio.ImageSpec(16, 8, 3, oiio.FLOAT))
    b.set_pixels(oiio.ROI(), np.tile(np.array([3.0, 0.0, 0.0], np.float32), (8, 16, 1)))
    b.write(path)
    s = sg.Scene()
    g = P.plane(20, 20)
    s.add_instance(s.add_mesh(g["positions"], g["indices"], g["normals"]), np.eye(4, dtype=np.float32),
                   material_id=s.add_material("diffuse", {"albedo": 0.5}))
    sp = P.uv_sphere(0.8)
    s.add_instance(s.add_mesh(sp["positions"], sp["indices"], sp["normals"]), P.translate([-1.0, 0.8, 0.0]),
                   class_id=1, material_id=s.add_material("conductor", {"metal": "silver", "roughness": 0.0}))
    s.add_instance(s.add_mesh(sp["positions"], sp["indices"], sp["normals"]), P.translate([1.2, 0.8, 0.0]),
                   class_id=2, material_id=s.add_material("diffuse", {"albedo": 0.8}))
    s.add_light("environment", {"radiance": [0.2, 0.2, 0.2]})
    if with_reflection:
        s.add_light("envmap", {"file": path, "reflection_only": True})
    s.set_camera(sg.PinholeCamera.from_fov(40, 128, 96, sg.PinholeCamera.look_at([0, 1.5, -6], [0, 0.7, 0])))
    return s


def test_only_reflections_see_it(tmp_path):
    plain = _scene(tmp_path, False).render(spp=64, seed=3)
    refl = _scene(tmp_path, True).render(spp=64, seed=3)
    cls = np.asarray(plain.class_id)
    mirror, matte = cls == 1, cls == 2
    a, b = np.asarray(plain.rgb), np.asarray(refl.rgb)
    # The mirror reflects the red dome where it sees the sky.
    assert b[mirror][:, 0].mean() > a[mirror][:, 0].mean() + 0.5
    # Nothing else changes: the matte sphere, the ground and the background (camera rays) are lit
    # and seen exactly as without it -- except what the mirror reflects onto them (a glossy path).
    rest = ~mirror
    diff = np.abs(b - a).max(axis=2)
    assert np.median(diff[rest]) == 0.0
    assert np.array_equal(b[cls == 0][:5], a[cls == 0][:5]) or diff[cls == 0].mean() < 0.02
    assert np.allclose(b[matte].mean(axis=0), a[matte].mean(axis=0), rtol=0.02, atol=1e-3)
