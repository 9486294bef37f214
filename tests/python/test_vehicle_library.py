"""Every vehicle of the asset library, rendered: its labelled 3D box (KITTI) encloses its mask
and is tight around it, from several sides, and its size (length, width, height in metres) is
in the plausible range of its class. Optional assets (the TORCS cars) are tested when they are
in the cache (`synthgen assets fetch mesh/torcs-p406`); the small SUMO and Kenney models always.
"""
import json
import os

import numpy as np
import pytest

from synthgen import run as runner
from synthgen.outputs.kitti import parse_calib, parse_kitti
from synthgen.scene import assets

import OpenImageIO as oiio

from test_output_kitti import corners, project

#: Plausible (min, max) length, width (mirrors included), height in metres per class.
CLASS_SIZES = {
    "car": ((3.2, 5.3), (1.5, 2.1), (1.1, 1.9)),
    "van": ((3.3, 7.0), (1.6, 2.4), (1.8, 3.0)),  # from kei vans (3.4 m) to long-wheelbase ones
    "truck": ((5.0, 12.0), (2.0, 2.6), (2.2, 4.2)),
    "bus": ((8.0, 15.0), (2.3, 2.6), (2.8, 4.2)),
    "motorcycle": ((1.7, 2.6), (0.6, 1.0), (1.0, 1.6)),
}


def _vehicles():
    m = assets.load_manifest()
    return sorted(k for k, e in m.items() if e["kind"] == "mesh" and e.get("class") in CLASS_SIZES)


def _available(asset_id):
    e = assets.load_manifest()[asset_id]
    if e.get("optional"):
        cached = os.path.join(assets.cache_dir(), asset_id, os.path.basename(e["source"]["path"]))
        if not os.path.isfile(cached):
            pytest.skip(f"{asset_id} is optional and not in the cache (synthgen assets fetch {asset_id})")
    try:
        return assets.resolve(asset_id)
    except Exception as ex:  # noqa: BLE001 - no ../shared, no apt: nothing to test with
        pytest.skip(f"{asset_id} is not available: {ex}")


def test_the_library_has_cars_vans_and_motorcycles():
    classes = {assets.load_manifest()[k]["class"] for k in _vehicles()}
    assert {"car", "van", "motorcycle"} <= classes, classes


@pytest.mark.parametrize("asset_id", _vehicles())
def test_library_vehicle_box_and_size(tmp_path, asset_id):
    _available(asset_id)
    cls = assets.load_manifest()[asset_id]["class"]
    scen = tmp_path / "s.yaml"
    scen.write_text(f"""
seed: 2
resolution: [240, 180]
camera: {{fov_y: 45, pose: {{type: orbit, target: [0, 0.8, 0], distance: 14, elevation: 18,
  azimuth: {{choice: [20, 110, 200, 290]}}}}}}
lights: [{{type: environment, radiance: 1.0}}]
objects: [{{class: {cls}, asset: {asset_id}, yaw: {{uniform: [0, 360]}}}}]
placement: {{region: [-0.2, -0.2, 0.2, 0.2]}}
render: {{spp: 1, max_depth: 1}}
outputs: [instance, kitti, kitti_calib]
""")
    out = str(tmp_path / "ds")
    s = runner.run(str(scen), out, count=4, progress=False)
    assert not s["failures"], s.text()
    sizes = []
    for k in range(4):
        calib = parse_calib(open(os.path.join(out, "kitti_calib", f"{k:06d}.txt")).read())
        P2 = np.asarray(calib["P2"]).reshape(3, 4)
        ids = np.asarray(oiio.ImageBuf(os.path.join(out, "instance", f"{k:06d}.png")).get_pixels(oiio.UINT16))[..., 0]
        lab = parse_kitti(open(os.path.join(out, "kitti", f"{k:06d}.txt")).read())[0]
        pts, _, _ = corners(lab["dimensions"], lab["location"], lab["rotation_y"])
        uv = project(P2, pts)
        ys, xs = np.nonzero(ids == 1)
        assert len(ys) > 200, f"{asset_id}: only {len(ys)} pixels in view"
        # Encloses the mask: to the pixel (a label is the hit of a ray through the pixel), plus what
        # KITTI's two decimals take off the box (5 mm; a tenth of a pixel here).
        assert uv[:, 0].min() <= xs.min() + 1.2 and uv[:, 0].max() >= xs.max() - 0.2 and \
            uv[:, 1].min() <= ys.min() + 1.2 and uv[:, 1].max() >= ys.max() - 0.2, (asset_id, k, uv.min(0), uv.max(0),
                                                                             (xs.min(), ys.min(), xs.max(), ys.max()))
        box_area = np.ptp(uv[:, 0]) * np.ptp(uv[:, 1])
        mask_area = (np.ptp(xs) + 1) * (np.ptp(ys) + 1)
        assert box_area < 2.2 * mask_area, (asset_id, k, box_area, mask_area)
        sizes.append(lab["dimensions"])
        with open(os.path.join(out, "meta", f"{k:06d}.json")) as f:
            assert json.load(f)["objects"][0]["class"] == cls
    h, w, l = sizes[0]
    assert all(np.allclose(s_, sizes[0], atol=1e-3) for s_ in sizes)  # one model, one box
    print(f"\n{asset_id}: {cls}, length {l:.2f} m, width {w:.2f} m, height {h:.2f} m")
    (lo_l, hi_l), (lo_w, hi_w), (lo_h, hi_h) = CLASS_SIZES[cls]
    assert lo_l <= l <= hi_l and lo_w <= w <= hi_w and lo_h <= h <= hi_h, \
        f"{asset_id}: {l:.2f} x {w:.2f} x {h:.2f} m (l x w x h) is not a plausible {cls}"
