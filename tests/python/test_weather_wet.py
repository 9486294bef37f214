"""Weather ``wet`` (docs/weather.md): a water film darkens a rough surface by the inter-reflections
under its interface (Lekner & Dorf 1988) -- checked against the closed form per pixel -- and adds
a narrow reflection lobe; puddles are flat water whose mirror image of a bright object lies at the
analytically expected pixel with the Fresnel reflectance of water; the puddles cover their share
of the ground; in scenarios every model keeps its materials, labels do not change and frames
without the condition are the frames of a scenario without it, byte for byte."""
import json
import math
import os

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P
from synthgen.scene import wear

from test_randomize_wear import COLORS, write_model
from test_weather_scenario import file_bytes, run_tiny

N_WATER = 1.33


def fresnel(cos_i, eta=N_WATER):
    """Unpolarized Fresnel reflectance of a dielectric interface (from the outside)."""
    cos_i = np.clip(cos_i, 0.0, 1.0)
    sin_t2 = (1.0 - cos_i ** 2) / eta ** 2
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs ** 2 + rp ** 2)


def wet_to_dry(rho, cos_i, cos_o, eta=N_WATER):
    """Lekner & Dorf's darkening of a Lambertian surface of albedo rho under a smooth water film:
    light enters (1 - F(cos_i)), of the diffuse light going up the fraction F_int is reflected
    back down, the rest escapes compressed by 1 / eta^2 -- f_wet / f_dry = T_i T_o / (eta^2 (1 -
    rho F_int)), F_int = 1 - Tbar / eta^2, Tbar = 2 int_0^1 (1 - F(c)) c dc."""
    c = (np.arange(20000) + 0.5) / 20000
    tbar = 2.0 * np.mean((1.0 - fresnel(c, eta)) * c)
    f_int = 1.0 - tbar / eta ** 2
    return (1.0 - fresnel(cos_i, eta)) * (1.0 - fresnel(cos_o, eta)) / (eta ** 2 * (1.0 - rho * f_int))


def test_a_water_film_darkens_as_lekner_and_dorf_say():
    """A Lambertian patch (albedo 0.3) under a sun at 40 degrees, seen from straight above (the
    film's mirror reflection of the sun goes elsewhere): wet / dry is the closed form (0.62),
    within the noise of 64 spp."""
    rho = 0.3
    out = {}
    for state in ("dry", "wet"):
        s = sg.Scene()
        dry = s.add_material("diffuse", {"albedo": rho})
        m = dry if state == "dry" else wear.wet_twin(s, dry, roughness=0.0)
        s.add_instance(s.add_mesh(**P.plane(1, 1)), P.scale(20.0), material_id=m)
        s.add_light("sun", {"elevation": 40.0, "azimuth": 30.0, "irradiance": 3.0, "angular_diameter": 0.0})
        s.set_camera(sg.PinholeCamera.from_fov(10, 24, 24, sg.PinholeCamera.look_at([0, 5, 0], [0, 0, 0],
                                                                                     [0, 0, -1])))
        out[state] = np.asarray(s.render(spp=64, max_depth=4, seed=3).rgb, np.float64)
    dry_expected = rho * 3.0 * math.sin(math.radians(40.0)) / math.pi
    assert out["dry"].mean() == pytest.approx(dry_expected, rel=1e-3)
    ratio = out["wet"].mean() / out["dry"].mean()
    expected = wet_to_dry(rho, math.sin(math.radians(40.0)), 1.0)
    assert 0.55 < expected < 0.7
    assert ratio == pytest.approx(expected, rel=0.01), (ratio, expected)


