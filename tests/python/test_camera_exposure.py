"""The camera's exposure of synthetic frames (scenario ``camera.exposure``, format version 2;
synthgen.frame.exposure, synthgen.post.exposure): the metering on analytic images (a uniform
grey lands on the key, a small sun barely moves it, a bright sky is kept below white), a
physical sky with a yellow car (blown out to white as rendered) exposed with the car's colour
kept, version 1 frames left as rendered, the factor in meta and the image exactly the render
times it, ev and factor, dusk/night keeping their own (dark) exposure, replayed journals
applying it, and the format's errors naming the key."""
from __future__ import annotations

import colorsys
import json
import os

import numpy as np
import OpenImageIO as oiio
import pytest

from synthgen import SceneFileError
from synthgen import scenario as S
from synthgen.frame import FrameRenderer
from synthgen.post import exposure as E
from synthgen.scenario import parse_scenario
from synthgen.schema.yaml_io import parse_yaml

Y = np.array([0.2126, 0.7152, 0.0722])

# A sky at physical scale (no strength: luminance / 683, a clear day's sky ~ 5-15 units)
# over a yellow car-sized box.
SKY_CAR = """
version: {version}
seed: 7
resolution: [48, 32]
camera:
  fov_y: 40
  pose: {{type: orbit, target: [0, 0.6, 0], distance: 6, elevation: 12, azimuth: 30}}
  {exposure}
lights: [{{type: sky, elevation: 40, azimuth: 120, turbidity: 3}}]
objects:
  - {{class: car, primitive: box, size: [2.0, 1.2, 1.6], material: {{type: coated, albedo: [0.8, 0.6, 0.05],
      roughness: 0.1}}}}
placement: {{region: [-0.2, -0.2, 0.2, 0.2]}}
render: {{spp: 8, max_depth: 4}}
{extra}
"""


def _scenario(version=2, exposure="", extra=""):
    text = SKY_CAR.format(version=version, exposure=exposure, extra=extra)
    return parse_scenario(parse_yaml(text), "s.yaml", os.getcwd(), text)


def _render(version=2, exposure="", extra="", frame=0):
    return FrameRenderer(_scenario(version, exposure, extra)).render(frame)


# -- metering on analytic images --------------------------------------------------------------

@pytest.mark.parametrize("grey", [1e-3, 0.18, 0.5, 7.0, 2500.0])
def test_a_uniform_grey_is_exposed_to_the_key(grey):
    rgb = np.full((30, 40, 3), grey, np.float32)
    a = E.auto_factor(rgb)
    assert a["factor"] * float(np.float32(grey)) == pytest.approx(E.KEY, rel=1e-12)
    assert not a["highlight_limited"]
    # ev is exposure compensation in stops on top of the metered factor.
    assert E.auto_factor(rgb, ev=1.5)["factor"] == pytest.approx(a["factor"] * 2.0 ** 1.5, rel=1e-12)
    assert E.auto_factor(rgb, key=0.09)["factor"] == pytest.approx(a["factor"] / 2.0, rel=1e-12)


def test_a_small_sun_barely_moves_the_metering():
    """0.1% of the pixels a million times brighter (the sun's disc) change the exposure by
    less than 1%; an unclipped log-average would move by 2^(0.001 log2 1e6) - 1 ~ 1.4%,
    the plain mean by a factor of 1000."""
    rng = np.random.default_rng(1)
    rgb = (0.3 + 0.2 * rng.random((100, 100, 3))).astype(np.float32)
    sun = rgb.copy()
    sun[50, 40:50] = 1e6
    a, b = E.auto_factor(rgb)["factor"], E.auto_factor(sun)["factor"]
    assert abs(b / a - 1.0) < 0.01, (a, b)


