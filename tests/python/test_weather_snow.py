"""Weather ``snow`` (docs/weather.md) and its preset (synthgen.scene.wear.snow): snow lies on
faces that look up and not on those that look down or sideways (a box seen from above and from
below), not on slopes steeper than max_slope, covers its share of the up-facing area; in
scenarios it keeps every model's materials on the faces it leaves, labels do not change and
frames without it are the frames of a scenario without it."""
import json
import os

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P
from synthgen.scene import wear

from test_randomize_wear import COLORS, write_model
from test_weather_scenario import file_bytes, run_tiny
from test_weather_wet import model_scenario, render_model

RED = (0.6, 0.05, 0.05)
SNOW = np.array(wear.SNOW_COLOR, np.float32)


def _is_snow(albedo):
    """Albedo of the snow layer: its colour times 0.9-1 (its grain)."""
    return np.all((albedo >= 0.9 * SNOW - 1e-4) & (albedo <= SNOW + 1e-4), axis=-1)


def _is_red(albedo):
    return np.all(np.abs(albedo - np.array(RED, np.float32)) < 1e-6, axis=-1)


def _view(scene, eye, target, up=(0.0, 1.0, 0.0), w=80, h=60):
    scene.set_camera(sg.PinholeCamera.from_fov(40, w, h, sg.PinholeCamera.look_at(list(eye), list(target), list(up))))
    r = scene.render(spp=1, labels_only=True)
    return np.asarray(r.albedo), np.asarray(r.normal), np.asarray(r.instance_id)


def test_snow_lies_on_the_top_of_a_box_not_under_it():
    """A red box (1 m, floating at 1-2 m) under snow (amount 1): seen from above, every pixel of
    its top is snow and every pixel of its sides is red; seen from below, every pixel of its
    bottom is red."""
    s = sg.Scene()
    b = P.box((1.0, 1.0, 1.0))
    red = s.add_material("diffuse", {"albedo": list(RED)})
    s.add_instance(s.add_mesh(b["positions"], b["indices"], normals=b["normals"], uvs=b["uvs"]),
                   P.translate([0.0, 1.5, 0.0]), material_id=wear.snow(s, red, seed=3, amount=1.0), instance_id=1)
    alb, n, ids = _view(s, (2.0, 4.5, 3.0), (0.0, 1.5, 0.0))
    top, side = (ids == 1) & (n[..., 1] > 0.99), (ids == 1) & (np.abs(n[..., 1]) < 0.01)
    assert top.sum() > 200 and side.sum() > 200
    assert _is_snow(alb[top]).all()
    assert _is_red(alb[side]).all()
    alb, n, ids = _view(s, (2.0, -1.5, 3.0), (0.0, 1.5, 0.0))
    bottom = (ids == 1) & (n[..., 1] < -0.99)
    assert bottom.sum() > 200
    assert _is_red(alb[bottom]).all()
    assert _is_red(alb[(ids == 1) & (np.abs(n[..., 1]) < 0.01)]).all()


@pytest.mark.parametrize("tilt,snowy", [(20.0, True), (40.0, None), (70.0, False)])
def test_snow_slides_off_steep_slopes(tilt, snowy):
    """Planes tilted 20 degrees hold snow everywhere, 70 degrees nowhere (max_slope 45: the
    mask fades over 35-55 degrees); at 40 degrees it is partly there (the smooth band)."""
    s = sg.Scene()
    red = s.add_material("diffuse", {"albedo": list(RED)})
    s.add_instance(s.add_mesh(**P.plane(2, 2)), P.rotate([1.0, 0.0, 0.0], tilt),
                   material_id=wear.snow(s, red, seed=1, amount=1.0, max_slope=45.0), instance_id=1)
    eye = 3.0 * np.array([0.0, np.cos(np.radians(tilt)), np.sin(np.radians(tilt))])  # along the normal
    alb, _, ids = _view(s, eye, (0.0, 0.0, 0.0), up=(0.0, 0.0, -1.0) if tilt < 45 else (0.0, 1.0, 0.0))
    m = ids == 1
    assert m.sum() > 1000
    if snowy is True:
        assert _is_snow(alb[m]).all()
    elif snowy is False:
        assert _is_red(alb[m]).all()
    else:
        assert not _is_snow(alb[m]).any() and not _is_red(alb[m]).any()


