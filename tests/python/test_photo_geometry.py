"""Nonsense photo geometry is caught before a run drops every object (issue 33.8): a horizon below
the image, a camera 500 m up, a placement region above the horizon, outside the photo or too
small for the objects are errors of `synthgen validate` (and of `synthgen run` before its first
frame) and of `synthgen calibrate`, at the calibration file's key with the numbers; a steep
camera and an implausible camera height are warnings. And calibrate's size check of a labelled
car compares its box with a car turned along the road (its length seen from the side)."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

import synthgen as sg
from synthgen import SceneFileError, cli
from synthgen import primitives as P
from synthgen import run as runner
from synthgen.background.calibration import Calibration
from synthgen.background.labels import RealObject
from synthgen.background.preview import label_checks
from synthgen.background.sidecar import PhotoSetup, read_photo_setup
from synthgen.outputs.files import write_srgb_png
from synthgen.scenario import check_inputs, load_scenario

#: A 200 x 100 photo seen through fx = fy = 100 (a 90 degree horizontal field of view), its principal
#: point at the centre; a camera 1.5 m up whose horizon is row 40 (pitch atan(10 / 100) down).
SANE = """intrinsics: {fx: 100, fy: 100, cx: 100, cy: 50}
ground: {camera_height: HEIGHT, horizon: HORIZON}
REGION
objects: []
"""


def _setup(tmp_path, height=1.5, horizon=40, region=""):
    write_srgb_png(str(tmp_path / "p.png"), np.full((100, 200, 3), 0.5, np.float32))
    (tmp_path / "cal.yaml").write_text(SANE.replace("HEIGHT", str(height)).replace("HORIZON", str(horizon))
                                       .replace("REGION", region))
    return read_photo_setup(str(tmp_path / "p.png"), 200, 100, shared=str(tmp_path / "cal.yaml"))


CAR = [("a car", 4.5, 1.8)]


def _findings(tmp_path, **kw):
    from synthgen.background.geometry import geometry_findings

    return geometry_findings(_setup(tmp_path, **kw), 4.0, 45.0, CAR)


def test_a_sane_photo_has_no_findings(tmp_path):
    assert _findings(tmp_path) == []


def test_a_horizon_below_the_image_is_an_error(tmp_path):
    (f,) = _findings(tmp_path, horizon=5100)
    assert f.error and (f.key, f.line) == ("ground.horizon", 2) and f.file.endswith("cal.yaml")
    assert "the horizon lies 5000 px below the image (row 5100 of a photo 100 px high)" in f.message
    assert "shows no ground" in f.message


def test_a_horizon_far_above_the_image_is_a_warning(tmp_path):
    # Row -150: the camera looks atan(200 / 100) = 63.4 degrees down; 10 m up, the ground in view
    # reaches 10 m / tan(63.4 - atan(50 / 100) degrees) = 13.3 m, within the distances.
    (f,) = _findings(tmp_path, height=10, horizon=-150)
    assert not f.error and f.key == "ground.horizon" and "150 px above the image" in f.message, str(f)
    assert f"pitch {math.degrees(math.atan(2.0)):.1f} deg" in f.message


def test_a_camera_500_m_up_sees_no_ground_within_the_distances(tmp_path):
    warn, err = _findings(tmp_path, height=500)
    assert not warn.error and warn.key == "ground.camera_height" and "500 m above the ground" in warn.message
    assert err.error and "none of it within background.min_distance .. max_distance (4 .. 45 m)" in err.message
    # The nearest ground in view is under the image's bottom row: 500 m / tan(pitch + atan(50 / 100)).
    nearest = 500.0 / math.tan(math.atan(0.1) + math.atan(0.5))
    got = float(re.search(r"lies ([\d.]+) to", err.message).group(1))
    assert got == pytest.approx(nearest, rel=0.02), err.message


def test_a_region_above_the_horizon_or_outside_the_photo_is_an_error(tmp_path):
    (f,) = _findings(tmp_path, region="region: [[[0, 5], [200, 5], [200, 30], [0, 30]]]")
    assert f.error and (f.key, f.line) == ("region", 3)
    assert "the placement region (rows 5 to 30) lies entirely above the horizon (row 40)" in f.message, str(f)
    (f,) = _findings(tmp_path, region="region: [[[300, 60], [400, 60], [400, 90], [300, 90]]]")
    assert f.error and "lies outside the photo (200 x 100)" in f.message, str(f)


def test_a_region_too_small_for_the_object_is_an_error_inside_the_image_a_warning_at_its_border(tmp_path):
    (f,) = _findings(tmp_path, region="region: [[[90, 60], [110, 60], [110, 62], [90, 62]]]")
    assert f.error and f.key == "region" and "less than the footprint of a car (4.50 x 1.80 m = 8.1 m^2)" in f.message
    assert "it cannot stand there" in f.message, str(f)
    # The same strip reaching the image's left border: objects sticking out of the image may stand there.
    (f,) = _findings(tmp_path, region="region: [[[0, 60], [8, 60], [8, 62], [0, 62]]]")
    assert not f.error and "only objects sticking out of the image" in f.message, str(f)
    # The control: a region of the road ahead holds the car.
    assert _findings(tmp_path, region="region: [[[0, 60], [200, 60], [200, 100], [0, 100]]]") == []


def _scenario(tmp_path, cal_text, obj="{class: car, primitive: box, size: [4.5, 1.5, 1.8]}"):
    (tmp_path / "cal.yaml").write_text(cal_text)
    write_srgb_png(str(tmp_path / "p.png"), np.full((100, 200, 3), 0.5, np.float32))
    p = tmp_path / "s.yaml"
    p.write_text("""