def test_a_bright_sky_over_a_quarter_of_the_frame_is_kept_below_white():
    """Highlight protection: a sky 40x brighter than the ground over the top 30% of the frame
    would be mapped far past white by the log-average alone; at most 3% of pixels clip."""
    rgb = np.full((100, 100, 3), 0.05, np.float32)
    rgb[:30] = 2.0
    a = E.auto_factor(rgb)
    y = (rgb.astype(np.float64) @ Y) * a["factor"]
    assert a["highlight_limited"] and (y > 1.0 + 1e-9).mean() <= 0.03
    assert y.max() == pytest.approx(1.0, rel=1e-9)


def test_a_black_frame_keeps_its_factor_finite():
    a = E.auto_factor(np.zeros((8, 8, 3), np.float32), ev=-1.0)
    assert a["factor"] == 0.5 and a["metered"] == 0.0
    nan = np.full((8, 8, 3), np.nan, np.float32)
    assert np.isfinite(E.auto_factor(nan)["factor"])


def test_metering_is_centre_weighted_and_deterministic():
    """The same bright patch meters brighter in the centre than in a corner; the same image
    gives the same figures bit for bit."""
    centre = np.full((40, 60, 3), 0.1, np.float32)
    corner = centre.copy()
    centre[15:25, 25:35] = 1.0
    corner[:10, :10] = 1.0
    assert E.meter(centre)["log_average"] > E.meter(corner)["log_average"]
    assert E.meter(centre) == E.meter(centre.copy())


# -- frames -------------------------------------------------------------------------------------

def _car_pixels(arrays):
    return np.asarray(arrays["rgb"], np.float64)[np.asarray(arrays["instance_id"]) == 1]


def test_a_physical_sky_is_exposed_and_the_yellow_car_keeps_its_colour():
    """Version 1 renders a physical sky as it is: the car's pixels past white (this is the
    bug). Version 2 meters: no car pixel clips, the car is yellow (hue within 15 degrees of its
    paint's, R > G > B), and the frame is neither black nor white."""
    old, meta_old, _ = _render(version=1)
    assert (_car_pixels(old) >= 1.0).any(axis=1).mean() > 0.5
    assert meta_old["exposure"]["mode"] == "fixed" and meta_old["exposure"]["factor"] == 1.0
    new, meta, _ = _render(version=2)
    e = meta["exposure"]
    assert e["mode"] == "auto" and 0.0 < e["factor"] < 0.1 and e["metered"] > 1.0, e
    car = _car_pixels(new)
    assert car.size and (car < 1.0).all(), car.max()
    mean = car.mean(axis=0)
    assert mean[0] > mean[1] > mean[2]
    hue = colorsys.rgb_to_hsv(*mean)[0] * 360.0
    paint = colorsys.rgb_to_hsv(0.8, 0.6, 0.05)[0] * 360.0
    assert abs(hue - paint) < 15.0, (hue, paint)
    y = np.asarray(new["rgb"], np.float64) @ Y
    assert 0.05 < float(np.median(y)) < 0.6


def test_the_image_is_the_render_times_the_recorded_factor():
    """Auto-exposure's pre-pass changes nothing of the render: the frame equals the same
    frame with that factor given as a fixed exposure, bit for bit, labels included; ev: 1
    doubles the factor; a version 1 frame is fixed at 1 unless it says otherwise."""
    auto, meta, _ = _render()
    f = meta["exposure"]["factor"]
    assert meta["exposure"]["total"] == f
    fixed, meta_fixed, _ = _render(exposure=f"exposure: {{mode: fixed, factor: {f!r}}}")
    assert meta_fixed["exposure"] == {"mode": "fixed", "factor": f, "ev": 0.0, "total": f}
    for k in ("rgb", "depth", "instance_id", "class_id", "normal", "albedo"):
        assert np.array_equal(np.asarray(auto[k]), np.asarray(fixed[k]), equal_nan=True), k
    brighter, meta_ev, _ = _render(exposure="exposure: {ev: 1}")
    assert meta_ev["exposure"]["factor"] == pytest.approx(2.0 * f, rel=1e-12)
    assert meta_ev["exposure"]["metered"] == meta["exposure"]["metered"]
    raw, _, _ = _render(version=1)
    assert np.array_equal(np.asarray(fixed["rgb"]), (np.asarray(raw["rgb"]) * np.float32(f)).astype(np.float32))
    v1_auto, meta_v1, _ = _render(version=1, exposure="exposure: {mode: auto}")
    assert meta_v1["exposure"]["factor"] == f


