"""Rendering through a participating medium (Scene.set_medium; medium plugins, cpp/medium/):
transmittance against Beer-Lambert, a furnace that a non-absorbing medium must not change,
determinism across thread counts, replay of a saved scene, labels that never see the medium,
and the scene file's ``medium`` key."""
import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P


from medium_checks import add as _add, furnace_mean, furnace_scene, light_sampling_on_and_off, mis_scene, street


def _absorbing_scene(extinction):
    """An emitter plane (radiance 2, facing the camera, 4 to 9 m away: tilted) in black
    surroundings, seen through a purely absorbing homogeneous medium."""
    s = sg.Scene()
    q = P.plane(8.0, 8.0)
    wall = s.add_mesh(q["positions"], q["indices"], normals=q["normals"])
    emit = s.add_material("emissive", {"radiance": 2.0})
    # The plane's normal +y turned to face -z (the camera), then tilted about y.
    T = P.translate([0.0, 0.0, 6.5]) @ P.rotate([0, 1, 0], 35.0) @ P.rotate([1, 0, 0], -90.0)
    s.add_instance(wall, T, class_id=1, material_id=emit)
    s.set_medium("homogeneous", {"extinction": float(extinction), "albedo": 0.0})
    pose = sg.PinholeCamera.look_at((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 64, 48, pose))
    return s


def test_transmittance_is_beer_lambert():
    """Each camera sample either crosses the medium (probability exp(-sigma d)) or is absorbed:
    the mean of a pixel is 2 exp(-sigma d), d the ray's length to the emitter (the `distance`
    label at the pixel centre). Over the emitter's pixels at 256 spp the image mean agrees with
    the analytic mean within 4 standard errors (the samples' Bernoulli variance), and the
    per-pixel ratio to the analytic value is 1 within 3% on average (sub-pixel jitter moves
    d slightly)."""
    sigma = 0.15
    s = _absorbing_scene(sigma)
    r = s.render(spp=256, max_depth=4, seed=3)
    d = np.asarray(r.distance, np.float64)
    on = np.isfinite(d) & (np.asarray(r.class_id) == 1)
    # Away from the plane's edges (pixels there mix emitter and background).
    inner = on.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= np.roll(np.roll(on, dy, 0), dx, 1)
    assert inner.sum() > 500
    rgb = np.asarray(r.rgb, np.float64)[..., 0][inner]
    t = np.exp(-sigma * d[inner])
    expect = 2.0 * t
    se = np.sqrt((4.0 * t * (1.0 - t) / 256.0).sum()) / inner.sum()
    z = (rgb.mean() - expect.mean()) / se
    ratio = float((rgb / expect).mean())
    print(f"\nBeer-Lambert, sigma {sigma}: d {d[inner].min():.2f}..{d[inner].max():.2f} m, image mean "
          f"{rgb.mean():.5f}, analytic {expect.mean():.5f} (z {z:+.2f}); mean per-pixel ratio {ratio:.4f}")
    assert abs(z) < 4.0, z
    assert abs(ratio - 1.0) < 0.03, ratio


def test_non_absorbing_medium_keeps_the_furnace():
    """Inside a closed sphere whose wall emits 1 and reflects 0.5 (Lambertian, both sides) the
    radiance is 1 / (1 - 0.5) = 2 everywhere; a non-absorbing medium (albedo 1, forward
    scattering g 0.5, a mean free path of a third of the radius) scatters that uniform field
    into itself: still 2. Image mean within 1.5% without and with the medium."""
    s = furnace_scene()
    means = {}
    for label in ("clear", "medium"):
        if label == "medium":
            s.set_medium("homogeneous", {"extinction": 1.0, "albedo": 1.0, "g": 0.5})
        means[label] = furnace_mean(s)
    print(f"\nfurnace (expect 2): clear {means['clear']:.4f}, with a non-absorbing medium {means['medium']:.4f}")
    assert abs(means["clear"] - 2.0) < 0.03, means
    assert abs(means["medium"] - 2.0) < 0.03, means