seed: 1
resolution: [100, 50]
background:
  photos: [{file: p.png, calibration: cal.yaml}]
  min_distance: 4
  max_distance: 45
objects: [OBJ]
placement: {allow_drops: true}
render: {spp: 1, max_depth: 1}
outputs: [rgb]
""".replace("OBJ", obj))
    return str(p)


def test_validate_and_run_refuse_a_photo_where_nothing_can_stand(tmp_path, capsys):
    path = _scenario(tmp_path, SANE.replace("HEIGHT", "500").replace("HORIZON", "40").replace("REGION", ""))
    with pytest.raises(SceneFileError) as e:
        check_inputs(load_scenario(path))
    assert e.value.source.endswith("cal.yaml") and e.value.key_path == "ground.horizon", str(e.value)
    assert "(camera height 500 m), none of it within background.min_distance .. max_distance (4 .. 45 m)" \
        in str(e.value) and "(photo p.png)" in str(e.value)
    with pytest.raises(SceneFileError):
        runner.run(path, str(tmp_path / "ds"), count=1, progress=False)
    assert cli.main(["validate", path]) == 2
    assert "nothing can be placed" in capsys.readouterr().err


def test_validate_warns_of_a_suspicious_camera_and_passes(tmp_path, capsys):
    # 35 m up, looking 47.7 degrees down (horizon row -60): its ground in view lies 9.8 to 90 m away.
    path = _scenario(tmp_path, SANE.replace("HEIGHT", "35").replace("HORIZON", "-60").replace("REGION", ""))
    warnings = []
    check_inputs(load_scenario(path), warnings)
    assert len(warnings) == 1 and "ground.camera_height: the camera stands 35 m above the ground" in warnings[0]
    assert cli.main(["validate", path]) == 0
    assert "warning: " in capsys.readouterr().err


def test_calibrate_refuses_nonsense_geometry(tmp_path, capsys):
    _setup(tmp_path, horizon=5100)
    assert cli.main(["calibrate", str(tmp_path / "p.png"), "--calibration", str(tmp_path / "cal.yaml"),
                     "-o", str(tmp_path / "prev.png")]) == 2
    assert "error: " in capsys.readouterr().err
    # Without a scenario, distances are calibrate's defaults (3 .. 40 m): nothing in range is a warning.
    _setup(tmp_path, height=500)
    assert cli.main(["calibrate", str(tmp_path / "p.png"), "--calibration", str(tmp_path / "cal.yaml"),
                     "-o", str(tmp_path / "prev.png")]) == 0
    err = capsys.readouterr().err
    assert "warning: " in err and "max_distance's defaults (3 .. 40 m)" in err and "error: " not in err, err
    _setup(tmp_path)
    assert cli.main(["calibrate", str(tmp_path / "p.png"), "--calibration", str(tmp_path / "cal.yaml"),
                     "-o", str(tmp_path / "prev.png")]) == 0
    assert "warning: " not in capsys.readouterr().err


def _rendered_car_box(cal, length, width, centre):
    """The image box (pixels) of a rendered car-sized box (length along world x, standing on the
    ground at ``centre``)."""
    s = sg.Scene()
    b = P.box((length, 1.5, width))
    s.add_instance(s.add_mesh(b["positions"], b["indices"]),
                   P.translate([centre[0], 0.75, centre[1]]).astype(np.float32), class_id=1)
    s.set_camera(cal.camera())
    ys, xs = np.nonzero(np.asarray(s.render(spp=1, labels_only=True).instance_id))
    return [float(xs.min()), float(ys.min()), float(xs.max() + 1), float(ys.max() + 1)]


def test_a_car_seen_from_the_side_is_measured_by_its_length():
    """A side-facing camera (road_direction 90: the road runs across the image, along world x) sees
    a 4.5 m car's side: its box is as wide as a car turned along the road (checked against a
    render), plausible; the same box under a road running away from the camera (a rear view,
    what the check assumed before) is too wide for any car's width."""
    from synthgen.background.preview import CAR_WIDTH, car_box_width

    cal = Calibration(width=640, height=360, fx=320.0, fy=320.0, cx=320.0, cy=180.0, camera_height=1.45, pitch=2.0)
    for centre in ([1.0, 12.0], [-6.0, 10.0]):
        box = _rendered_car_box(cal, 4.5, 1.8, centre)
        assert car_box_width(cal, box, 90.0, 4.5, 1.8) == pytest.approx(box[2] - box[0], rel=0.02, abs=1.0)
        side = label_checks(PhotoSetup("x", cal, road_direction=90.0, objects=[RealObject("car", box)]))[0]
        assert side["plausible"], side
        lo, hi = side["expected"]
        assert lo < box[2] - box[0] < hi
        # Not 1.5 to 2.1 m wide as seen from behind: the old check flagged every such car.
        assert side["width"] > CAR_WIDTH[1], side
    rear = label_checks(PhotoSetup("x", cal, road_direction=0.0,
                                   objects=[RealObject("car", _rendered_car_box(cal, 4.5, 1.8, [1.0, 12.0]))]))[0]
    assert not rear["plausible"], rear


def test_the_smallest_object_an_entry_can_draw_is_what_must_fit(tmp_path):
    """A region 7.4 to 10 m ahead, about 1.4 m across (3.5 m^2 of ground): a 4.5 x 1.8 m box cannot
    stand there; scaled by 0.6 to 1 (2.7 x 1.08 m at the smallest) it can."""
    cal = SANE.replace("HEIGHT", "1.5").replace("HORIZON", "40").replace(
        "REGION", "region: [[[92, 55], [108, 55], [108, 60], [92, 60]]]")
    with pytest.raises(SceneFileError) as e:
        check_inputs(load_scenario(_scenario(tmp_path, cal)))
    assert e.value.key_path == "region" and "less than the footprint of objects[0] (a box) (4.50 x 1.80 m" \
        in str(e.value), str(e.value)
    check_inputs(load_scenario(_scenario(tmp_path, cal, "{class: car, primitive: box, size: [4.5, 1.5, 1.8], "
                                                        "scale: {uniform: [0.6, 1.0]}}")))
