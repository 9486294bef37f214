"""Weather ``dusk`` and ``night`` (synthgen.randomize.weather, docs/weather.md "Dusk and night"):
the frame's lights become the twilight sky, vehicles' lamps light up with headlamp beams,
street lights stand along the road, and the frame is exposed automatically. Checked against
the written dataset: a street light's spot and a headlamp's beam light the road by the
inverse-square law (radiance = albedo / pi x I cos / d^2 at the pixels' world points, from the
depth and camera the dataset writes), lamps are lit where the metadata says, labels do not see
the lights, a given exposure scales the image exactly, auto-exposure lands near its key, and a
light condition that never happens changes no byte."""
import json
import math
import os

import numpy as np
import OpenImageIO as oiio
import pytest

from synthgen import run as runner
from synthgen.scene import assets

from test_output_kitti import _asset

CAR = "mesh/sumo-car-normal-citrus"
Y = np.array([0.2126, 0.7152, 0.0722])

BASE = """
seed: 9
resolution: [{w}, {h}]
camera: {{fov_y: 55, pose: {{type: look_at, eye: {eye}, target: {target}}}}}
lights: [{{type: sky, elevation: 40, azimuth: 200, strength: 0.02}}]
ground: {{material: {{type: diffuse, albedo: 0.5}}}}
objects: [{objects}]
placement: {{region: {region}, min_pixels: 1, min_visible_fraction: 0.0}}
render: {{spp: {spp}, max_depth: 3}}
outputs: [rgb, rgb_exr, depth, instance, semantic]
{weather}
"""
BOX = "{class: box, primitive: box, size: [1, 1, 1], yaw: 0}"


def _run(tmp_path, name, weather="", *, w=96, h=64, spp=8, eye="[0, 14, -12]", target="[0, 0, 3]",
         objects=BOX, region="[-6.5, 5.5, -5.5, 6.5]", count=1):
    d = tmp_path / name
    d.mkdir()
    (d / "s.yaml").write_text(BASE.format(w=w, h=h, eye=eye, target=target, objects=objects, region=region,
                                          spp=spp, weather=weather))
    s = runner.run(str(d / "s.yaml"), str(d / "ds"), count=count, progress=False)
    assert not s["failures"], s.text()
    return str(d / "ds")


def _read(out, kind, k=0, fmt=oiio.FLOAT):
    ext = {"images": "exr" if fmt == oiio.FLOAT else "png", "depth": "exr"}.get(kind, "png")
    return oiio.ImageBuf(os.path.join(out, kind, f"{k:06d}.{ext}")).get_pixels(fmt)


def _meta(out, k=0):
    return json.load(open(os.path.join(out, "meta", f"{k:06d}.json")))


def _world_points(out, meta):
    """World position of every pixel's surface (pixel centres; from depth, K, world_from_camera)."""
    depth = _read(out, "depth")[..., 0].astype(np.float64)
    cam = meta["camera"]
    h, w = depth.shape
    v, u = np.mgrid[0:h, 0:w] + 0.5
    x = (u - cam["cx"]) / cam["fx"] * depth
    y = (v - cam["cy"]) / cam["fy"] * depth
    p = np.stack([x, y, depth, np.ones_like(depth)], -1)
    return (p @ np.asarray(cam["world_from_camera"]).T)[..., :3], np.isfinite(depth)