def _mirror_scene(ground_fn, w=96, h=72):
    """A bright emissive ball (radius 0.1 m, radiance 40) 0.6 m above a ground, seen from 1.2 m
    up and 4 m away: (rgb, ids, camera, the ball's mirror image's expected pixel, the cosine of
    incidence there)."""
    s = sg.Scene()
    base = s.add_material("diffuse", {"albedo": 0.1})
    g = P.ground()
    s.add_instance(s.add_mesh(g["positions"], g["indices"], normals=g["normals"], uvs=g["uvs"]), np.eye(4),
                   material_id=ground_fn(s, base), class_id=0, instance_id=0)
    ball = P.uv_sphere(0.1, 32, 16)
    c = np.array([0.0, 0.6, 0.0])
    s.add_instance(s.add_mesh(ball["positions"], ball["indices"], normals=ball["normals"]), P.translate(c),
                   material_id=s.add_material("emissive", {"radiance": 40.0}), class_id=1, instance_id=1)
    s.add_light("environment", {"radiance": 0.05})
    eye = np.array([0.0, 1.2, 4.0])
    cam = sg.PinholeCamera.from_fov(30, w, h, sg.PinholeCamera.look_at(eye.tolist(), [0.0, 0.0, 0.0]))
    s.set_camera(cam)
    r = s.render(spp=64, max_depth=4, seed=5)
    image = np.array([c[0], -c[1], c[2]])                  # the mirror image of the ball's centre
    uv = cam.project(image.tolist())
    hit = eye + (image - eye) * (eye[1] / (eye[1] - image[1]))   # where the ray to it meets y = 0
    cos_i = float(eye[1] / np.linalg.norm(eye - hit))
    return np.asarray(r.rgb, np.float64), np.asarray(r.instance_id), cam, uv, cos_i


def test_puddles_mirror_a_bright_object_where_optics_says():
    """A ground all puddle: the brightest ground pixels are the ball's mirror image, centred on
    the pixel its reflection through y = 0 projects to (within a pixel), as bright as the ball times the
    Fresnel reflectance of water at that angle (within 10%); the dry ground shows no image (its
    brightest pixel is a few percent of it); a wet film (roughness 0.3) spreads the reflection:
    a dimmer peak over more pixels."""
    def puddle(s, base):
        return wear.wet_ground(s, base, seed=1, wetness=0.0, puddles=1.0)

    def film(s, base):
        return wear.wet_ground(s, base, seed=1, wetness=1.0, roughness=0.3, puddles=0.0)

    rgb, ids, cam, (u, v), cos_i = _mirror_scene(puddle)
    assert ids[int(v), int(u)] == 0, "the reflection is on the ground"
    y = rgb.mean(axis=2)
    ground = np.where(ids == 0, y, 0.0)
    ground[: int(v) - 12] = 0.0  # below the horizon and the ball: the reflection
    # The ball's image: the pixels above half the brightest, centred on the expected pixel.
    disc = ground > 0.5 * ground.max()
    assert 4 <= disc.sum() <= 60, disc.sum()
    ys, xs = np.nonzero(disc)
    assert abs(xs.mean() + 0.5 - u) <= 0.5 and abs(ys.mean() + 0.5 - v) <= 1.0, ((xs.mean(), ys.mean()), (u, v))
    peak = y[int(v), int(u)]
    assert peak == pytest.approx(40.0 * fresnel(cos_i), rel=0.1), (peak, 40.0 * fresnel(cos_i), cos_i)
    rgb_d, ids_d, _, _, _ = _mirror_scene(lambda s, base: base)
    yd = np.where(ids_d == 0, rgb_d.mean(axis=2), 0.0)
    assert yd[int(v) - 3: int(v) + 4, int(u) - 3: int(u) + 4].max() < 0.1 * peak
    rgb_f, ids_f, _, _, _ = _mirror_scene(film)
    yf = np.where(ids_f == 0, rgb_f.mean(axis=2), 0.0)
    yf[: int(v) - 12] = 0.0
    sharp, wide = _spread(ground, ids, u, v), _spread(yf, ids_f, u, v)
    assert yf.max() < 0.5 * peak and wide > 1.5 * sharp, (yf.max(), peak, wide, sharp)


def _spread(y, ids, u, v, r=16):
    """RMS distance (pixels) from (u, v) of the light above the ground's median within r pixels."""
    h, w = y.shape
    yy, xx = np.mgrid[0:h, 0:w] + 0.5
    near = (np.hypot(xx - u, yy - v) < r) & (ids == 0)
    e = np.where(near, np.maximum(y - np.median(y[ids == 0]), 0.0), 0.0)
    return float(np.sqrt((e * ((xx - u) ** 2 + (yy - v) ** 2)).sum() / e.sum()))


def _weight_texture(scene, mix_id):
    w = scene.material_info(mix_id)["params"]["weight"]
    assert w[0] == "texture"
    return int(w[1])


