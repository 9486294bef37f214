"""Scenes and estimates shared by the participating-media tests (test_medium_render,
test_heterogeneous_media): the closed furnace sphere, the scene where light sampling with MIS
is checked against BSDF and phase sampling alone, and that comparison."""
import numpy as np

import synthgen as sg
from synthgen import primitives as P


def add(s, geometry, world_from_object, **instance):
    """An instance of a primitive's mesh (synthgen.primitives) in scene ``s``."""
    mesh = s.add_mesh(geometry["positions"], geometry["indices"], normals=geometry["normals"])
    return s.add_instance(mesh, world_from_object, **instance)


def furnace_scene():
    """Inside a closed sphere (radius 3) whose wall emits 1 and reflects 0.5 (Lambertian, both
    sides) the radiance is 1 / (1 - 0.5) = 2 everywhere; the camera at its centre."""
    s = sg.Scene()
    wall = s.add_material("emissive", {"radiance": 1.0, "albedo": 0.5, "two_sided": True})
    add(s, P.uv_sphere(3.0), np.eye(4), material_id=wall)
    pose = sg.PinholeCamera.look_at((0.0, 0.0, 0.0), (0.3, 0.2, 1.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(60.0, 32, 24, pose))
    return s


def furnace_mean(s):
    """The furnace's image mean (paths long enough for albedo 1 media and the 0.5 wall)."""
    r = s.render(spp=64, max_depth=200, rr_depth=200, max_medium_depth=4000, seed=5)
    return float(np.asarray(r.rgb, np.float64).mean())


def street(width, height):
    """A red car-sized box 12 m ahead on a ground (box: class 1, instance 7), a sun and a uniform
    sky, seen from 1.5 m: the determinism and label tests' scene."""
    s = sg.Scene()
    add(s, P.ground(), np.eye(4), material_id=s.add_material("diffuse", {"albedo": 0.3}))
    add(s, P.box((1.8, 1.5, 4.2)), P.translate([0.0, 0.75, 12.0]), class_id=1, instance_id=7,
        material_id=s.add_material("diffuse", {"albedo": [0.6, 0.1, 0.1]}))
    s.add_light("sun", {"direction": [0.3, 0.8, -0.5], "irradiance": 3.0})
    s.add_light("environment", {"radiance": 0.4})
    pose = sg.PinholeCamera.look_at((0.0, 1.5, 0.0), (0.0, 1.0, 12.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(45.0, width, height, pose))
    return s


def mis_scene(medium, params, width, height):
    """A ground, a glossy box, a spherical emitter and a 10-degree sun under a uniform sky, in
    medium ``medium`` with ``params``."""
    s = sg.Scene()
    add(s, P.ground(), np.eye(4), material_id=s.add_material("diffuse", {"albedo": 0.5}))
    add(s, P.box((1.0, 1.0, 1.0)), P.translate([1.0, 0.5, 5.0]), class_id=1,
        material_id=s.add_material("coated", {"albedo": [0.6, 0.2, 0.1], "roughness": 0.3}))
    add(s, P.uv_sphere(0.5), P.translate([-1.0, 2.0, 6.0]), material_id=s.add_material("emissive", {"radiance": 8.0}))
    s.add_light("sun", {"direction": [0.3, 0.7, 0.5], "irradiance": 3.0, "angular_diameter": 10.0})
    s.add_light("environment", {"radiance": 0.3})
    s.set_medium(medium, params)
    pose = sg.PinholeCamera.look_at((0.0, 1.5, 0.0), (0.0, 1.0, 5.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(50.0, width, height, pose))
    return s


def light_sampling_on_and_off(s):
    """Renders ``s`` with next-event estimation and MIS (64 spp) and with BSDF and phase sampling
    alone (1024 spp): per channel each image's mean, its standard error (from the half-sample
    images) and the per-sample variance, with light sampling and without, and the z-scores of
    the means' difference."""
    stats = {}
    for nee, spp, seed in ((True, 64, 7), (False, 1024, 8)):
        r = s.render(spp=spp, max_depth=6, seed=seed, next_event=nee)
        x = np.asarray(r.rgb, np.float64)
        d = np.asarray(r.rgb_even, np.float64) - np.asarray(r.rgb_odd, np.float64)
        n = x.shape[0] * x.shape[1]
        se = np.sqrt((d ** 2 / 4.0).sum(axis=(0, 1))) / n
        stats[nee] = (x.mean(axis=(0, 1)), se, se ** 2 * spp)
    (m1, s1, v1), (m0, s0, v0) = stats[True], stats[False]
    z = np.abs(m1 - m0) / np.sqrt(s1 ** 2 + s0 ** 2)
    return (m1, s1, v1), (m0, s0, v0), z