def _smoothstep_falloff(cos_t, cone, start):
    ce, cs = math.cos(math.radians(cone)), math.cos(math.radians(start))
    t = np.clip((cos_t - ce) / (cs - ce), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


NIGHT_SPOT = ("weather: {night: {elevation: -30, sky_glow: 0, moon: {probability: 0}, lamps: {head: off, tail: false},"
              " exposure: {ev: 0}, street_lights: {spacing: 1000, sides: one, offset: 4, height: 8, intensity: 5000,"
              " range: 100, poles: false}}}")


def test_street_light_lights_the_road_by_the_inverse_square_law(tmp_path):
    """One street light (5000 cd, 8 m up, the twilight sky at -30 degrees: only the night sky's
    1e-5 of it): every ground pixel's radiance is albedo / pi x I f(theta) cos(i) / d^2 with the
    spot's position, intensity and falloff from meta -- the median ratio within 0.5%, 95% of
    the pixels within 3% (a pixel averages over its footprint); 78 lx straight under it;
    nothing beyond its 65-degree cone but the night sky."""
    out = _run(tmp_path, "spot", NIGHT_SPOT)
    meta = _meta(out)
    w = meta["weather"]["night"]
    assert w["street_light_count"] == 1 and w["headlamp_beams"] == 0 and w["exposure"] == {"ev": 0.0, "auto": False}
    spots = [li["params"] for li in meta["lights"] if li["type"] == "spot"]
    assert len(spots) == 1 and [li["type"] for li in meta["lights"]][0] == "twilight"
    s = spots[0]
    pos, inten = np.asarray(s["position"]), np.asarray(s["intensity"])
    assert pos[1] == pytest.approx(7.97) and pos[2] == pytest.approx(4.0 - 1.4)  # over the road side of the pole
    # 5000 cd in the sky's units (strength 0.02): luminance 5000 / 683 x 0.02.
    assert float(inten @ Y) == pytest.approx(5000.0 / 683.0 * 0.02, rel=1e-6)
    rgb = _read(out, "images")[..., :3].astype(np.float64)
    ids = _read(out, "instance", fmt=oiio.UINT16)[..., 0]
    pts, ok = _world_points(out, meta)
    ground = ok & (ids == 0) & (np.abs(pts[..., 1]) < 1e-3)
    box = np.asarray(meta["objects"][0]["world_from_object"])[:3, 3]
    ground &= np.hypot(pts[..., 0] - box[0], pts[..., 2] - box[2]) > 2.5  # away from the box's reflection
    d = pos - pts
    dist = np.linalg.norm(d, axis=-1)
    cos_i = d[..., 1] / dist
    f = _smoothstep_falloff(cos_i, 65.0, 30.0)  # the spot points straight down: its angle is the incidence
    expect = 0.5 / np.pi * inten[None, None, :] * (f * cos_i / dist ** 2)[..., None]
    lit = ground & (f > 0.05)
    ratio = (rgb[lit] @ Y) / (expect[lit] @ Y)
    print(f"\n{lit.sum()} lit ground pixels: ratio median {np.median(ratio):.4f}, "
          f"5-95% {np.percentile(ratio, 5):.4f}-{np.percentile(ratio, 95):.4f}")
    assert lit.sum() > 500
    assert np.median(ratio) == pytest.approx(1.0, abs=5e-3)
    assert np.mean(np.abs(ratio - 1.0) < 0.03) > 0.95
    e_under = float(inten @ Y) / 7.97 ** 2 * 683.0 / 0.02
    assert e_under == pytest.approx(78.7, abs=0.1)
    dark = ground & (f == 0.0)
    assert dark.sum() > 50 and float((rgb[dark] @ Y).max()) < 1e-4 * float((expect[lit] @ Y).max())


def test_headlamp_beams_light_the_road_ahead(tmp_path):
    """A car at night: its head and tail lamps are lit (metadata), two headlamp beams sit 5 cm
    in front of its headlamp lenses (the manifest's height and offset) aimed along the car; the
    road 5-12 m ahead gets what the beams send it: the difference with the beams switched off
    (the lenses still lit) is albedo / pi x sum I(w) cos / d^2 of the low-beam pattern, over
    patches of pixels within 5%."""
    _asset(CAR)
    weather = ("weather: {night: {elevation: -30, sky_glow: 0, moon: {probability: 0}, exposure: {ev: 0}, "
               "lamps: {high_beam: 0, beams: %s}, street_lights: {enabled: false}}}")
    kw = dict(w=120, h=80, spp=64, eye="[-2, 6, 6]", target="[8, 0, 0]",
              objects=f"{{class: car, asset: {CAR}, yaw: 0}}", region="[-0.01, -0.01, 0.01, 0.01]")
    on = _run(tmp_path, "on", weather % "true", **kw)
    off = _run(tmp_path, "off", weather % "false", **kw)
    meta = _meta(on)
    rec = meta["objects"][0]["lamps"]
    assert rec["head"] == "low" and {"head.left", "head.right", "tail.left", "tail.right"} <= set(rec["lit"])
    assert meta["weather"]["night"]["headlamp_beams"] == 2 and _meta(off)["weather"]["night"]["headlamp_beams"] == 0
    heads = [li["params"] for li in meta["lights"] if li["type"] == "headlamp"]
    entry = assets.entry(CAR)["lamps"]["head"]
    world = np.asarray(meta["objects"][0]["world_from_object"])
    front = max(p["position"][0] for p in heads)
    for p in heads:
        assert p["position"][1] == pytest.approx(entry["height"], abs=0.03)
        assert abs(p["position"][2]) == pytest.approx(entry["offset"], abs=0.03)
        assert p["position"][0] == pytest.approx(front, abs=0.03) and front > world[0, 3] + 1.0
        assert np.allclose(p["direction"], [1, 0, 0], atol=1e-6) and np.allclose(p["up"], [0, 1, 0], atol=1e-6)
        assert p["beam"] == "low"
        assert float(np.asarray(p["intensity"]) @ Y) == pytest.approx(15000.0 / 683.0 * 0.02, rel=1e-6)
    diff = (_read(on, "images")[..., :3] - _read(off, "images")[..., :3]).astype(np.float64) @ Y
    pts, ok = _world_points(on, meta)

    def pattern(w, fwd, up):
        right = np.cross(fwd, up)
        hdeg = np.degrees(np.arctan2(w @ right, w @ fwd))
        vdeg = np.degrees(np.arcsin(np.clip(w @ up, -1, 1)))
        g = lambda x, s: np.exp(-0.5 * (x / s) ** 2)  # noqa: E731
        hh = 0.7 * g(hdeg, 5.0) + 0.3 * g(hdeg, 22.0)
        c, hot = -0.57, -1.57
        below = np.where(vdeg >= hot, 1.0, g(vdeg - hot, 3.5))
        t = np.clip((vdeg - (c - 0.3)) / 0.6, 0, 1)
        t = t * t * (3 - 2 * t)
        return np.where(w @ fwd > 0, hh * (below * (1 - t) + 0.01 * t), 0.0)

    expect = np.zeros(diff.shape)
    for p in heads:
        d = pts - np.asarray(p["position"])
        dist = np.linalg.norm(d, axis=-1)
        wdir = d / dist[..., None]
        cos_i = -wdir[..., 1]
        expect += 0.5 / np.pi * float(np.asarray(p["intensity"]) @ Y) * pattern(
            wdir, np.asarray(p["direction"]), np.asarray(p["up"])) * np.clip(cos_i, 0, None) / dist ** 2
    ids = _read(on, "instance", fmt=oiio.UINT16)[..., 0]
    ahead = ok & (ids == 0) & (pts[..., 0] > front + 5.0) & (pts[..., 0] < front + 12.0) & (np.abs(pts[..., 2]) < 2.5)
    assert ahead.sum() > 150
    # Patches of 5 x 5 pixels entirely on the road ahead: the means agree.
    checked = 0
    h, w = diff.shape
    for y0 in range(0, h - 5, 5):
        for x0 in range(0, w - 5, 5):
            m = ahead[y0:y0 + 5, x0:x0 + 5]
            if m.all():
                r = diff[y0:y0 + 5, x0:x0 + 5].mean() / expect[y0:y0 + 5, x0:x0 + 5].mean()
                assert r == pytest.approx(1.0, abs=0.05), (y0, x0, r)
                checked += 1
    assert checked >= 4


def test_labels_do_not_see_the_lights(tmp_path):
    """The same frames by day and at night with a car (its lamps and beams lit), street lights
    without poles: the instance and semantic masks are identical, byte for byte; with poles the
    only differences are pixels where a pole (class 0, unlabelled) now stands in front."""
    _asset(CAR)
    kw = dict(eye="[0.5, 2, 12]", target="[0, 0.6, 0]", objects=f"{{class: car, asset: {CAR}, yaw: 0}}, " + BOX,
              region="[-3, -3, 3, 3]", count=2)
    day = _run(tmp_path, "day", "", **kw)
    night = _run(tmp_path, "night", "weather: {night: {street_lights: {poles: false, offset: 5}}}", **kw)
    poles = _run(tmp_path, "poles", "weather: {night: {street_lights: {offset: 5, spacing: 5, sides: both}}}", **kw)
    seen_pole = 0
    for k in range(2):
        assert _meta(night, k)["weather"]["night"]["street_light_count"] > 0
        for kind in ("instance", "semantic"):
            a = _read(day, kind, k, oiio.UINT16)
            assert np.array_equal(a, _read(night, kind, k, oiio.UINT16)), (k, kind)
            b = _read(poles, kind, k, oiio.UINT16)
            changed = a != b
            assert (b[changed] == 0).all(), (k, kind)
            seen_pole += int(changed.sum())
    assert seen_pole > 0


def test_exposure_given_scales_exactly_and_auto_lands_near_its_key(tmp_path):
    """ev: 2 gives the ev: 0 image x 4 exactly (no clamping in this scenario); auto-exposure
    records its ev and the metered scene's EV100 (a lit street at night: -3 to 6) and brings the
    image's log-average luminance to its key (0.05) within a factor 2, unless the highlight
    limit holds it lower; the frame is not black."""
    base = NIGHT_SPOT.replace("spacing: 1000, sides: one, offset: 4", "spacing: 12, sides: both, offset: 5")
    a = _run(tmp_path, "ev0", base)
    b = _run(tmp_path, "ev2", base.replace("ev: 0", "ev: 2"))
    ra, rb = _read(a, "images")[..., :3], _read(b, "images")[..., :3]
    assert np.array_equal(rb, (ra * np.float32(4.0)).astype(np.float32))
    auto = _run(tmp_path, "auto", base.replace("exposure: {ev: 0}", "exposure: {key: 0.05}"))
    e = _meta(auto)["weather"]["night"]["exposure"]
    assert e["auto"] and e["key"] == 0.05 and -3.0 < e["scene_ev100"] < 6.0, e
    y = _read(auto, "images")[..., :3].astype(np.float64) @ Y
    assert np.allclose(y, (ra.astype(np.float64) @ Y) * 2.0 ** e["ev"], rtol=1e-5, atol=1e-9)
    log_avg = float(np.exp(np.mean(np.log(np.maximum(y, 0.01 * np.median(y))))))
    print(f"\nauto-exposure: ev {e['ev']}, scene EV100 {e['scene_ev100']}, log-average {log_avg:.4f}")
    assert log_avg < 0.1
    assert log_avg > 0.025 or np.percentile(y, 97) > 0.7
    assert float(np.median(y)) > 0.005


def test_dusk_sky_glows_towards_the_sun(tmp_path):
    """Dusk with the scenario's sun azimuth kept (200 degrees: the camera looks that way): the
    sky just above the horizon is brighter and redder than higher up, which is bluer."""
    out = _run(tmp_path, "dusk", "weather: {dusk: {elevation: -4, exposure: {ev: 0}, street_lights: {enabled: false}}}",
               eye="[0, 1.5, 0]", target="[-3.4, 1.9, 9.4]", objects=BOX, region="[20, 20, 21, 21]")
    meta = _meta(out)
    w = meta["weather"]["dusk"]
    assert w["azimuth"] == 200.0 and w["sky_light"] == "twilight" and w["strength"] == 0.02
    rgb = _read(out, "images")[..., :3].astype(np.float64)
    ids = _read(out, "instance", fmt=oiio.UINT16)[..., 0]
    depth = _read(out, "depth")[..., 0]
    sky = ~np.isfinite(depth) & (ids == 0)
    rows = np.where(sky.any(axis=1))[0]
    low, high = rgb[rows[-1]][sky[rows[-1]]].mean(axis=0), rgb[rows[0]][sky[rows[0]]].mean(axis=0)
    assert low @ Y > 2.0 * (high @ Y)
    assert low[0] / low[2] > 2.0 * high[0] / high[2]
    assert high[2] > high[0]


def test_light_conditions_that_never_happen_change_nothing(tmp_path):
    """dusk and night with probability 0 (their group's own random stream): the frames are those
    of the scenario without a weather section, byte for byte; meta says no weather."""
    kw = dict(count=2, eye="[4, 5, -6]", target="[0, 0, 0]", region="[-2, -2, 2, 2]")
    a = _run(tmp_path, "plain", "", **kw)
    b = _run(tmp_path, "never", "weather: {dusk: {probability: 0}, night: {probability: 0}}", **kw)
    for k in range(2):
        assert np.array_equal(_read(a, "images", k, oiio.UINT8), _read(b, "images", k, oiio.UINT8)), k
        assert np.array_equal(_read(a, "images", k), _read(b, "images", k)), k
        assert _meta(b, k)["weather"] is None


def test_dusk_and_night_are_refused_over_photos_and_documented():
    """Over photo backgrounds the condition is an error at its key (the photo has its own time
    of day); the schema documents both conditions in the light group."""
    from synthgen.randomize import weather

    for key in ("dusk", "night"):
        c = weather.condition(key)
        assert c.group == "light"
        msgs = []
        c.check({}, {"background": {"photos": "x"}}, msgs.append)
        assert msgs and "photo" in msgs[0]
    doc = weather.schema().doc
    assert "light (dusk, night)" in doc


def test_layout_never_sees_the_previous_frames_street_lights(tmp_path, monkeypatch):
    """A worker's scene keeps the weather geometry of the frame it rendered last (hidden, for the
    next night): the next frame's layout checks must not see the poles that were shown, or the
    frame would depend on what its worker rendered before (not bit-identical when rendered
    alone)."""
    from synthgen.frame import renderer as R
    from synthgen.scenario.load import load_scenario

    (tmp_path / "s.yaml").write_text(BASE.format(
        w=48, h=32, eye="[0, 14, -12]", target="[0, 0, 3]", objects=BOX, region="[-6.5, 5.5, -5.5, 6.5]", spp=1,
        weather="weather: {night: {street_lights: {offset: 4, spacing: 5, sides: both}}}"))
    fr = R.FrameRenderer(load_scenario(str(tmp_path / "s.yaml")), threads=1)
    fr.render(0)
    pools = [i for p in fr.weather_pools.values() for i in p.ids]
    assert any(fr.scene.instance_visible(i) for i in pools)  # frame 0's poles stand in the scene
    seen = []
    search = R.search_layout

    def spy(view, *a, **k):
        seen.append([i for i in pools if fr.scene.instance_visible(i)])
        return search(view, *a, **k)

    monkeypatch.setattr(R, "search_layout", spy)
    fr.prepare(1)
    assert seen == [[]]