@pytest.mark.parametrize("share", [0.1, 0.3])
def test_puddles_cover_their_share_of_the_ground(share):
    """The puddle mask, sampled over 200 x 200 m (not the points it was calibrated on), covers
    the share asked (within 0.03); the film's mask covers the wetness asked (and the rim)."""
    s = sg.Scene()
    base = s.add_material("diffuse", {"albedo": 0.2})
    top = wear.wet_ground(s, base, seed=7, wetness=0.5, puddles=share, puddle_scale=2.0)
    info = s.material_info(top)
    assert info["type"] == "mix" and s.material_info(info["params"]["material_b"][1] if isinstance(
        info["params"]["material_b"], tuple) else info["params"]["material_b"])["type"] == "coated"
    rng = np.random.default_rng(0)
    pts = np.zeros((20000, 3), np.float32)
    pts[:, [0, 2]] = rng.uniform(-100, 100, (20000, 2))
    puddle = s.texture_values(_weight_texture(s, top), pts)[:, 0]
    assert puddle.mean() == pytest.approx(share, abs=0.03)
    film_mix = info["params"]["material_a"]
    film_mix = int(film_mix[1]) if isinstance(film_mix, tuple) else int(film_mix)
    wet = s.texture_values(_weight_texture(s, film_mix), pts)[:, 0]
    # The film covers half the ground and the rim (twice the puddles' share) wherever it is.
    assert wet.mean() >= 0.5 - 0.03 and wet.mean() <= 0.5 + 2 * share + 0.03
    assert (wet[puddle > 0.5] > 0.99).mean() > 0.95, "puddles are ringed by wet ground"


def test_wet_twins_keep_textures_and_leave_metals():
    s = sg.Scene()
    tex = s.add_texture("noise", {})
    p = s.add_material("principled", {"base_color": sg.TextureRef(tex), "roughness": 0.8})
    twin = s.material_info(wear.wet_twin(s, p, roughness=0.05))
    assert twin["type"] == "principled" and twin["params"]["clearcoat"] == 1.0
    assert twin["params"]["clearcoat_roughness"] == pytest.approx(0.05)
    # The base colour: the same texture, darker (rough: porous).
    bc = s.texture_values(twin["params"]["base_color"][1], np.zeros((1, 3), np.float32))[0]
    orig = s.texture_values(tex, np.zeros((1, 3), np.float32))[0]
    assert np.all(bc < orig) and np.all(bc > 0.5 * orig)
    assert wear.wet_twin(s, s.add_material("conductor", {"metal": "iron"})) is None
    d = s.add_material("diffuse", {"albedo": [0.2, 0.3, 0.4]})
    t = s.material_info(wear.wet_twin(s, d, roughness=0.1))
    assert t["type"] == "coated" and t["params"]["ior"] == pytest.approx(1.33)
    assert list(t["params"]["albedo"]) == pytest.approx([0.2, 0.3, 0.4])


# -- in scenarios -------------------------------------------------------------------------

def test_wet_changes_the_image_not_the_labels(tmp_path):
    """Half the frames wet: meta records the drawn parameters (and the pattern's seed); every
    label file is the dry run's, byte for byte; the wet frames' images differ, the others are
    the dry run's; the dataset verifies."""
    dry = run_tiny(tmp_path, "dry", "", count=4)
    wet = run_tiny(tmp_path, "wet", "weather: {wet: {probability: 0.5, wetness: {uniform: [0.5, 1]}, puddles: 0.2}}",
                   count=4)
    kinds = []
    for k in range(4):
        meta = json.load(open(os.path.join(wet, "meta", f"{k:06d}.json")))
        for sub in ("instance", "semantic"):
            assert file_bytes(os.path.join(dry, sub, f"{k:06d}.png")) == file_bytes(os.path.join(wet, sub, f"{k:06d}.png"))
        assert file_bytes(os.path.join(dry, "depth", f"{k:06d}.exr")) == file_bytes(os.path.join(wet, "depth", f"{k:06d}.exr"))
        img = os.path.join("images", f"{k:06d}.png")
        same = file_bytes(os.path.join(dry, img)) == file_bytes(os.path.join(wet, img))
        if meta["weather"] is None:
            assert same, k
            kinds.append("dry")
            continue
        w = meta["weather"]["wet"]
        assert 0.5 <= w["wetness"] <= 1 and w["puddles"] == 0.2 and w["roughness"] == 0.1
        assert w["puddle_scale"] == 3.0 and isinstance(w["seed"], int)
        assert not same, k
        kinds.append("wet")
    assert set(kinds) == {"dry", "wet"}, kinds
    from synthgen.outputs.verify import verify_dataset

    verify_dataset(wet)