def test_an_auto_exposed_frame_does_not_depend_on_what_its_worker_rendered_before():
    """Frame 1 rendered after frames 0 and 2 by the same renderer (pre-passes included) is frame
    1 rendered alone, bit for bit, its metering too."""
    fr = FrameRenderer(_scenario(exposure="exposure: {ev: {uniform: [-1, 1]}}"))
    fr.render(0)
    fr.render(2)
    a, meta_a, _ = fr.render(1)
    b, meta_b, _ = FrameRenderer(_scenario(exposure="exposure: {ev: {uniform: [-1, 1]}}")).render(1)
    assert meta_a["exposure"] == meta_b["exposure"]
    for k in ("rgb", "depth", "instance_id"):
        assert np.array_equal(np.asarray(a[k]), np.asarray(b[k]), equal_nan=True), k


def test_a_randomized_exposure_draws_from_its_own_stream():
    """ev as a distribution: recorded under camera.exposure.ev, and every other draw is the
    frame's draw without it."""
    _, a, _ = _render(exposure="exposure: {mode: fixed, ev: {uniform: [-1, 1]}}", frame=2)
    _, b, _ = _render(exposure="exposure: {mode: fixed}", frame=2)
    ev = a["sampled"]["camera.exposure.ev"]
    assert -1.0 <= ev <= 1.0 and a["exposure"]["factor"] == pytest.approx(2.0 ** ev, rel=1e-12)
    assert {k: v for k, v in a["sampled"].items() if not k.startswith("camera.exposure")} == b["sampled"]


def _log_average(rgb):
    y = np.asarray(rgb, np.float64) @ Y
    return float(np.exp(np.mean(np.log(np.maximum(y, 1e-4)))))


NIGHT = ("weather: {night: {elevation: -30, sky_glow: 0.01, moon: {probability: 0}, "
         "street_lights: {spacing: 12, offset: 5, poles: false}}}")


DUSK = "weather: {dusk: {elevation: -4, street_lights: {spacing: 12, offset: 5, poles: false}}}"


@pytest.mark.parametrize("key, weather", [("night", NIGHT), ("dusk", DUSK)])
def test_dusk_and_night_keep_their_own_dark_exposure(key, weather):
    """A dusk or night scene is metered by its condition (whose lower key keeps it dark): in
    version 2 its image is version 1's bit for bit, meta says who metered, it is darker than
    the day, and ev still compensates."""
    v1, m1, _ = _render(version=1, extra=weather)
    v2, m2, _ = _render(version=2, extra=weather)
    assert m2["exposure"] == {"mode": "auto", "factor": 1.0, "ev": 0.0, "metered_by": f"weather.{key}",
                              "total": m1["exposure"]["total"]}
    assert np.array_equal(np.asarray(v1["rgb"]), np.asarray(v2["rgb"]))
    day, _, _ = _render(version=2)
    night_key, day_key = _log_average(v2["rgb"]), _log_average(day["rgb"])
    print(f"\nlog-average luminance: {key} {night_key:.4f}, day {day_key:.4f}")
    assert night_key < 0.6 * day_key  # their keys: night 0.05, dusk 0.1; the day 0.18
    v3, m3, _ = _render(version=2, exposure="exposure: {ev: 1}", extra=weather)
    assert m3["exposure"]["factor"] == 2.0
    assert np.array_equal(np.asarray(v3["rgb"]), (np.asarray(v1["rgb"]) * np.float32(2.0)).astype(np.float32))


