"""Scenario validation (file:line:col errors) and the distributions' statistics."""
from __future__ import annotations

import os

import numpy as np
import pytest

from synthgen.schema import distributions as D
from synthgen import scenario as S
from synthgen import SceneFileError

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))

BASE = """\
version: 1
seed: 3
count: 2
resolution: [64, 48]
objects:
  - class: box
    primitive: box
    size: {uniform: [0.5, 1.0]}
"""


def load_text(tmp_path, text: str) -> S.Scenario:
    p = tmp_path / "s.yaml"
    p.write_text(text)
    return S.load_scenario(str(p))


def error_of(tmp_path, text: str) -> SceneFileError:
    with pytest.raises(SceneFileError) as ei:
        load_text(tmp_path, text)
    return ei.value


def test_shipped_scenarios_validate():
    for name in ("scenarios/default.yaml", "scenarios/road_signs.yaml", "scenarios/augmented_road.yaml",
                 "scenarios/vehicles.yaml", "tests/python/scenarios/tiny.yaml"):
        sc = S.load_scenario(os.path.join(REPO, name))
        assert sc.class_names and sc.count >= 1


@pytest.mark.parametrize("snippet, line, col, key, words", [
    # unknown key with a close spelling
    ("objects:\n  - class: box\n    primitive: box\n    sise: 1\n", 4, 5, "objects[0].sise", ["did you mean 'size'"]),
    # out of range, with the allowed range stated
    ("placement: {min_visible_fraction: 1.5}\nobjects:\n  - {class: a, primitive: box}\n", 1, 35,
     "placement.min_visible_fraction", ["out of range", "[0, 1]"]),
    # a distribution bound out of range
    ("camera: {fov_y: {uniform: [10, 200]}}\nobjects:\n  - {class: a, primitive: box}\n", 1, 32,
     "camera.fov_y.uniform[1]", ["out of range", "(0, 180)"]),
    # misspelled distribution
    ("camera: {fov_y: {unifrom: [10, 20]}}\nobjects:\n  - {class: a, primitive: box}\n", 1, 17, "camera.fov_y",
     ["did you mean 'uniform'", "distributions:"]),
    # inverted bounds
    ("camera: {fov_y: {uniform: [50, 20]}}\nobjects:\n  - {class: a, primitive: box}\n", 1, 27,
     "camera.fov_y.uniform", ["low <= high"]),
    # integer slot given a real distribution
    ("objects:\n  - {class: a, primitive: box, count: {uniform: [1, 3]}}\n", 2, 49, "objects[0].count.uniform",
     ["{int: [low, high]}"]),
    # bad choice value
    ("objects:\n  - {class: a, primitive: cones}\n", 2, 27, "objects[0].primitive", ["unknown value 'cones'",
                                                                                   "box, sphere, cylinder, cone",
                                                                                   "did you mean 'cone'"]),
    # bad choice inside a choice distribution
    ("objects:\n  - {class: a, primitive: {choice: [box, sphre]}}\n", 2, 42, "objects[0].primitive.choice[1]",
     ["did you mean 'sphere'"]),
    # weights of the wrong length
    ("objects:\n  - {class: a, primitive: {choice: [box, sphere], weights: [1]}}\n", 2, 60,
     "objects[0].primitive.weights", ["list of 2 numbers"]),
    # missing required section
    ("seed: 1\n", 1, 1, "", ["missing required key 'objects'"]),
    # wrong type
    ("count: many\nobjects:\n  - {class: a, primitive: box}\n", 1, 8, "count", ["expected an integer"]),
    # mesh and primitive together
    ("objects:\n  - {class: a, primitive: box, mesh: x.obj}\n", 2, 32, "objects[0].mesh", ["cannot be combined"]),
    # material parameter of another type
    ("objects:\n  - {class: a, primitive: box, material: {type: diffuse, ior: 1.5}}\n", 2, 58,
     "objects[0].material.ior", ["not allowed with type 'diffuse'"]),
    # normal truncated away from its mass
    ("camera: {fov_y: {normal: [100, 1], min: 150}}\nobjects:\n  - {class: a, primitive: box}\n", 1, 17, "camera.fov_y",
     ["of its mass"]),
])
def test_errors_name_file_line_column_key(tmp_path, snippet, line, col, key, words):
    e = error_of(tmp_path, snippet)
    assert e.source.endswith("s.yaml")
    assert (e.line, e.column, e.key_path) == (line, col, key), str(e)
    for w in words:
        assert w in str(e), str(e)


