"""Objects inserted into real photos (scenario ``background``): the photo's camera and ground,
its light, the composite, its real labels and occluders, photos used in turn, and runs that
record which photos they used. The "photo" here is a render of the same world without the
objects, so the answers are known."""
from __future__ import annotations

import json
import os

import numpy as np
import OpenImageIO as oiio
import pytest

import synthgen as sg
from synthgen import primitives as P
from synthgen.background.calibration import Calibration
from synthgen.cli import main

W, H = 192, 128
CAL = dict(width=W, height=H, fx=170.0, fy=170.0, cx=96.0, cy=60.0, camera_height=1.6, pitch=6.0, roll=0.0)
SUN = (230.0, 35.0)


def _write_exr(path, rgb):
    spec = oiio.ImageSpec(rgb.shape[1], rgb.shape[0], 3, oiio.FLOAT)
    b = oiio.ImageBuf(spec)
    b.set_pixels(oiio.ROI(), np.ascontiguousarray(rgb, np.float32))
    assert b.write(path)


def _photo(path, seed=0):
    """A converged render of the empty world: ground (albedo 0.15) under the scenario's sky."""
    s = sg.Scene()
    g = P.ground()
    s.add_instance(s.add_mesh(g["positions"], g["indices"], g["normals"], g["uvs"]), np.eye(4, dtype=np.float32),
                   material_id=s.add_material("diffuse", {"albedo": 0.15}))
    s.add_light("sky", {"elevation": SUN[1], "azimuth": SUN[0], "strength": 0.02})
    s.set_camera(Calibration(**CAL).camera())
    rgb = np.array(s.render(spp=256, seed=seed).rgb)
    _write_exr(path, rgb)
    return rgb


CALIBRATION = f"""intrinsics: {{fx: {CAL['fx']}, cx: {CAL['cx']}, cy: {CAL['cy']}}}
ground: {{camera_height: {CAL['camera_height']}, pitch: {CAL['pitch']}}}
sun: {{azimuth: {SUN[0]}, elevation: {SUN[1]}}}
"""


def _scenario(tmp_path, photos="photos", count=4, extra="", objects=None):
    p = tmp_path / "aug.yaml"
    p.write_text(f"""seed: 5
count: {count}
resolution: [{W}, {H}]
background:
  photos: [{photos}]
  ground_albedo: 0.15
{extra}
objects:
  - class: box
    primitive: box
    size: [1.6, 1.2, 1.6]
    material: {{type: diffuse, albedo: [0.7, 0.1, 0.1]}}
    count: {objects or 1}
render: {{spp: 16}}
""")
    return str(p)


@pytest.fixture(scope="module")
def photo_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("aug") / "photos"
    d.mkdir()
    rgb = _photo(str(d / "street.exr"))
    (d / "calibration.yaml").write_text(CALIBRATION +
                                        "objects:\n  - {class: box, box: [10, 70, 40, 100]}\n"
                                        "ignore:\n  - {box: [150, 64, 190, 80]}\n")
    return d, rgb


def test_the_composite_is_the_photo_where_the_objects_change_nothing(photo_dir, tmp_path):
    d, photo = photo_dir
    os.symlink(d, tmp_path / "photos")
    sc = sg.Scenario(_scenario(tmp_path))
    for f in sc.frames(0, 2):
        bg = f.meta["background"]
        # The light matches the photo's (the same sky): the exposure factor is 1.
        assert bg["exposure"]["factor"] == pytest.approx(1.0, abs=0.06), bg["exposure"]
        assert bg["lighting"].startswith("sky with the photo's sun")
        objs = f.objects
        assert objs, "an object was inserted"
        same = np.all(f.rgb == photo, axis=2)
        assert same.mean() > 0.4, same.mean()
        # Where the composite differs, it is near the object (its pixels, shadow, light it sends).
        x, y, w, h = objs[0]["bbox"]
        ys, xs = np.nonzero(~same)
        far = (np.abs(xs - (x + w / 2)) > 3 * w) | (np.abs(ys - (y + h / 2)) > 3 * h)
        if far.any():
            assert np.abs(f.rgb[ys[far], xs[far]] - photo[ys[far], xs[far]]).max() < 0.05 * photo.max()
        # The object is drawn: its pixels differ from the photo.
        m = f.mask(objs[0]["instance_id"])
        assert np.abs(f.rgb[m] - photo[m]).mean() > 0.02
        # Labels: only the inserted object in the masks; the ground is never labelled.
        assert set(np.unique(f.instance_id)) <= {0, objs[0]["instance_id"]}
        assert np.all(np.isinf(f.depth[f.instance_id == 0]))