def test_a_replayed_journal_applies_the_frames_exposure(tmp_path):
    """`synthgen replay` of a version 2 frame's journal writes the frame's image (the render
    times the recorded exposure), not the blown-out render."""
    from synthgen import run as runner
    from synthgen.cli import main

    src = tmp_path / "s.yaml"
    src.write_text(SKY_CAR.format(version=2, exposure="", extra="outputs: [rgb_exr, instance]"))
    out = tmp_path / "ds"
    s = runner.run(str(src), str(out), count=1, progress=False, journal=True)
    assert s["rendered"] == 1 and not s["failures"], s.text()
    meta = json.load(open(out / "meta" / "000000.json"))
    assert main(["replay", str(out / "journals" / "000000.journal"), "-o", str(tmp_path / "r")]) == 0
    frame = oiio.ImageBuf(str(out / "images" / "000000.exr")).get_pixels(oiio.FLOAT)[..., :3]
    replayed = oiio.ImageBuf(str(tmp_path / "r" / "rgb.exr")).get_pixels(oiio.FLOAT)[..., :3]
    assert np.array_equal(frame, replayed)
    r = json.load(open(tmp_path / "r" / "meta.json"))
    assert r["exposure"]["factor"] == pytest.approx(meta["exposure"]["factor"], rel=1e-6)


# -- the format -----------------------------------------------------------------------------------

def _error(tmp_path, text):
    p = tmp_path / "s.yaml"
    p.write_text(text)
    with pytest.raises(SceneFileError) as ei:
        S.load_scenario(str(p))
    return ei.value


BASE = "version: {v}\nobjects: [{{class: a, primitive: box}}]\ncamera:\n  exposure: {e}\n"


@pytest.mark.parametrize("v, e, key, words", [
    (2, "{mode: auto, factor: 2}", "camera.exposure.factor", ["fixed factor with mode: auto"]),
    (2, "{factor: 2, key: 0.1}", "camera.exposure.key", ["key is auto-exposure's"]),
    (1, "{key: 0.1}", "camera.exposure.key", ["key is auto-exposure's"]),
    (2, "{mode: manual}", "camera.exposure.mode", ["auto, fixed"]),
    (2, "{ev: 30}", "camera.exposure.ev", ["out of range"]),
    (2, "{factor: 0}", "camera.exposure.factor", ["out of range"]),
    (3, "{}", "version", ["out of range", "[1, 2]"]),
])
def test_format_errors_name_the_key(tmp_path, v, e, key, words):
    err = _error(tmp_path, BASE.format(v=v, e=e))
    assert err.key_path == key, str(err)
    assert err.line is not None
    for w in words:
        assert w in str(err), str(err)


def test_photo_backgrounds_refuse_a_camera_exposure(tmp_path):
    text = ("version: 2\nobjects: [{class: a, primitive: box}]\ncamera:\n  exposure: {ev: 1}\n"
            "background: {photos: [p.jpg]}\n")
    err = _error(tmp_path, text)
    assert err.key_path == "camera.exposure" and "photo's own exposure" in str(err), str(err)


def test_version_2_is_the_default_of_nothing_else():
    """A scenario without version is version 1 (every scenario written before version 2)."""
    sc = parse_scenario(parse_yaml("objects: [{class: a, primitive: box}]\n"), "s.yaml", os.getcwd())
    assert sc.spec["version"] == 1 and S.sample_frame(sc, 0).camera.exposure["mode"] == "fixed"


