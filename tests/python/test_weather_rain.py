"""Weather ``rain`` and the post step ``rain`` (docs/weather.md): streaks are deterministic per
seed; a streak is drawn only where its drop is nearer than the surface the pixel sees; the
number of drops is the Marshall-Palmer density times the volume seen; the veil is Koschmieder's
with the rain's extinction; in scenarios labels are the render's, byte for byte, and frames
without rain are the frames of a scenario without it."""
import json
import math
import os

import numpy as np
import pytest

from synthgen import post
from synthgen.post.rain import drop_density, rain_extinction, rain_streaks

from test_weather_scenario import file_bytes, run_tiny

W, H, F = 240, 160, 200.0


def _image():
    """A white sky over the top rows (nothing there: depth inf), black below at ``depth``."""
    rgb = np.zeros((H, W, 3), np.float32)
    rgb[:20] = 1.0
    depth = np.full((H, W), np.inf, np.float32)
    return rgb, depth


def _rain(rgb, depth, seed=1, **kw):
    return rain_streaks(rgb, depth, np.random.default_rng(seed), fx=F, fy=F, cx=W / 2, cy=H / 2, **kw)


def test_rain_is_deterministic_per_seed():
    arrays = {"rgb": np.full((H, W, 3), 0.1, np.float32), "depth": np.full((H, W), 5.0, np.float32)}
    arrays["rgb"][:10] = 2.0
    params = {"rate": 20.0, "exposure": 0.004, "wind": 2.0, "brightness": 1.0, "near": 0.3, "far": 8.0,
              "veil": 1.0, "fov_y": 50.0}
    a = post.apply_steps(arrays, [("rain", dict(params, seed=3))])
    b = post.apply_steps(arrays, [("rain", dict(params, seed=3))])
    c = post.apply_steps(arrays, [("rain", dict(params, seed=4))])
    assert np.array_equal(a["rgb"], b["rgb"]) and not np.array_equal(a["rgb"], c["rgb"])
    assert np.array_equal(a["depth"], arrays["depth"]), "labels untouched"
    assert (a["rgb"][10:] > 0.1 + 1e-4).mean() > 0.05, "streaks show against the dark part"


def test_streaks_behind_a_surface_are_not_drawn():
    """Left third: a wall 0.2 m away (nearer than every drop): not one pixel changes. Middle:
    a wall at 2 m hides the drops beyond it: fewer streaks than on the right, open to 8 m."""
    rgb, depth = _image()
    depth[:, : W // 3] = 0.2
    depth[20:, W // 3: 2 * W // 3] = 2.0
    out, info = _rain(rgb, depth, rate=30.0, veil=0.0)
    assert info["drops"] > 1000
    assert np.array_equal(out[:, : W // 3], rgb[:, : W // 3])
    middle = out[20:, W // 3: 2 * W // 3].mean()
    right = out[20:, 2 * W // 3:].mean()
    assert 0.0 < middle < 0.5 * right, (middle, right)


def test_the_number_of_drops_is_marshall_palmer_times_the_volume():
    rgb, depth = _image()
    counts = []
    for seed in range(4):
        counts.append(_rain(rgb, depth, seed=seed, rate=10.0, near=0.5, far=4.0)[1]["drops"])
    margin = 0.25 * max(W, H)
    volume = (W + 2 * margin) * (H + 2 * margin) / F ** 2 * (4.0 ** 3 - 0.5 ** 3) / 3.0
    expected = drop_density(10.0) * volume
    assert abs(np.mean(counts) - expected) < 5 * math.sqrt(expected / 4), (counts, expected)
    # Marshall-Palmer at 10 mm/h: about 900 drops per m^3 over 0.5 mm; extinction 1.5e-3 / m.
    assert 800 < drop_density(10.0) < 1000
    assert rain_extinction(10.0) == pytest.approx(1.55e-3, rel=0.02)


def test_the_veil_is_koschmieder_with_the_rains_extinction():
    """No drops (near = far): each pixel at distance d is I t + A (1 - t), t = exp(-beta (d - far))."""
    rgb = np.full((H, W, 3), 0.05, np.float32)
    rgb[:20] = 1.0
    depth = np.full((H, W), 300.0, np.float32)
    out, info = _rain(rgb, depth, rate=20.0, near=1.0, far=1.0)
    assert info["drops"] == 0
    beta = rain_extinction(20.0)
    v, u = np.mgrid[0:H, 0:W] + 0.5
    dist = 300.0 * np.sqrt(1 + ((u - W / 2) / F) ** 2 + ((v - H / 2) / F) ** 2)
    t = np.exp(-beta * (dist - 1.0))[..., None]
    a = np.array(info["drop_radiance"])  # brightness 1: the environment estimate
    np.testing.assert_allclose(out, rgb * t + a * (1 - t), rtol=1e-5, atol=1e-6)


# -- in scenarios -------------------------------------------------------------------------

def test_rain_changes_images_not_labels_and_is_reproducible(tmp_path):
    """Rain in half the frames: labels byte-identical to the clear run, images too where it does
    not rain; a second run gives the same images; meta records the parameters and the drops."""
    clear = run_tiny(tmp_path, "clear", "", count=4)
    weather = "weather: {rain: {probability: 0.5, rate: {uniform: [5, 30]}, wind: {uniform: [-3, 3]}}}"
    rain = run_tiny(tmp_path, "rain", weather, count=4)
    again = run_tiny(tmp_path, "again", weather, count=4)
    kinds = set()
    for k in range(4):
        name = f"{k:06d}"
        for sub in ("instance/{}.png", "semantic/{}.png", "depth/{}.exr"):
            assert file_bytes(os.path.join(clear, sub.format(name))) == file_bytes(os.path.join(rain, sub.format(name)))
        img = os.path.join("images", f"{name}.png")
        assert file_bytes(os.path.join(rain, img)) == file_bytes(os.path.join(again, img)), "rain is deterministic"
        meta = json.load(open(os.path.join(rain, "meta", f"{name}.json")))
        raining = meta["weather"] is not None
        kinds.add(raining)
        assert (file_bytes(os.path.join(clear, img)) == file_bytes(os.path.join(rain, img))) == (not raining)
        if raining:
            r = meta["weather"]["rain"]
            assert 5 <= r["rate"] <= 30 and -3 <= r["wind"] <= 3 and r["drops"] > 0 and r["extinction"] > 0
    assert kinds == {True, False}


def test_rain_as_a_post_step(tmp_path):
    clear = run_tiny(tmp_path, "clear", "", count=2)
    out = run_tiny(tmp_path, "post", "post: [{type: rain, rate: 40, seed: {int: [0, 1000]}}]", count=2)
    for k in range(2):
        name = f"{k:06d}"
        assert file_bytes(os.path.join(clear, "instance", f"{name}.png")) == file_bytes(os.path.join(out, "instance",
                                                                                            f"{name}.png"))
        assert file_bytes(os.path.join(clear, "images", f"{name}.png")) != file_bytes(os.path.join(out, "images",
                                                                                          f"{name}.png"))
        meta = json.load(open(os.path.join(out, "meta", f"{name}.json")))
        assert meta["post"][0]["type"] == "rain" and meta["post"][0]["params"]["rate"] == 40