def test_yaml_is_safe_loaded(tmp_path):
    e = error_of(tmp_path, BASE.replace("seed: 3", "seed: !!python/object/apply:os.system ['echo hi']"))
    assert e.source.endswith("s.yaml") and e.line == 2 and "python/object" in str(e)


def test_frame_parameters_depend_only_on_seed_and_frame(tmp_path):
    sc = load_text(tmp_path, BASE + "    count: {int: [1, 4]}\n    yaw: {uniform: [0, 360]}\n")
    a = S.sample_frame(sc, 5)
    b = S.sample_frame(sc, 5)
    assert a.sampled == b.sampled and a.sampled and a == b
    assert S.sample_frame(sc, 6).sampled != a.sampled
    sc2 = load_text(tmp_path, BASE.replace("seed: 3", "seed: 4") + "    count: {int: [1, 4]}\n")
    assert S.sample_frame(sc2, 5).sampled != a.sampled


def test_distribution_statistics():
    rng = np.random.default_rng(0)
    n = 20000
    u = np.array([D.Uniform(2.0, 5.0).sample(rng) for _ in range(n)])
    assert u.min() >= 2.0 and u.max() <= 5.0 and abs(u.mean() - 3.5) < 0.03
    v = np.array([D.Uniform((0.0, 1.0), (1.0, 3.0)).sample(rng) for _ in range(2000)])
    assert v.shape == (2000, 2) and np.all(v[:, 1] >= 1.0) and abs(v[:, 1].mean() - 2.0) < 0.05
    g = np.array([D.Normal(0.0, 1.0, -1.0, 2.0).sample(rng) for _ in range(n)])
    assert g.min() >= -1.0 and g.max() <= 2.0
    # Mean of a standard normal truncated to [-1, 2]: (phi(-1) - phi(2)) / (Phi(2) - Phi(-1)).
    phi = lambda x: np.exp(-x * x / 2) / np.sqrt(2 * np.pi)  # noqa: E731
    expect = (phi(-1.0) - phi(2.0)) / D.Normal(0.0, 1.0, -1.0, 2.0).acceptance()
    assert abs(g.mean() - expect) < 0.02
    lg = np.log10([D.LogUniform(0.01, 1.0).sample(rng) for _ in range(n)])
    assert abs(lg.mean() + 1.0) < 0.02 and lg.min() >= -2.0 and lg.max() <= 0.0
    ints = np.array([D.IntUniform(1, 3).sample(rng) for _ in range(n)])
    counts = np.bincount(ints, minlength=4)[1:]
    assert counts.sum() == n and np.all(np.abs(counts / n - 1 / 3) < 0.02), "both ends included, uniform"
    c = D.Choice(["a", "b", "c"], [1.0, 2.0, 1.0])
    picks = [c.sample(rng) for _ in range(n)]
    freq = np.array([picks.count(x) for x in "abc"]) / n
    # Chi-square with 2 degrees of freedom, 0.1% level: 13.8.
    exp = np.array([0.25, 0.5, 0.25]) * n
    chi2 = float((((freq * n) - exp) ** 2 / exp).sum())
    assert chi2 < 13.8, chi2
    hsv = D.HsvJitter((0.8, 0.2, 0.1), h=0.05, s=0.1, v=0.1)
    cols = np.array([hsv.sample(rng) for _ in range(2000)])
    assert cols.min() >= 0.0 and cols.max() <= 1.0
    assert np.all(cols[:, 0] > cols[:, 2]), "a red stays reddish under a small hue jitter"
    assert D.HsvJitter((0.3, 0.6, 0.9)).sample(rng) == pytest.approx((0.3, 0.6, 0.9))