def test_photo_frames_are_not_exposed_by_the_camera(tmp_path):
    """Objects inserted into a photo are matched to the photo's light and exposure: a version 2
    scenario's photo frame is version 1's bit for bit, meta says mode photo. (The "photo" is a
    render of the empty world, as in test_augmented_photo.py.)"""
    import synthgen as sg
    from synthgen import primitives as P
    from synthgen.background.calibration import Calibration

    w, h = 64, 48
    cal = dict(width=w, height=h, fx=57.0, fy=57.0, cx=32.0, cy=20.0, camera_height=1.6, pitch=6.0, roll=0.0)
    s = sg.Scene()
    g = P.ground()
    s.add_instance(s.add_mesh(g["positions"], g["indices"], g["normals"], g["uvs"]), np.eye(4, dtype=np.float32),
                   material_id=s.add_material("diffuse", {"albedo": 0.15}))
    s.add_light("sky", {"elevation": 35.0, "azimuth": 230.0, "strength": 0.02})
    s.set_camera(Calibration(**cal).camera())
    photos = tmp_path / "photos"
    photos.mkdir()
    buf = oiio.ImageBuf(oiio.ImageSpec(w, h, 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(np.asarray(s.render(spp=16, seed=1).rgb), np.float32))
    assert buf.write(str(photos / "street.exr"))
    (photos / "calibration.yaml").write_text(
        f"intrinsics: {{fx: {cal['fx']}, cx: {cal['cx']}, cy: {cal['cy']}}}\n"
        f"ground: {{camera_height: 1.6, pitch: 6.0}}\nsun: {{azimuth: 230.0, elevation: 35.0}}\n"
        "objects:\n  - {class: box, box: [2, 30, 10, 40]}\n")
    frames = []
    for version in (1, 2):
        text = (f"version: {version}\nseed: 5\nresolution: [{w}, {h}]\n"
                "background: {photos: [photos], ground_albedo: 0.15, dome: false}\n"
                "objects: [{class: box, primitive: box, size: [1.6, 1.2, 1.6], "
                "material: {type: diffuse, albedo: [0.7, 0.1, 0.1]}}]\nrender: {spp: 4}\n")
        sc = parse_scenario(parse_yaml(text), str(tmp_path / "aug.yaml"), str(tmp_path), text)
        frames.append(FrameRenderer(sc).render(0))
    (a, meta_a, _), (b, meta_b, _) = frames
    assert meta_b["exposure"]["mode"] == "photo" and meta_b["exposure"]["factor"] == 1.0
    assert meta_a["exposure"]["mode"] == "photo"
    for k in ("rgb", "instance_id", "depth"):
        assert np.array_equal(np.asarray(a[k]), np.asarray(b[k]), equal_nan=True), k


def test_a_physical_sky_that_nothing_exposes_is_warned_about(tmp_path, capsys):
    """Version 1 with a sky without strength (white in an 8-bit image) validates and runs with
    a warning naming the file, line and key; version 2, a strength, a camera.exposure or a
    night condition (which exposes) need none. An exposure post step under version 2's default
    auto-exposure is warned about too."""
    from synthgen.cli import main

    def warnings(version=1, exposure="", extra="", light=None):
        text = SKY_CAR.format(version=version, exposure=exposure, extra=extra)
        if light:
            text = text.replace("{type: sky, elevation: 40, azimuth: 120, turbidity: 3}", light)
        p = tmp_path / "w.yaml"
        p.write_text(text)
        assert main(["validate", str(p)]) == 0
        return capsys.readouterr().err

    err = warnings()
    assert f"warning: {tmp_path / 'w.yaml'}:9:10: lights[0]: a sky without strength is at physical scale" in err, err
    assert "write version: 2" in err
    assert warnings(version=2) == ""
    assert warnings(light="{type: sky, elevation: 40, strength: 0.02}") == ""
    assert warnings(exposure="exposure: {factor: 1}") == ""
    assert warnings(extra=NIGHT) == ""
    # A version 1 hand exposure moved to version 2 would multiply the metered image.
    err = warnings(version=2, extra="post: [{type: exposure, ev: 8}]")
    assert "post[0]: an exposure step on top of version 2's auto-exposure" in err, err
    assert warnings(version=2, exposure="exposure: {mode: auto}", extra="post: [{type: exposure, ev: 1}]") == ""
    from synthgen import run as runner

    s = runner.run(str(tmp_path / "w.yaml"), str(tmp_path / "ds"), count=1, progress=False)
    assert not s["failures"]
    p = tmp_path / "w.yaml"
    p.write_text(SKY_CAR.format(version=1, exposure="", extra=""))
    runner.run(str(p), str(tmp_path / "ds1"), count=1, progress=False)
    assert "lights[0]: a sky without strength" in capsys.readouterr().err