def _foggy_street():
    return street(64, 48)


def test_fog_is_deterministic_replays_and_leaves_labels_alone(tmp_path):
    """Fog (visibility 40 m, a 30 m layer) over a street: bit-identical for 1 and 2 threads and
    after save / load; the labels are the same as without fog; the box's contrast against the
    fog falls (its pixels move towards the fog's brightness)."""
    s = _foggy_street()
    clear = s.render(spp=8, max_depth=5, seed=9)
    s.set_medium("homogeneous", {"visibility": 40.0, "top": 30.0})
    a = s.render(spp=8, max_depth=5, seed=9, threads=1)
    b = s.render(spp=8, max_depth=5, seed=9, threads=2)
    assert np.array_equal(np.asarray(a.rgb), np.asarray(b.rgb))
    path = str(tmp_path / "fog.xml")
    s.save(path)
    c = sg.Scene.load(path).render(spp=8, max_depth=5, seed=9, threads=2)
    assert np.array_equal(np.asarray(a.rgb), np.asarray(c.rgb))
    for k in ("depth", "distance", "albedo", "normal", "instance_id", "class_id", "alpha"):
        assert np.array_equal(np.asarray(getattr(a, k)), np.asarray(getattr(clear, k))), k
    box = np.asarray(a.class_id) == 1
    lum = lambda x: np.asarray(x.rgb, np.float64) @ [0.2126, 0.7152, 0.0722]  # noqa: E731
    contrast = lambda x: abs(lum(x)[box].mean() - lum(x)[~box].mean())  # noqa: E731
    print(f"\nbox contrast clear {contrast(clear):.4f}, in fog {contrast(a):.4f}")
    assert contrast(a) < 0.7 * contrast(clear)
    s.clear_medium()
    assert np.array_equal(np.asarray(s.render(spp=8, max_depth=5, seed=9).rgb), np.asarray(clear.rgb))


def test_bad_medium_parameters_are_errors():
    s = sg.Scene()
    with pytest.raises(sg.SynthgenError, match="visibility|extinction"):
        s.set_medium("homogeneous", {})
    with pytest.raises(sg.SynthgenError, match="did you mean"):
        s.set_medium("homogeneous", {"visibilty": 10.0})
    with pytest.raises(sg.SynthgenError, match="homogeneous"):
        s.set_medium("homogenous", {"visibility": 10.0})


def test_scene_file_medium(tmp_path):
    """The scene file's `medium` key sets the medium (reported in meta) and bad keys are errors
    at their line."""
    from synthgen.scene.scene_file import load_scene

    base = """
camera: {fov_y: 45, width: 32, height: 24, look_at: {eye: [0, 1.5, 0], target: [0, 1, 10]}}
objects: [{primitive: box, translate: [0, 0.5, 10], class_id: 1}]
lights: [{type: environment, radiance: 0.5}]
"""
    f = tmp_path / "fog.yaml"
    f.write_text(base + "medium: {type: homogeneous, visibility: 50, top: 20}\n")
    scene, settings, meta = load_scene(str(f))
    assert meta["medium"] == {"type": "homogeneous", "visibility": 50.0, "top": 20.0}
    assert scene.medium_type() == "homogeneous"
    f.write_text(base + "medium: {type: homogeneous, visibility: 50, g: 1.5}\n")
    with pytest.raises(sg.SynthgenError, match=r"fog\.yaml:5:.*medium\.g.*out of range"):
        load_scene(str(f))


def test_medium_with_catchers_is_an_error():
    """A photo background (shadow catchers) has no fog of its own: rendering fog over it would
    composite a clear photo with foggy objects. Refused, naming the medium."""
    s = _foggy_street()
    s.set_instance_catcher(0, True)
    s.set_medium("homogeneous", {"visibility": 40.0})
    with pytest.raises(sg.SynthgenError, match="homogeneous.*catchers"):
        s.render(spp=1)
    s.render(spp=1, labels_only=True)  # labels never see the medium


