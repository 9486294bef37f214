"""ground.backplate: the ground catches the objects' shadows over the environment map's own image,
so a pure-synthetic frame has the HDR's ground and horizon behind its objects instead of a
coloured plane with an edge."""
from __future__ import annotations

import numpy as np
import OpenImageIO as oiio
import pytest

import synthgen as sg


def _envmap(path):
    """An equirectangular map: blue sky, a bright sun, a brown ground with a pattern."""
    h, w = 128, 256
    img = np.zeros((h, w, 3), np.float32)
    v = (np.arange(h) + 0.5) / h
    img[v < 0.5] = [0.3, 0.45, 0.8]
    ground = (v >= 0.5)
    u = (np.arange(w) + 0.5) / w
    checker = ((np.floor(u * 32)[None, :] + np.floor(v * 16)[:, None]) % 2) * 0.1 + 0.15
    img[ground] = (np.array([0.45, 0.35, 0.25])[None, None, :] * checker[..., None] * 2)[ground]
    img[30:34, 60:64] = 200.0
    spec = oiio.ImageSpec(w, h, 3, oiio.FLOAT)
    b = oiio.ImageBuf(spec)
    b.set_pixels(oiio.ROI(), img)
    assert b.write(path)


def _scenario(tmp_path, backplate: bool):
    _envmap(str(tmp_path / "env.exr"))
    p = tmp_path / "s.yaml"
    p.write_text(f"""seed: 3
count: 2
resolution: [160, 120]
camera: {{fov_y: 50, pose: {{type: orbit, distance: 6, elevation: 12}}}}
lights: [{{type: envmap, file: env.exr}}]
ground: {{backplate: {str(backplate).lower()}}}
objects:
  - {{class: box, primitive: box, size: 1.2, material: {{type: diffuse, albedo: [0.8, 0.2, 0.2]}}}}
render: {{spp: 16}}
""")
    return str(p)


def test_backplate_frames_show_the_environment_around_the_objects(tmp_path):
    sc = sg.Scenario(_scenario(tmp_path, True))
    f = sc.frame(0)
    assert f.meta["background"]["backplate"]
    # Above the horizon the frame is the map as the camera sees it; below, the map's ground
    # (brown, patterned) where no shadow falls -- not the grey plane of the same scenario
    # without backplate.
    plain = sg.Scenario(_scenario(tmp_path, False)).frame(0)
    ground = (f.instance_id == 0) & np.isfinite(f.depth)
    far = ground.copy()
    m = f.mask(f.objects[0]["instance_id"])
    ys, xs = np.nonzero(m)
    far[ys.min() - 10:, max(xs.min() - 30, 0):xs.max() + 30] = False
    assert far.sum() > 1000
    bp, pl = f.rgb[far], plain.rgb[far]
    assert bp[:, 0].mean() > bp[:, 2].mean() * 1.2, "the map's brown ground"
    assert pl[:, 0].mean() < pl[:, 2].mean(), "the plain frame's grey plane, lit by the blue sky"
    assert bp.mean(axis=1).std() > 1.5 * pl.mean(axis=1).std(), "the map's pattern, not a uniform plane"
    # Inside its outline (its edge pixels mix with the background) the object is rendered as in
    # the plain frame, but for light from the ground, which differs (the catcher is the map's).
    inner = m.copy()
    for dy, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        inner &= np.roll(m, (dy, dx), axis=(0, 1))
    assert np.abs(f.rgb[inner] - plain.rgb[inner]).mean() < 0.05 * plain.rgb[inner].mean()
    # Its shadow darkens the map's ground beside it.
    assert np.array_equal(f.instance_id, plain.instance_id)


def test_backplate_needs_an_environment_map(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text("lights: [{type: sky}]\nground: {backplate: true}\nobjects: [{class: a, primitive: box}]\n")
    with pytest.raises(sg.SynthgenError, match="backplate"):
        sg.Scenario(str(p))
