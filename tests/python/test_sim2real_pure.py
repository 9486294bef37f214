"""bench/sim2real/pure.py: the pure synthetic scenario of sim2real validates; rendered small, its
cars stand on the far carriageway below the rig's horizon, and each car's box height is the
pinhole law's (focal length x the car's height / its depth) for the camera the rig asks for;
the same arguments write the same file and render the same frames; a rig's lens distortion
goes into the scenario camera, a malformed one is refused. Also the frame renderer's material
slots: a slot whose object became a model with its own materials (or a sign) lets go of the
previous frame's textures (a variable count used to fail the next frame)."""
from __future__ import annotations

import importlib.util
import json
import math
import os

import numpy as np
import pytest
import yaml

import synthgen as sg
from synthgen import run as runner
from synthgen.scenario import load_scenario
from synthgen.scene import assets

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location(
    "sim2real_pure", os.path.join(HERE, "..", "..", "bench", "sim2real", "pure.py"))
pure = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(pure)


def _torcs_cached() -> bool:
    m = assets.load_manifest()
    for aid in ("mesh/torcs-p406", "mesh/torcs-155-DTM", "mesh/torcs-acura-nsx-sz"):
        e = m[aid]
        if not os.path.isfile(os.path.join(assets.cache_dir(), aid, os.path.basename(e["source"]["path"]))):
            return False
    return True


def test_written_scenario_validates_and_is_reproducible(tmp_path):
    a = pure.write_pure_scenario(str(tmp_path / "a.yaml"), seed=5, count=4, spp=2)
    b = pure.write_pure_scenario(str(tmp_path / "b.yaml"), seed=5, count=4, spp=2)
    c = pure.write_pure_scenario(str(tmp_path / "c.yaml"), seed=6, count=4, spp=2)
    assert open(a).read() == open(b).read()
    assert open(a).read() != open(c).read()  # the ground variants come from the seed
    sc = load_scenario(a)  # validates (as synthgen validate does)
    assert sc.resolution == (676, 380)
    d = yaml.safe_load(open(a))
    # fov_x 90 over 676 px: fx = 338 / tan(45 deg) = 338.
    assert d["camera"]["fx"] == pytest.approx(338.0)
    assert {o["class"] for o in d["objects"] if o.get("label", True)} == {"car"}
    assert "rgb" in d["outputs"] and "coco" in d["outputs"]


def test_rig_distortion_goes_into_the_camera_and_bad_rigs_are_refused(tmp_path):
    p = pure.write_pure_scenario(str(tmp_path / "d.yaml"), seed=1, count=1, rig={"distortion": [-0.3, 0.1, 0, 0.001]})
    cam = yaml.safe_load(open(p))["camera"]
    assert (cam["k1"], cam["k2"], cam["p2"]) == (-0.3, 0.1, 0.001) and "p1" not in cam and "k3" not in cam
    load_scenario(p)  # validates: rgb and coco, no kitti
    plain = yaml.safe_load(open(pure.write_pure_scenario(str(tmp_path / "z.yaml"), seed=1, count=1,
                                                         rig={"distortion": [0, 0, 0, 0, 0]})))["camera"]
    assert not {"k1", "k2", "p1", "p2", "k3"} & set(plain)
    with pytest.raises(sg.SynthgenError, match=r"rig distortion \[-0.3, 0.1\]: expected OpenCV's 4 or 5"):
        pure.write_pure_scenario(str(tmp_path / "e.yaml"), seed=1, count=1, rig={"distortion": [-0.3, 0.1]})
    with pytest.raises(sg.SynthgenError, match="rig key 'fov_y' unknown"):
        pure.write_pure_scenario(str(tmp_path / "e.yaml"), seed=1, count=1, rig={"fov_y": 50})
    assert not os.path.exists(tmp_path / "e.yaml")


