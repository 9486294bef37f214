"""Output kinds ``normal`` and ``albedo``: the ground's normal is the world's up turned into
the camera frame, unit length on every hit and 0 on the sky; the albedo is the materials'."""
import json

import numpy as np
import OpenImageIO as oiio

from synthgen.outputs.surface import camera_normals
from synthgen.run import runner

SCENARIO = """
seed: 2
count: 2
resolution: [64, 48]
camera: {fov_y: 60, pose: {type: orbit, distance: 5, elevation: {uniform: [10, 30]}, azimuth: {uniform: [0, 360]}}}
lights: [{type: sky, strength: 0.02}]
ground: {material: {type: diffuse, albedo: [0.3, 0.2, 0.1]}}
objects:
  - {class: box, primitive: box, size: 1.0, material: {type: diffuse, albedo: 0.6}}
render: {spp: 2, max_depth: 2}
outputs: [rgb, semantic, depth, normal, albedo]
"""


def _read(path):
    buf = oiio.ImageBuf(str(path))
    return np.asarray(buf.get_pixels(oiio.FLOAT)), buf.spec().channelnames


def test_normals_and_albedo_of_a_run(tmp_path):
    sc = tmp_path / "s.yaml"
    sc.write_text(SCENARIO)
    out = tmp_path / "ds"
    s = runner.run(str(sc), str(out), progress=False)
    assert s["rendered"] == 2, s.text()
    for k in range(2):
        meta = json.loads((out / "meta" / f"{k:06d}.json").read_text())
        n, names = _read(out / "normal" / f"{k:06d}.exr")
        alb, _ = _read(out / "albedo" / f"{k:06d}.exr")
        depth, _ = _read(out / "depth" / f"{k:06d}.exr")
        cls = np.asarray(oiio.ImageBuf(str(out / "semantic" / f"{k:06d}.png")).get_pixels(oiio.UINT16))[..., 0]
        assert names == ("X", "Y", "Z") and n.shape == (48, 64, 3)
        hit = np.isfinite(depth[..., 0])
        assert np.allclose(np.linalg.norm(n[hit], axis=1), 1.0, atol=1e-3)
        assert np.all(n[~hit] == 0) and np.all(alb[~hit] == 0)
        # The ground: world up (0, 1, 0) in the camera frame, i.e. the second row of the
        # camera's rotation (R^T up); it faces the camera (z < 0).
        r = np.asarray(meta["camera"]["world_from_camera"])[:3, :3]
        ground = hit & (cls == 0)
        assert ground.sum() > 100
        assert np.allclose(n[ground], r[1], atol=1e-3) and r[1][2] < 0
        assert np.allclose(alb[ground], [0.3, 0.2, 0.1], atol=1e-3)
        assert np.allclose(alb[cls == 1], 0.6, atol=1e-3)
        # Box faces are axis-aligned in the box's frame: in the world every box normal is
        # horizontal or vertical.
        wn = n[cls == 1] @ r.T
        assert np.all(np.isclose(np.abs(wn[:, 1]), 1.0, atol=1e-3) | np.isclose(wn[:, 1], 0.0, atol=1e-3))


def test_camera_normals_is_the_inverse_rotation():
    a = np.radians(30.0)
    w = np.eye(4)
    w[:3, :3] = [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
    n = np.array([[[np.sin(a), 0.0, np.cos(a)]]])  # the camera's forward axis in the world
    assert np.allclose(camera_normals(n, w), [[[0.0, 0.0, 1.0]]])