def test_real_labels_go_to_every_format(photo_dir, tmp_path):
    d, _ = photo_dir
    os.symlink(d, tmp_path / "photos")
    out = str(tmp_path / "out")
    assert main(["run", _scenario(tmp_path, count=2), "-o", out, "--no-progress"]) == 0
    assert main(["verify", out]) == 0
    coco = json.load(open(os.path.join(out, "annotations", "coco.json")))
    coco_val = os.path.join(out, "annotations", "coco_val.json")
    anns = coco["annotations"] + (json.load(open(coco_val))["annotations"] if os.path.exists(coco_val) else [])
    real = [a for a in anns if a["source"] == "real"]
    assert {(tuple(a["bbox"]), a["iscrowd"]) for a in real} == {((10.0, 70.0, 30.0, 30.0), 0),
                                                                ((150.0, 64.0, 40.0, 16.0), 1)}
    assert all(a["source"] == "synthetic" for a in anns if a not in real)
    kitti = open(os.path.join(out, "kitti", "000000.txt")).read().splitlines()
    assert kitti[-1].startswith("DontCare") and kitti[-2].startswith("box ")
    yolo = open(os.path.join(out, "labels", "000000.txt")).read().splitlines()
    assert len(yolo) == len(kitti) - 1  # YOLO has no ignore regions
    meta = json.load(open(os.path.join(out, "meta", "000000.json")))
    assert meta["background"]["sha256"] and f"photo:{meta['background']['sha256']}" in meta["split_keys"]
    data = sg.read_dataset(out)[0]
    assert len(data.boxes_xyxy) == len(data.objects) + 1 and data.target_masks().shape[0] == len(data.boxes_xyxy)


