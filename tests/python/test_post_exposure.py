"""Post-processing step "exposure": the image times 2^ev, labels untouched, and in a
scenario the same frame with and without the step differs only in the image."""
import json
import os

import numpy as np
import OpenImageIO as oiio
import pytest

from synthgen import post
from synthgen.frame import FrameRenderer
from synthgen.scenario import parse_scenario
from synthgen.schema.yaml_io import parse_yaml


def test_exposure_scales_the_image_only():
    rng = np.random.default_rng(2)
    arrays = {"rgb": rng.random((4, 5, 3), dtype=np.float32), "depth": rng.random((4, 5), dtype=np.float32),
              "instance_id": np.arange(20, dtype=np.uint32).reshape(4, 5)}
    out = post.apply_steps(arrays, [("exposure", {"ev": 1.0}), ("exposure", {"ev": -3.0})])
    np.testing.assert_array_equal(out["rgb"], arrays["rgb"] * np.float32(2.0) * np.float32(0.125))
    assert out["depth"] is arrays["depth"] and out["instance_id"] is arrays["instance_id"]
    assert arrays["rgb"].max() <= 1.0  # the input is not modified


SCENARIO = """
seed: 5
resolution: [40, 30]
camera: {fov_y: 45, pose: {type: orbit, distance: 5, elevation: 20}}
lights: [{type: environment, radiance: 0.6}]
objects:
  - {class: box, primitive: box, count: 2, material: {type: diffuse, albedo: 0.6}}
render: {spp: 2, max_depth: 2}
"""


def _render(text, frame=1):
    sc = parse_scenario(parse_yaml(text), "s.yaml", os.getcwd(), text)
    return FrameRenderer(sc).render(frame)


def test_exposure_in_a_scenario_changes_only_the_image():
    a, meta_a, _ = _render(SCENARIO)
    b, meta_b, _ = _render(SCENARIO + "post: [{type: exposure, ev: {uniform: [0.5, 1.5]}}]\n")
    ev = meta_b["post"][0]["params"]["ev"]
    assert 0.5 <= ev <= 1.5 and meta_b["sampled"]["post[0].ev"] == ev
    np.testing.assert_array_equal(b["rgb"], (a["rgb"] * np.float32(2.0 ** ev)).astype(np.float32))
    for k in ("depth", "instance_id", "class_id"):
        np.testing.assert_array_equal(a[k], b[k])
    assert "post" not in meta_a
    # Everything drawn before the post-processing steps is drawn as without them.
    assert {k: v for k, v in meta_b["sampled"].items() if not k.startswith("post")} == meta_a["sampled"]
