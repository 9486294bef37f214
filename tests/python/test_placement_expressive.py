"""What placement can express: per-entry regions, tilted objects (roll, pitch) resting on
the ground, objects stacked on others (rests_on), objects placed by their size in the image
(pixel_height), and negative frames."""
import numpy as np
import pytest

import synthgen as sg
from synthgen import scenario
from synthgen.frame.renderer import FrameRenderer

HEAD = """seed: {seed}
count: {count}
resolution: [160, 120]
camera: {{fov_y: 50, pose: {{type: orbit, distance: 9, elevation: 20, azimuth: {{uniform: [0, 360]}}}}}}
render: {{spp: 1, max_depth: 1}}
placement: {{min_pixels: 0, max_retries: 5}}
"""


def _frames(tmp_path, body, count=6, seed=1):
    p = tmp_path / "s.yaml"
    p.write_text(HEAD.format(seed=seed, count=count) + body)
    sc = scenario.load_scenario(p)
    fr = FrameRenderer(sc)
    for k in range(sc.count):
        arrays, meta, _ = fr.render(k)
        yield fr, arrays, meta


def _world_points(fr, o):
    """World-space vertices of a placed object's mesh."""
    pos = np.asarray(fr.scene.mesh_arrays(o.shape.mesh_id)["positions"], np.float64)
    return pos @ o.world[:3, :3].T + o.world[:3, 3]


def test_each_entry_stands_in_its_region(tmp_path):
    body = """objects:
  - {class: left, primitive: box, size: 0.4, count: 3, region: [-4, -1, -2, 1]}
  - {class: right, primitive: sphere, size: 0.4, count: 3, region: [2, -1, 4, 1]}
"""
    for fr, _, meta in _frames(tmp_path, body):
        for o in fr.objects:
            if o.world is None:
                continue
            x, z = o.world[0, 3], o.world[2, 3]
            lo = -4 if o.spec.class_name == "left" else 2
            assert lo <= x <= lo + 2 and -1 <= z <= 1, (o.spec.class_name, x, z)


def test_tilted_objects_rest_on_the_ground(tmp_path):
    body = """objects:
  - {class: box, primitive: box, size: [1.2, 0.5, 0.8], count: 2, roll: {uniform: [-60, 60]}, pitch: {uniform: [-45, 45]}}
  - {class: can, primitive: cylinder, size: [0.4, 1.0, 0.4], count: 1, roll: 90}
"""
    tilts = 0
    for fr, _, meta in _frames(tmp_path, body):
        for o in fr.objects:
            if o.world is None:
                continue
            p = _world_points(fr, o)
            assert p[:, 1].min() == pytest.approx(0.0, abs=1e-5), "resting on the ground"
            up = o.world[:3, 1] / np.linalg.norm(o.world[:3, 1])
            tilts += up[1] < 0.99
            if o.spec.class_name == "can":  # on its side: its axis horizontal, height = its diameter
                assert abs(up[1]) < 1e-6 and p[:, 1].max() == pytest.approx(0.4, abs=1e-3)
    assert tilts >= 6


def test_stacked_objects_rest_on_the_top_of_their_support(tmp_path):
    body = """objects:
  - {class: table, name: table, primitive: box, size: [1.6, 0.8, 1.0], count: 1}
  - {class: cup, primitive: cylinder, size: [0.15, 0.2, 0.15], count: 3, rests_on: table}
"""
    for fr, arrays, meta in _frames(tmp_path, body):
        table = next(o for o in fr.objects if o.spec.class_name == "table")
        tp = _world_points(fr, table)
        for o in fr.objects:
            if o.spec.class_name != "cup" or o.world is None:
                continue
            p = _world_points(fr, o)
            assert p[:, 1].min() == pytest.approx(tp[:, 1].max(), abs=1e-5), "on the table's top"
            # Within the table's top (its footprint, in the table's own frame).
            local = (p - table.world[:3, 3]) @ (table.world[:3, :3] / np.linalg.norm(table.world[:3, :3], axis=0))
            assert np.all(np.abs(local[:, 0]) <= 0.8 + 1e-4) and np.all(np.abs(local[:, 2]) <= 0.5 + 1e-4)
        cups = [o for o in fr.objects if o.spec.class_name == "cup" and o.world is not None]
        for i, a in enumerate(cups):  # cups on one table do not overlap
            for b in cups[i + 1:]:
                assert np.hypot(*(a.world[[0, 2], 3] - b.world[[0, 2], 3])) >= a.radius + b.radius


