"""Randomizer "wear" on models with materials of their own: each of the model's materials is
wrapped (a per-instance material map), so a multi-material model keeps its colours wherever
the wear mask is zero (it used to turn every sub-material into one grey)."""
import os

import numpy as np
import pytest

from synthgen.frame import FrameRenderer
from synthgen.scenario import parse_scenario
from synthgen.schema.yaml_io import parse_yaml

COLORS = {"red": (0.8, 0.1, 0.1), "green": (0.1, 0.7, 0.1), "blue": (0.1, 0.1, 0.75)}


def write_model(d):
    """A unit box whose faces use three materials (two faces each), as OBJ + MTL."""
    with open(os.path.join(d, "box.mtl"), "w") as f:
        for name, (r, g, b) in COLORS.items():
            f.write(f"newmtl {name}\nKd {r} {g} {b}\nKs 0 0 0\nNs 10\n\n")
    v = [(x, y, z) for x in (-0.5, 0.5) for y in (0.0, 1.0) for z in (-0.5, 0.5)]
    faces = {"red": [(1, 2, 4, 3), (5, 7, 8, 6)], "green": [(1, 5, 6, 2), (3, 4, 8, 7)],
             "blue": [(1, 3, 7, 5), (2, 6, 8, 4)]}
    with open(os.path.join(d, "box.obj"), "w") as f:
        f.write("mtllib box.mtl\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in v))
        for name, quads in faces.items():
            f.write(f"usemtl {name}\n" + "".join(f"f {a} {b} {c} {e}\n" for a, b, c, e in quads))
    return os.path.join(d, "box.obj")


def scenario(mesh, wear=""):
    return f"""
seed: 11
resolution: [96, 72]
camera: {{fov_y: 40, pose: {{type: look_at, eye: [1.6, 1.6, -2.2], target: [0, 0.4, 0]}}}}
lights: [{{type: environment, radiance: 0.8}}]
objects:
  - {{class: model, mesh: {mesh}, yaw: 0, size: 1{wear}}}
placement: {{region: [-0.001, -0.001, 0.001, 0.001]}}
render: {{spp: 1, max_depth: 1}}
"""


def albedo_of(text, base_dir):
    sc = parse_scenario(parse_yaml(text), "s.yaml", base_dir, text)
    fr = FrameRenderer(sc)
    fr.render(0)
    r = fr.scene.render(spp=1, labels_only=True)
    return np.asarray(r.albedo), np.asarray(r.instance_id)


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    d = tmp_path_factory.mktemp("model")
    return str(d), write_model(str(d))


def _regions(albedo, ids):
    """Pixels of each material (by their exact albedo without wear)."""
    out = {}
    for name, c in COLORS.items():
        m = (ids == 1) & np.all(np.abs(albedo - np.array(c, np.float32)) < 1e-6, axis=-1)
        out[name] = m
    return out


def test_wear_keeps_each_material_of_a_model(model):
    d, mesh = model
    clean, ids = albedo_of(scenario(mesh), d)
    regions = _regions(clean, ids)
    assert all(m.sum() > 150 for m in regions.values()), {k: int(m.sum()) for k, m in regions.items()}
    assert sum(m.sum() for m in regions.values()) == (ids == 1).sum(), "every model pixel is one of its materials"

    # No coverage: the model is exactly as without wear (not one grey).
    none, ids0 = albedo_of(scenario(mesh, ", wear: {rust: {amount: 0.0}, dirt: {amount: 0.0, ao_weight: 0}}"), d)
    np.testing.assert_array_equal(ids0, ids)
    np.testing.assert_array_equal(none, clean)

    # Light wear: each material keeps its exact albedo where the mask is zero, and only there
    # does the albedo change.
    worn, ids1 = albedo_of(scenario(mesh, ", wear: {rust: {amount: 0.3, seed: 4}}"), d)
    np.testing.assert_array_equal(ids1, ids)
    changed_total = 0
    for name, m in regions.items():
        same = np.all(worn[m] == clean[m], axis=-1)
        # Most of each material is untouched by a 30% rust (the mask covers the object, not a
        # material); the untouched pixels have that material's exact albedo.
        assert same.mean() > 0.4, (name, same.mean())
        changed_total += int((~same).sum())
    assert changed_total > 20, "the rust shows somewhere"


def test_decals_layer_over_the_material_they_land_on(model, tmp_path):
    from synthgen.outputs.files import write_exr

    d, mesh = model
    img = str(tmp_path / "sticker.exr")
    write_exr(img, np.full((8, 8, 3), 0.5, np.float32))
    clean, ids = albedo_of(scenario(mesh), d)
    dec, ids1 = albedo_of(scenario(mesh, f", decals: [{{image: {img}, size: 0.5, height: 0.5}}]"), d)
    np.testing.assert_array_equal(ids1, ids)
    regions = _regions(clean, ids)
    sticker = np.all(np.abs(dec - 0.5) < 1e-6, axis=-1) & (ids == 1)
    assert sticker.sum() > 30, "the decal shows on the model's front"
    # Outside the decal every material keeps its own albedo.
    for name, m in regions.items():
        outside = m & ~sticker
        np.testing.assert_array_equal(dec[outside], clean[outside])
    assert sum((m & ~sticker).sum() for m in regions.values()) > 300