def test_a_real_occluder_hides_the_objects_behind_it(photo_dir, tmp_path):
    d, _ = photo_dir
    p = tmp_path / "photos"
    p.mkdir()
    os.symlink(d / "street.exr", p / "street.exr")
    mask = np.zeros((H, W, 3), np.float32)
    mask[:, : W // 2] = 1.0  # a wall over the left half
    _write_exr(str(tmp_path / "wall.exr"), mask)  # not in the photos' folder: it would be a photo
    (p / "street.exr.yaml").write_text(CALIBRATION +
                                       "objects: []\noccluders: ../wall.exr\n")
    sc = sg.Scenario(_scenario(tmp_path, objects=3))
    for f in sc.frames(0, 3):
        assert not f.instance_id[:, : W // 2].any()
        assert np.array_equal(f.rgb[:, : W // 2], sc_photo(d)[:, : W // 2])
        for o in f.meta["objects"]:
            assert "dropped" in o or o["bbox"][0] >= W // 2


@pytest.mark.parametrize("outline", ["box", "polygon"])
def test_nothing_stands_behind_a_real_object_known_by_its_box_alone(photo_dir, tmp_path, outline):
    """A box label would hide what stands behind it by its whole rectangle (background corners
    included: a rectangular notch in the object), so placement puts nothing behind one; the same
    object outlined by a polygon hides exactly, and objects do go behind it (the control: the
    test can fail)."""
    d, _ = photo_dir
    p = tmp_path / "photos"
    p.mkdir()
    os.symlink(d / "street.exr", p / "street.exr")
    x0, y0, x1, y1 = 40, 62, 150, 112  # a wide real object in the middle of the ground
    label = (f"box: [{x0}, {y0}, {x1}, {y1}]" if outline == "box" else
             f"polygon: [[{x0}, {y0}], [{x1}, {y0}], [{x1}, {y1}], [{x0}, {y1}]]")
    (p / "street.exr.yaml").write_text(CALIBRATION + f"objects:\n  - {{class: box, {label}}}\n")
    sc = sg.Scenario(_scenario(tmp_path, count=6, objects=4, extra="  max_real_overlap: 0.9"))
    occluded = placed = 0
    for f in sc.frames():
        occ = f.meta["background"]["real_occlusion"]
        occluded += occ["pixels"]
        for o in f.meta["objects"]:
            if "dropped" in o:
                continue
            placed += 1
            bx, by, bw, bh = o["bbox"]
            overlaps = bx < x1 and bx + bw > x0 and by < y1 and by + bh > y0
            if outline == "box" and overlaps:
                assert by + bh >= y1 - 1, f"an object stands behind the box label: {o['bbox']}"
    assert placed >= 8
    if outline == "box":
        assert occluded == 0
    else:
        assert occluded > 0


def sc_photo(d):
    return sg.read_image(str(d / "street.exr"))


def test_photos_are_used_in_turn_and_capped(photo_dir, tmp_path):
    d, _ = photo_dir
    p = tmp_path / "photos"
    p.mkdir()
    for name in ("a.exr", "b.exr", "c.exr"):
        os.symlink(d / "street.exr", p / name)
    (p / "calibration.yaml").write_text(CALIBRATION + "objects: []\n")
    sc = sg.Scenario(_scenario(tmp_path, count=6))
    used = [os.path.basename(f.meta["background"]["path"]) for f in sc.frames()]
    assert sorted(used[:3]) == ["a.exr", "b.exr", "c.exr"] and sorted(used[3:]) == ["a.exr", "b.exr", "c.exr"]
    with pytest.raises(sg.SynthgenError, match="max_uses 1"):
        sg.Scenario(_scenario(tmp_path, count=6, extra="  max_uses: 1"))


def test_unlabelled_photos_are_refused_unless_allowed(photo_dir, tmp_path):
    d, _ = photo_dir
    p = tmp_path / "photos"
    p.mkdir()
    os.symlink(d / "street.exr", p / "street.exr")
    (p / "street.exr.yaml").write_text(CALIBRATION)
    with pytest.raises(sg.SynthgenError, match="declares no real labels"):
        sg.Scenario(_scenario(tmp_path))
    sg.Scenario(_scenario(tmp_path, extra="  unlabelled_ok: true"))


def test_resume_refuses_when_a_photo_was_added(photo_dir, tmp_path, capsys):
    d, _ = photo_dir
    p = tmp_path / "photos"
    p.mkdir()
    os.symlink(d / "street.exr", p / "a.exr")
    (p / "calibration.yaml").write_text(CALIBRATION + "objects: []\n")
    out = str(tmp_path / "out")
    scen = _scenario(tmp_path, count=2)
    assert main(["run", scen, "-o", out, "-n", "1", "--no-progress"]) == 0
    os.symlink(d / "street.exr", p / "b.exr")
    assert main(["run", scen, "-o", out, "--resume", "--no-progress"]) == 2
    assert "b.exr" in capsys.readouterr().err


@pytest.mark.parametrize("sun, lighting", [
    ("sun: {overcast: true}\n", "overcast"),
    ("", "the scenario's lights (fallback"),
    ("sun:\n  shadow: {base: [100, 100], tip: [60, 110], height: 2.0}\n", "sky with the photo's sun (marked shadow)"),
])
def test_the_light_follows_what_the_photo_says(photo_dir, tmp_path, sun, lighting):
    d, _ = photo_dir
    p = tmp_path / "photos"
    p.mkdir()
    os.symlink(d / "street.exr", p / "street.exr")
    cal = CALIBRATION.replace(f"sun: {{azimuth: {SUN[0]}, elevation: {SUN[1]}}}\n", sun) + "objects: []\n"
    (p / "street.exr.yaml").write_text(cal)
    f = next(sg.Scenario(_scenario(tmp_path, count=1)).frames())
    assert f.meta["background"]["lighting"].startswith(lighting)
    assert bool(f.meta["background"].get("lighting_fallback")) == ("fallback" in lighting)
    if "shadow" in sun:
        assert f.meta["lights"][0]["type"] == "sky"
        assert 0 < f.meta["background"]["sun"]["elevation"] < 90


def test_a_photos_hdr_is_turned_so_its_sun_matches_the_photos(tmp_path):
    """envmap without a rotation, sun given: the map's brightest pixel lands at the sun's azimuth
    (seen by a camera looking there, the sun is in the middle of the image)."""
    from synthgen.frame.photo import envmap_rotation_to

    path = str(tmp_path / "env.exr")
    img = np.full((64, 128, 3), 0.2, np.float32)
    img[20:23, 30:33] = 500.0  # the sun at map azimuth 360 * 31.5 / 128
    _write_exr(path, img)
    for azimuth in (40.0, 200.0, 300.0):
        rot = envmap_rotation_to(path, azimuth)
        s = sg.Scene()
        b = P.box((0.1, 0.1, 0.1))
        s.add_instance(s.add_mesh(b["positions"], b["indices"]), P.translate([0.0, -50.0, 0.0]))
        s.add_light("envmap", {"file": path, "rotation": rot})
        el = np.radians(90.0 * (1 - 21.5 / 32))  # the sun's row: elevation above the horizon
        a = np.radians(azimuth)
        d = [np.cos(el) * np.sin(a), np.sin(el), -np.cos(el) * np.cos(a)]
        s.set_camera(sg.PinholeCamera.from_fov(20, 65, 65, sg.PinholeCamera.look_at([0, 0, 0], d)))
        rgb = np.asarray(s.render(spp=4, texture_filtering=False).rgb)
        ys, xs = np.nonzero(rgb.sum(axis=2) > 100.0)  # the sun's disc (3 x 3 texels: 8 degrees)
        assert len(ys) and abs(xs.mean() - 32.5) <= 1.5 and abs(ys.mean() - 32.5) <= 1.5, (azimuth, xs.mean(),
                                                                                            ys.mean())


def test_weather_with_photo_backgrounds_is_an_error_at_its_key(tmp_path, photo_dir):
    """Fog or haze over a photo is applied from the photo's depth map (test_weather_photo_fog.py):
    a photo without one is refused at the YAML key, before anything renders (docs/weather.md)."""
    from synthgen.scenario import check_inputs, load_scenario

    d, _ = photo_dir
    for kind in ("fog", "haze"):
        path = _scenario(tmp_path, photos=str(d), extra=f"weather: {{{kind}: {{visibility: 50}}}}")
        with pytest.raises(sg.SynthgenError, match=rf"aug\.yaml:\d+:\d+: weather\.{kind}: over a photo background "
                                                   r"it needs the photo's depth map"):
            check_inputs(load_scenario(path))



def test_the_white_balance_is_measured_on_the_placement_region(tmp_path):
    """The light's colour comes from the ground around the objects in the placement region
    only: the catcher's albedo stands for the region's ground, so grass around it (here: the
    photo's ground outside a band tinted green) must not turn the light green. With the region,
    the white balance is within 3 % of neutral (the photo's band is the render's own ground);
    the same photo without a region gets the grass's colour (G above R and B by more than 20 %)."""
    d = tmp_path / "photos"
    d.mkdir()
    rgb = _photo(str(tmp_path / "street.exr"))
    grass = rgb * np.array([0.5, 1.3, 0.4], np.float32)
    band = (70, 112)
    photo = grass.copy()
    photo[band[0]:band[1]] = rgb[band[0]:band[1]]
    _write_exr(str(d / "street.exr"), photo)
    wbs = {}
    for region in (True, False):
        (d / "calibration.yaml").write_text(
            CALIBRATION + "objects: []\n" +
            (f"region:\n  - [[0, {band[0]}], [{W}, {band[0]}], [{W}, {band[1]}], [0, {band[1]}]]\n" if region else ""))
        f = next(iter(sg.Scenario(_scenario(tmp_path)).frames(0, 1)))
        assert f.objects, "an object was inserted"
        assert f.meta["background"]["exposure"]["from"] == "ring around the objects"
        wbs[region] = np.array(f.meta["background"]["exposure"]["white_balance"])
    assert np.allclose(wbs[True], 1.0, atol=0.03), wbs
    assert wbs[False][1] > 1.2 * max(wbs[False][0], wbs[False][2]), wbs


def test_the_dome_of_a_distorted_photo_maps_no_nan(recwarn):
    """A barrel lens (the highway rig's k1 -0.223, k2 0.045) folds beyond the photo's corners:
    the directions past the fold map to NaN or to coordinates beyond any integer. They lie
    outside the photo (the dome's top / bottom means there) and reach no integer cast (it
    warned twice per frame: 'invalid value encountered in cast'); the dome is bit-identical to
    the one before (checked once by hand on this photo)."""
    from synthgen.frame.photo import photo_dome
    cal = Calibration(width=676, height=380, fx=338.0, fy=338.0, cx=338.0, cy=190.0, camera_height=2.1,
                      pitch=2.54, roll=0.0, distortion=(-0.223, 0.045, 0, 0, 0))
    photo = np.random.default_rng(0).random((380, 676, 3)).astype(np.float32)
    dome = photo_dome(photo, cal, width=128)
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]
    assert np.isfinite(dome).all()
    top = photo[:380 // 7].reshape(-1, 3).mean(axis=0)
    bottom = photo[-(380 // 5):].reshape(-1, 3).mean(axis=0)
    # behind the camera (the dome's seam, u = 0) nothing of the photo: the means
    assert np.allclose(dome[0, 0], top) and np.allclose(dome[-1, 0], bottom)