def test_cars_stand_below_the_horizon_and_scale_with_distance(tmp_path):
    w, h = 338, 190  # half the real frames' size: cars 10 to 60 px tall
    path = pure.write_pure_scenario(str(tmp_path / "p.yaml"), seed=3, count=3, spp=1, resolution=(w, h),
                                    torcs=_torcs_cached(), max_depth=2)
    s = runner.run(path, str(tmp_path / "out"), progress=False, isolate=False)
    assert not s["failures"]
    fx = 0.5 * w / math.tan(math.radians(45.0))
    horizon = 188.0 * h / 380.0
    # The pitch jitter moves the horizon by at most fx tan(PITCH_JITTER).
    slack = fx * math.tan(math.radians(pure.PITCH_JITTER)) + 0.5
    n_checked = 0
    coco = json.load(open(tmp_path / "out" / "annotations" / "coco.json"))
    assert len(coco["annotations"]) >= 3
    for f in range(3):
        meta = json.load(open(tmp_path / "out" / "meta" / f"{f:06d}.json"))
        cam = meta["camera"]
        assert (cam["fx"], cam["fy"], cam["width"], cam["height"]) == (pytest.approx(fx), pytest.approx(fx), w, h)
        # The level camera's horizon row (a point at infinity straight ahead, level).
        P2 = np.asarray(meta["kitti_frame"]["P2"])
        row = P2[1, 2] / P2[2, 2]
        assert abs(row - horizon) <= slack
        wfc = np.asarray(cam["world_from_camera"])
        assert wfc[1, 3] == pytest.approx(1.45, abs=0.051)  # the rig's height
        for o in meta["objects"]:
            if o.get("class") != "car" or "bbox" not in o:
                continue
            x, y, bw, bh = o["bbox"]
            depth = o["location_camera"][2]
            # On the far carriageway: its lanes are 4.8 to 20.8 m from the camera across the
            # road (a car off to the side is less deep, at most 0.8 m for its half-length).
            lanes = (pure.ROAD_Z + 0.5 * pure.LANE_WIDTH - 0.3 - pure.CAMERA_Z[1],
                     pure.ROAD_Z + (pure.LANES - 0.5) * pure.LANE_WIDTH + 0.3 - pure.CAMERA_Z[0])
            assert lanes[0] - 3.0 < depth < lanes[1] + 0.5
            # It stands on the ground below the horizon: the bottom of its box lies below the
            # horizon row by the ground's angle at its depth, fx x camera height / depth (the
            # height 1.40 to 1.50 m); a car hidden by a nearer one may show less of its bottom.
            bottom = y + bh
            assert bottom > row + 0.5 * fx * 1.40 / depth
            if o["truncation"] > 0 or o["occlusion"] > 0.02:
                continue
            # Its near side is up to 1.1 m closer than its centre.
            assert row + 0.95 * fx * 1.40 / depth - 1.0 <= bottom <= row + fx * 1.50 / (depth - 1.1) + 1.5
            # Pinhole law: the box is about fy H / Z tall (H: the car's height; Z: its depth;
            # the box spans its near and far edges, so up to a few per cent more).
            expected = fx * o["dimensions_hwl"][0] / depth
            assert 0.85 * expected - 1.0 <= bh <= 1.25 * expected + 1.5, (o["bbox"], depth, expected)
            n_checked += 1
    assert n_checked >= 2


def test_same_seed_renders_the_same_frames(tmp_path):
    path = pure.write_pure_scenario(str(tmp_path / "p.yaml"), seed=4, count=1, spp=1, resolution=(96, 54),
                                    torcs=False, max_depth=2)
    images = []
    for k in range(2):
        s = runner.run(path, str(tmp_path / f"out{k}"), progress=False, isolate=False)
        assert not s["failures"]
        images.append(open(tmp_path / f"out{k}" / "images" / "000000.png", "rb").read())
        assert len(json.load(open(tmp_path / f"out{k}" / "annotations" / "coco.json"))["images"]) == 1
    assert images[0] == images[1]


def test_material_slot_of_a_model_lets_go_of_the_last_frames_texture(tmp_path):
    """Object k is a textured sphere in one frame and a sign in the next (a variable count in
    front of it): the slot's old texture is released without a 'still used' failure."""
    sc = {
        "seed": 2, "count": 6, "resolution": [32, 24],
        "camera": {"fov_y": 50, "pose": {"type": "orbit", "target": [0, 0.5, 0], "distance": 8, "elevation": 10}},
        "objects": [
            {"class": "sign", "sign": {"family": "warning"}, "count": {"int": [0, 1]}},
            {"label": False, "primitive": "sphere", "count": {"int": [1, 2]},
             "material": {"type": "diffuse", "albedo": {"texture": {"type": "noise", "mapping": "world"}}}},
        ],
        "placement": {"region": [-3, -3, 3, 3], "allow_drops": True},
        "render": {"spp": 1, "max_depth": 1},
        "outputs": ["rgb"],
    }
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(sc))
    s = runner.run(str(path), str(tmp_path / "out"), progress=False, isolate=False)
    assert not s["failures"], s["failures"]
    counts = []
    for f in range(6):
        meta = json.load(open(tmp_path / "out" / "meta" / f"{f:06d}.json"))
        counts.append(sum(o.get("class") == "sign" for o in meta["objects"]))
    # The case that failed: a frame with the sign after one without (slot 0 was the sphere's).
    assert any(a == 0 and b == 1 for a, b in zip(counts, counts[1:])), counts