@pytest.mark.parametrize("amount", [0.3, 0.7])
def test_snow_covers_its_share_of_the_up_facing_area(amount):
    """A 40 x 40 m flat ground with patches of 1 m: the share of it under snow (more than half
    the snow's albedo) is the amount asked, within 0.06."""
    s = sg.Scene()
    grey = s.add_material("diffuse", {"albedo": 0.1})
    s.add_instance(s.add_mesh(**P.plane(1, 1)), P.scale(40.0),
                   material_id=wear.snow(s, grey, seed=9, amount=amount, scale=1.0), instance_id=1)
    alb, _, ids = _view(s, (0.0, 40.0, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, -1.0), w=200, h=200)
    covered = alb[ids == 1].mean(axis=-1) > 0.1 + 0.5 * (0.9 * SNOW.mean() - 0.1)
    assert covered.mean() == pytest.approx(amount, abs=0.06)


# -- in scenarios -------------------------------------------------------------------------

def test_snow_on_a_model_keeps_its_materials_where_it_does_not_lie(tmp_path):
    """A three-material model under snow: its top is snow, its sides (two materials) keep their
    own material's albedo exactly; labels and depth are the clear frame's; meta records the drawn
    parameters; the ground is snowy."""
    d = str(tmp_path)
    mesh = write_model(d)
    clear, _, _ = render_model(model_scenario(mesh), d)
    snowy, meta, fr = render_model(model_scenario(mesh, "weather: {snow: {amount: 1, ground: 1}}"), d)
    assert np.array_equal(clear["instance_id"], snowy["instance_id"])
    assert np.array_equal(clear["depth"], snowy["depth"])
    ids, n = clear["instance_id"], clear["normal"]
    top = (ids == 1) & (n[..., 1] > 0.99)
    assert top.sum() > 100 and _is_snow(snowy["albedo"][top]).all()
    rest = (ids == 1) & (n[..., 1] < 0.5)
    assert rest.sum() > 300
    np.testing.assert_array_equal(snowy["albedo"][rest], clear["albedo"][rest])
    for name, c in COLORS.items():
        if name == "green":  # the model's top and bottom
            continue
        assert (np.all(np.abs(snowy["albedo"][rest] - np.array(c, np.float32)) < 1e-6, axis=-1)).sum() > 50, name
    ground = (ids == 0) & np.isfinite(clear["depth"])
    assert _is_snow(snowy["albedo"][ground]).mean() > 0.99
    w = meta["weather"]["snow"]
    assert w["amount"] == 1.0 and w["ground"] == 1.0 and w["max_slope"] == 45.0 and isinstance(w["seed"], int)


def test_snow_changes_the_image_not_the_labels(tmp_path):
    clear = run_tiny(tmp_path, "clear", "", count=4)
    snowy = run_tiny(tmp_path, "snowy", "weather: {snow: {probability: 0.5, amount: {uniform: [0.5, 1]}}}", count=4)
    kinds = set()
    for k in range(4):
        meta = json.load(open(os.path.join(snowy, "meta", f"{k:06d}.json")))
        for sub in ("instance/{}.png", "semantic/{}.png", "depth/{}.exr"):
            f = sub.format(f"{k:06d}")
            assert file_bytes(os.path.join(clear, f)) == file_bytes(os.path.join(snowy, f)), f
        same = file_bytes(os.path.join(clear, "images", f"{k:06d}.png")) == \
            file_bytes(os.path.join(snowy, "images", f"{k:06d}.png"))
        kinds.add(meta["weather"] is not None)
        assert same == (meta["weather"] is None), k
        if meta["weather"]:
            assert 0.5 <= meta["weather"]["snow"]["amount"] <= 1.0
    assert kinds == {True, False}