def test_pixel_height_sets_the_size_in_the_image(tmp_path):
    """The box's height in the image is the asked one (its projected corners, so the box's
    depth and the camera's pitch are included), up to the mask's pixel rounding."""
    body = """objects:
  - {class: box, primitive: box, size: [0.5, 1.0, 0.5], count: 2, pixel_height: {uniform: [12, 60]}}
""".replace("elevation: 20", "")
    text = HEAD.replace("elevation: 20", "elevation: 6")
    p = tmp_path / "s.yaml"
    p.write_text(text.format(seed=3, count=10) + body)
    fr = FrameRenderer(scenario.load_scenario(p))
    got = []
    for k in range(10):
        arrays, meta, _ = fr.render(k)
        for o, rec in zip(fr.objects, meta["objects"]):
            if "bbox" in rec and rec["occlusion"] == 0:
                got.append((rec["bbox"][3], o.spec.pixel_height))
    assert len(got) >= 10
    for h, target in got:
        assert abs(h - target) <= 1.5 + 0.03 * target, got


def test_negative_frames_have_no_labelled_objects(tmp_path):
    body = """negative_frames: 0.3
objects:
  - {class: box, primitive: box, size: 0.5, count: 2}
  - {label: false, primitive: sphere, size: 0.5, count: 1}
"""
    negatives = 0
    n = 40
    for fr, arrays, meta in _frames(tmp_path, body, count=n, seed=5):
        labelled = [o for o in meta["objects"] if o.get("label", True)]
        if meta["negative"]:
            negatives += 1
            assert not labelled and np.all(np.asarray(arrays["instance_id"]) == 0)
            assert len(meta["objects"]) == 1, "the unlabelled entry stays"
        else:
            assert len(labelled) == 2
    assert abs(negatives - 0.3 * n) < 4 * np.sqrt(n * 0.3 * 0.7)


@pytest.mark.parametrize("body, message", [
    ("objects:\n  - {class: a, primitive: box, rests_on: tabel}\n  - {class: b, name: table, primitive: box}\n",
     r"objects\[0\].rests_on: no object entry is named 'tabel' \(did you mean 'table'\?\)"),
    ("objects:\n  - {class: a, primitive: box, rests_on: a}\n", r"an entry cannot rest on itself"),
    ("objects:\n  - {class: a, name: x, primitive: box, rests_on: y}\n  - {class: b, name: y, primitive: box, rests_on: x}\n",
     r"form a cycle"),
    ("objects:\n  - {class: a, primitive: box, region: [1, 0, 0, 1]}\n", r"objects\[0\].region: region must satisfy"),
])
def test_placement_mistakes_are_named(tmp_path, body, message):
    p = tmp_path / "s.yaml"
    p.write_text(body)
    with pytest.raises(sg.SynthgenError, match=message):
        scenario.load_scenario(p)


def test_what_rests_on_a_dropped_object_is_dropped_too(tmp_path):
    """A table that must be half hidden (max_visible_fraction 0.01, impossible alone) is
    dropped; the cups on it go with it instead of floating."""
    body = """objects:
  - {class: table, name: table, primitive: box, size: [1.6, 0.8, 1.0], count: 1, max_visible_fraction: 0.01}
  - {class: cup, primitive: cylinder, size: [0.15, 0.2, 0.15], count: 2, rests_on: table}
"""
    for fr, arrays, meta in _frames(tmp_path, body, count=2):
        recs = {o["class"]: o for o in meta["objects"]}
        assert "dropped" in recs["table"]
        for o in meta["objects"]:
            if o["class"] == "cup":
                assert o["dropped"] == "the object it rests on was dropped"
        assert np.all(np.asarray(arrays["instance_id"]) == 0)