def model_scenario(mesh, weather=""):
    return f"""
seed: 11
resolution: [96, 72]
camera: {{fov_y: 40, pose: {{type: look_at, eye: [1.6, 1.6, -2.2], target: [0, 0.4, 0]}}}}
lights: [{{type: environment, radiance: 0.8}}]
ground: {{size: 10, material: {{type: diffuse, albedo: 0.3}}}}
objects:
  - {{class: model, mesh: {mesh}, yaw: 0, size: 1}}
placement: {{region: [-0.001, -0.001, 0.001, 0.001]}}
{weather}
render: {{spp: 16, max_depth: 3}}
"""


def render_model(text, base_dir):
    from synthgen.frame import FrameRenderer
    from synthgen.scenario import parse_scenario
    from synthgen.schema.yaml_io import parse_yaml

    fr = FrameRenderer(parse_scenario(parse_yaml(text), "s.yaml", base_dir, text))
    arrays, meta, _ = fr.render(0)
    return arrays, meta, fr


def test_a_wet_model_keeps_each_of_its_materials(tmp_path):
    """A model with three materials under a full film: each face keeps its own colour (its
    albedo), its image changes (the film's gloss) and its labels do not; its material map
    wraps each of its materials (three mixes)."""
    d = str(tmp_path)
    mesh = write_model(d)
    dry, _, _ = render_model(model_scenario(mesh), d)
    wet, meta, fr = render_model(model_scenario(mesh, "weather: {wet: {wetness: 1, puddles: 0}}"), d)
    assert np.array_equal(dry["instance_id"], wet["instance_id"]) and np.array_equal(dry["depth"], wet["depth"])
    ids = dry["instance_id"]
    for name, c in COLORS.items():
        m = (ids == 1) & np.all(np.abs(dry["albedo"] - np.array(c, np.float32)) < 1e-6, axis=-1)
        assert m.sum() > 100, name
        # The wet face keeps its colour: the same hue, the same albedo.
        np.testing.assert_allclose(wet["albedo"][m], dry["albedo"][m], atol=1e-6)
        assert np.abs(wet["rgb"][m] - dry["rgb"][m]).mean() > 0.01, "the film shows"
    inst = fr.objects[0].instance
    mapped = fr.scene.instance_material_map(inst)
    assert len(mapped) == 3 and all(fr.scene.material_info(m)["type"] == "mix" for m in mapped.values())
    g = (ids == 0) & np.isfinite(dry["depth"])
    assert wet["rgb"][g].mean() != dry["rgb"][g].mean(), "the ground is wet too"
    assert meta["weather"]["wet"]["wetness"] == 1.0


def test_wet_over_a_photo_wets_the_objects_not_the_photos_ground(tmp_path):
    """Over a photo background the ground is the photo's (a shadow catcher): it stays as it is --
    away from the inserted object the composite is the photo -- while the object gets its film."""
    from test_augmented_photo import CALIBRATION, _photo, _scenario

    d = tmp_path / "photos"
    d.mkdir()
    photo = _photo(str(d / "street.exr"))
    (d / "calibration.yaml").write_text(CALIBRATION + "objects: []\n")
    dry = sg.Scenario(_scenario(tmp_path, photos=str(d), count=1)).frame(0)
    wet = sg.Scenario(_scenario(tmp_path, photos=str(d), count=1, extra="weather: {wet: {wetness: 1}}")).frame(0)
    assert wet.meta["weather"]["wet"]["wetness"] == 1.0
    assert np.array_equal(dry.instance_id, wet.instance_id)
    assert np.all(wet.rgb == photo, axis=2).mean() > 0.4
    m = wet.instance_id > 0
    assert m.sum() > 50 and np.abs(wet.rgb[m] - dry.rgb[m]).mean() > 1e-3
