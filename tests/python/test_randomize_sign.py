"""Randomizer "sign": whole signs on whole poles -- at every size and for every family the
post reaches the panel's opaque part (no panel floating above a gap); and, for every outdoor
frame, the ground reaches the horizon (no band of background below it)."""
import math
import os

import numpy as np
import pytest

from synthgen.frame import FrameRenderer
from synthgen.scenario import parse_scenario
from synthgen.scene import signs
from synthgen.schema.yaml_io import parse_yaml


def renderer(text):
    return FrameRenderer(parse_scenario(parse_yaml(text), "s.yaml", os.getcwd(), text))


def _opaque_rows(family):
    """(lowest, highest) opaque row of the pictogram's middle column, as fractions of its
    height from the bottom."""
    a = np.asarray(signs.render_sign(family, None, 256)["rgba"])[..., 3]
    col = a[:, a.shape[1] // 2 - 3: a.shape[1] // 2 + 3].max(axis=1) >= 0.5
    rows = np.nonzero(col)[0]
    h = a.shape[0]
    return 1.0 - (rows.max() + 1) / h, 1.0 - rows.min() / h


@pytest.mark.parametrize("family", signs.FAMILIES)
def test_post_reaches_the_panel_at_every_size(family):
    text = f"""
seed: 1
resolution: [64, 48]
camera: {{pose: {{type: orbit, target: [0, 1, 0], distance: 8, elevation: 5}}}}
lights: [{{type: environment, radiance: 1}}]
objects: [{{class: s, count: 3, sign: {{family: {family}, size: {{uniform: [0.2, 1.6]}}, mount_height: {{uniform: [0.3, 2.5]}}}}}}]
placement: {{region: [-3, -1, 3, 1], min_pixels: 0}}
render: {{spp: 1, max_depth: 1}}
"""
    fr = renderer(text)
    low, high = _opaque_rows(family)
    for frame in range(4):
        fr.render(frame)
        for o in fr.objects:
            s = o.dims[0]                       # panel width = height
            mount = o.dims[1] - s               # its lower edge
            post_top = (o.post_world @ np.array([0.0, 0.5, 0.0, 1.0]))[1]
            panel_bottom_visible = mount + low * s
            # the post runs into the opaque panel: its top is behind it, at or above its visible
            # bottom and below its visible top
            assert panel_bottom_visible <= post_top + 1e-9 <= mount + high * s + 1e-6, \
                (family, frame, s, mount, post_top, panel_bottom_visible)
            # posts stand on the ground under their panels
            assert abs((o.post_world @ np.array([0.0, -0.5, 0.0, 1.0]))[1]) < 1e-9
            assert np.allclose(o.post_world[[0, 2], 3], (o.world @ np.array([0.0, 0.0, 0.03 / 1.0, 1.0]))[[0, 2]],
                               atol=0.05)


@pytest.mark.parametrize("elevation", [2, 10, 35])
def test_the_ground_reaches_the_horizon(elevation):
    w, h = 160, 120
    text = f"""
seed: 2
resolution: [{w}, {h}]
camera: {{fov_y: 50, pose: {{type: orbit, target: [0, 1, 0], distance: 6, elevation: {elevation}}}}}
lights: [{{type: sky, elevation: 30, strength: 0.02}}]
objects: [{{class: box, primitive: box, count: 1}}]
placement: {{region: [-1, -1, 1, 1]}}
render: {{spp: 1, max_depth: 1}}
"""
    fr = renderer(text)
    arrays, meta, _ = fr.render(0)
    depth = arrays["depth"]
    cam = fr.scene.camera
    below = np.zeros((h, w), bool)
    pixel_angle = math.radians(50) / h
    for j in range(h):
        for i in range(w):
            _, d = cam.generate_ray(i + 0.5, j + 0.5)
            below[j, i] = d[1] < -math.tan(1.5 * pixel_angle)
    assert below.sum() > 0.2 * w * h
    # Every pixel whose ray points below the horizon (by more than a pixel and a half) hits
    # the ground or an object: no band of background between the ground's edge and the horizon.
    assert np.isfinite(depth[below]).all(), int((~np.isfinite(depth[below])).sum())
