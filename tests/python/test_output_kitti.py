"""KITTI labels of real models: the 3D box follows the model's own axes (forward and up from
its asset entry), so its dimensions (h, w, l) and rotation_y are KITTI's, in a level camera
frame that the calibration's P2 projects into the (tilted) image: the projected box encloses
the object's mask, length is the longer side of a car, and the box's front face is where the
car's headlights are."""
import json
import os

import numpy as np
import pytest

from synthgen import run as runner
from synthgen.outputs.kitti import parse_calib, parse_kitti
from synthgen.scene import assets

import OpenImageIO as oiio

HERE = os.path.dirname(os.path.abspath(__file__))


def _asset(asset_id):
    try:
        return assets.resolve(asset_id)
    except Exception as e:  # noqa: BLE001 - no ../shared, no apt: nothing to test with
        pytest.skip(f"{asset_id} is not available: {e}")


def corners(dims, loc, ry):
    """The 8 corners (camera frame) of a KITTI box, and the centres of its front and back faces."""
    h, w, l = dims
    x = np.array([1, 1, -1, -1, 1, 1, -1, -1]) * l / 2
    y = np.array([0, 0, 0, 0, -1, -1, -1, -1]) * h
    z = np.array([1, -1, 1, -1, 1, -1, 1, -1]) * w / 2
    c, s = np.cos(ry), np.sin(ry)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    pts = (R @ np.stack([x, y, z])).T + np.asarray(loc)
    front = R @ np.array([l / 2, -h / 2, 0]) + loc
    back = R @ np.array([-l / 2, -h / 2, 0]) + loc
    return pts, front, back


def project(P2, p):
    """Image points of points in the labels' frame, through the calibration's P2."""
    q = np.asarray(P2) @ np.c_[np.atleast_2d(p), np.ones(len(np.atleast_2d(p)))].T
    return (q[:2] / q[2]).T


@pytest.mark.parametrize("asset_id, front_material_z", [("mesh/kenney-vehicle-truck-red", None),
                                                         ("mesh/sumo-car-normal-citrus", 0.9)])
def test_kitti_boxes_follow_the_models_axes(tmp_path, asset_id, front_material_z):
    _asset(asset_id)
    scen = tmp_path / "s.yaml"
    scen.write_text(f"""
seed: 5
resolution: [160, 120]
camera: {{fov_y: 45, pose: {{type: orbit, target: [0, 0.6, 0], distance: 9, elevation: 20, azimuth: {{uniform: [0, 360]}}}}}}
lights: [{{type: environment, radiance: 1.0}}]
objects: [{{class: car, asset: {asset_id}, yaw: {{uniform: [0, 360]}}}}]
placement: {{region: [-0.5, -0.5, 0.5, 0.5]}}
render: {{spp: 1, max_depth: 1}}
outputs: [instance, kitti, kitti_calib]
""")
    out = str(tmp_path / "ds")
    s = runner.run(str(scen), out, count=4, progress=False)
    assert not s["failures"], s.text()
    for k in range(4):
        with open(os.path.join(out, "meta", f"{k:06d}.json")) as f:
            meta = json.load(f)
        calib = parse_calib(open(os.path.join(out, "kitti_calib", f"{k:06d}.txt")).read())
        P2 = np.asarray(calib["P2"]).reshape(3, 4)
        assert calib["R0_rect"] == [1, 0, 0, 0, 1, 0, 0, 0, 1]
        ids = np.asarray(oiio.ImageBuf(os.path.join(out, "instance", f"{k:06d}.png")).get_pixels(oiio.UINT16))[..., 0]
        lab = parse_kitti(open(os.path.join(out, "kitti", f"{k:06d}.txt")).read())[0]
        h, w, l = lab["dimensions"]
        assert l > w, f"length {l} <= width {w}: KITTI's l runs along the car"
        pts, front, back = corners(lab["dimensions"], lab["location"], lab["rotation_y"])
        uv = project(P2, pts)
        ys, xs = np.nonzero(ids == 1)
        # The projected box encloses the mask (to the pixel) ...
        assert uv[:, 0].min() <= xs.min() + 1 and uv[:, 0].max() >= xs.max() and \
            uv[:, 1].min() <= ys.min() + 1 and uv[:, 1].max() >= ys.max(), (k, uv.min(0), uv.max(0))
        # ... and is not much larger than it (a box with the right dimensions).
        box_area = np.ptp(uv[:, 0]) * np.ptp(uv[:, 1])
        mask_area = (np.ptp(xs) + 1) * (np.ptp(ys) + 1)
        assert box_area < 2.2 * mask_area, (k, box_area, mask_area)
        if front_material_z is not None:
            # The headlights (model z ~ +0.9 on the model's centre line) project nearer to the
            # box's front face than to its back face.
            world = np.asarray(meta["objects"][0]["world_from_object"])
            velo_to_cam = np.asarray(calib["Tr_velo_to_cam"]).reshape(3, 4)
            lamp = velo_to_cam @ world @ np.array([0.0, 0.4, front_material_z, 1.0])
            lamp_uv = project(P2, lamp)[0]
            d_front = np.linalg.norm(lamp_uv - project(P2, front)[0])
            d_back = np.linalg.norm(lamp_uv - project(P2, back)[0])
            assert d_front < d_back, (k, d_front, d_back)