def test_single_scattering_of_the_sun_is_analytic():
    """Single scattering (max_medium_depth 1: one scattering vertex) of a delta
    sun in a layer, seen along horizontal rays (a one-row image whose pixels span 1e-4 rad
    vertically, fanned over 90 degrees of azimuth): along a horizontal ray the sun's
    transmittance to every point is the same, T_sun = exp(-sigma (top - h) / sin(elevation)),
    and the ray never leaves the layer, so the radiance is exactly
    albedo * E * T_sun * HG(g, dot(-d, sun)) -- per pixel the phase function's shape, its
    orientation and the scale. Within 0.5% of it (the pixel's horizontal extent averaged
    numerically), with a zero-variance estimator up to the rows' tiny tilt."""
    sigma, albedo, g, top, h, E = 0.1, 0.8, 0.6, 20.0, 10.0, 3.0
    sun = np.array([0.3, 0.8, -0.5])
    sun /= np.linalg.norm(sun)
    s = sg.Scene()
    _add(s, P.box((0.1, 0.1, 0.1)), P.translate([0.0, -1000.0, 0.0]),
         material_id=s.add_material("diffuse", {"albedo": 0.0}))  # a scene needs an instance
    s.add_light("sun", {"direction": sun.tolist(), "irradiance": E, "angular_diameter": 0.0})
    s.set_medium("homogeneous", {"extinction": sigma, "albedo": albedo, "g": g, "top": top})
    W = 64
    pose = sg.PinholeCamera.look_at((0.0, h, 0.0), (1.0, h, 1.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera(W / 2.0, 1.0e4, W / 2.0, 0.5, W, 1, pose))
    r = s.render(spp=64, max_depth=2, max_medium_depth=1, seed=3)
    img = np.asarray(r.rgb, np.float64)[0, :, 0]
    R = np.asarray(pose, np.float64)[:3, :3]
    t_sun = np.exp(-sigma * (top - h) / sun[1])

    def hg(c):
        return (1 - g * g) / (4 * np.pi * (1 + g * g + 2 * g * c) ** 1.5)

    expect = []
    for x in range(W):
        u = x + (np.arange(64) + 0.5) / 64.0  # across the pixel
        d = (R @ np.stack([(u - W / 2.0) / (W / 2.0), np.zeros_like(u), np.ones_like(u)])).T
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        expect.append(albedo * E * t_sun * hg(-(d @ sun)).mean())
    expect = np.array(expect)
    err = np.abs(img / expect - 1.0)
    print(f"\nsingle scattering: radiance {img.min():.5f}..{img.max():.5f} over the fan, analytic "
          f"{expect.min():.5f}..{expect.max():.5f}, max relative error {err.max():.4f}")
    assert err.max() < 0.005, err.max()


def test_light_sampling_on_and_off_agree_in_fog():
    """Energy with MIS on and off: fog (visibility 30 m, an 8 m layer) over a ground, a glossy box,
    a spherical emitter and a 10-degree sun under a uniform sky, rendered with next-event
    estimation and MIS (64 spp) and with BSDF and phase sampling alone (`next_event: false`,
    1024 spp): the image means agree within 4 standard errors (from each render's half-sample
    images) in every channel, and light sampling is worth its name (its per-sample variance is
    below a quarter of the other's; measured about 1/95)."""
    s = mis_scene("homogeneous", {"visibility": 30.0, "top": 8.0, "g": 0.5}, 64, 48)
    (m1, s1, v1), (m0, s0, v0), z = light_sampling_on_and_off(s)
    print(f"\nfog, light sampling on: mean {m1.round(5)} +- {s1.round(5)}; off: {m0.round(5)} +- {s0.round(5)}; "
          f"z {z.round(2)}; per-sample variance off / on {float((v0 / v1).mean()):.1f}")
    assert (z < 4.0).all(), z
    assert (v1 < v0 / 4.0).all(), (v1, v0)
