"""Weather in scenarios (`weather: {fog, haze}`, docs/weather.md): the frame's medium is drawn
from its own random stream (a scenario whose weather never happens renders the frames it
rendered before weather existed), recorded in meta, and every visible object gets its
transmittance to the camera -- checked against Beer-Lambert over the depth and intrinsics the
dataset itself writes -- and its visible contrast, in meta and in the COCO annotations."""
import json
import os

import numpy as np
import OpenImageIO as oiio

from synthgen import run as runner

HERE = os.path.dirname(os.path.abspath(__file__))
TINY = os.path.join(HERE, "scenarios", "tiny.yaml")


def _scenario(tmp_path, name, weather):
    text = open(TINY).read().replace("render: {spp: 4, max_depth: 4}", weather + "\nrender: {spp: 4, max_depth: 4}")
    assert weather in text
    p = tmp_path / f"{name}.yaml"
    p.write_text(text)
    return str(p)


def run_tiny(tmp_path, name, weather, count=3):
    """The dataset of tests/python/scenarios/tiny.yaml with ``weather`` (any YAML lines: a
    weather or post section) added, ``count`` frames, in tmp_path / name (shared by the weather
    tests)."""
    out = str(tmp_path / name)
    s = runner.run(_scenario(tmp_path, name, weather), out, count=count, progress=False)
    assert not s["failures"], s.text()
    return out


_run = run_tiny


def file_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def _read(path, kind=oiio.FLOAT):
    return oiio.ImageBuf(path).get_pixels(kind)


def test_fog_labels_transmittance_and_contrast(tmp_path):
    """Fog in every frame (visibility 20-40 m, a 10 m layer; the orbit camera stands 1.6-3.3 m
    high, inside it): meta records the drawn fog; each visible object's
    transmittance is the mean over its pixels of exp(-3.912 / V * distance), the distance from
    the written depth and K (within 1e-3: depth is float32 and the label is per pixel centre);
    contrast is a number; the COCO annotation carries both; the dataset verifies."""
    out = _run(tmp_path, "fog", "weather: {fog: {visibility: {uniform: [20, 40]}, top: 10}}")
    coco = json.load(open(os.path.join(out, "annotations", "coco.json")))
    checked = 0
    for k in range(3):
        meta = json.load(open(os.path.join(out, "meta", f"{k:06d}.json")))
        assert list(meta["weather"]) == ["fog"]
        w = meta["weather"]["fog"]
        assert 20 <= w["visibility"] <= 40 and w["top"] == 10.0
        beta = 3.912 / w["visibility"]
        depth = _read(os.path.join(out, "depth", f"{k:06d}.exr"))[..., 0].astype(np.float64)
        ids = _read(os.path.join(out, "instance", f"{k:06d}.png"), oiio.UINT16)[..., 0]
        K = np.asarray(meta["camera"]["K"])
        h, wd = depth.shape
        v, u = np.mgrid[0:h, 0:wd] + 0.5
        dist = depth * np.sqrt(1 + ((u - K[0, 2]) / K[0, 0]) ** 2 + ((v - K[1, 2]) / K[1, 1]) ** 2)
        anns = {a["instance_id"]: a for a in coco["annotations"] if a["image_id"] == k}
        for o in meta["objects"]:
            if o.get("dropped") or not o.get("visible_pixels"):
                assert "weather" not in o
                continue
            m = ids == o["instance_id"]
            expect = float(np.exp(-beta * dist[m]).mean())
            assert abs(o["weather"]["transmittance"] - expect) < 1e-3, (k, o["instance_id"], o["weather"], expect)
            assert 0.0 < o["weather"]["transmittance"] < 1.0
            assert o["weather"]["contrast"] is None or o["weather"]["contrast"] >= 0.0
            a = anns[o["instance_id"]]
            assert a["transmittance"] == o["weather"]["transmittance"] and a["contrast"] == o["weather"]["contrast"]
            checked += 1
    assert checked >= 3
    from synthgen.outputs.verify import verify_dataset

    verify_dataset(out)


def test_weather_that_never_happens_changes_nothing(tmp_path):
    """The weather is drawn from a stream of its own: with probability 0 the frames are the
    frames of the scenario without a weather section, byte for byte, and meta says none."""
    a = _run(tmp_path, "plain", "", count=2)
    b = _run(tmp_path, "never", "weather: {fog: {probability: 0, visibility: 30}, haze: {probability: 0}}", count=2)
    for k in range(2):
        ra = _read(os.path.join(a, "images", f"{k:06d}.png"), oiio.UINT8)
        rb = _read(os.path.join(b, "images", f"{k:06d}.png"), oiio.UINT8)
        assert np.array_equal(ra, rb), k
        meta = json.load(open(os.path.join(b, "meta", f"{k:06d}.json")))
        assert meta["weather"] is None
        assert all("weather" not in o for o in meta["objects"])


def test_ground_fog_and_clouds_are_drawn_per_frame_and_labelled(tmp_path):
    """The heterogeneous media as weather: each frame draws its own noise seed (recorded, and a
    pure function of the scenario seed and frame: a second run is byte-identical); objects in
    ground fog get a transmittance in (0, 1) from the medium's deterministic quadrature; the
    group's order holds (ground fog before clouds: with both certain, every frame has ground
    fog)."""
    w = ("weather: {ground_fog: {visibility: 15, scale_height: 4, coverage: 1.0, feature_size: 20}, "
         "clouds: {bottom: 300, top: 600}}")
    a = _run(tmp_path, "gf", w, count=2)
    b = _run(tmp_path, "gf2", w, count=2)
    seeds = set()
    labelled = 0
    for k in range(2):
        meta = json.load(open(os.path.join(a, "meta", f"{k:06d}.json")))
        assert list(meta["weather"]) == ["ground_fog"]
        g = meta["weather"]["ground_fog"]
        assert g["visibility"] == 15.0 and isinstance(g["seed"], int)
        seeds.add(g["seed"])
        for o in meta["objects"]:
            if o.get("visible_pixels"):
                assert 0.0 < o["weather"]["transmittance"] < 1.0
                labelled += 1
        ra = _read(os.path.join(a, "images", f"{k:06d}.png"), oiio.UINT8)
        rb = _read(os.path.join(b, "images", f"{k:06d}.png"), oiio.UINT8)
        assert np.array_equal(ra, rb), k
    assert len(seeds) == 2 and labelled >= 2
    c = _run(tmp_path, "clouds", "weather: {clouds: {bottom: 300, top: 600, coverage: 0.7}}", count=1)
    meta = json.load(open(os.path.join(c, "meta", "000000.json")))
    assert list(meta["weather"]) == ["clouds"] and meta["weather"]["clouds"]["bottom"] == 300.0


def test_a_fog_layer_below_the_ground_is_refused_or_not_recorded(tmp_path, capsys):
    """A layer from the ground up to a top at or below the ground holds nothing of the scene: a
    fixed top (or a distribution whose every draw is) is refused at validate, naming the key; a
    frame whose drawn top falls there has no fog -- meta.weather null (nothing rendered, no
    object gets fog labels) and meta.weather_notes says why -- while the other frames of the
    same distribution have their fog (it was recorded as fog in every frame)."""
    from synthgen.cli import main

    for top in ("-5", "0", "{uniform: [-9, -1]}"):
        path = _scenario(tmp_path, "below", f"weather: {{fog: {{visibility: 50, top: {top}}}}}")
        assert main(["validate", path]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"synthgen: error: {path}:28:") and "weather.fog.top: " in err, err
        assert "at or below the ground" in err and "give a top above 0 m" in err
    out = run_tiny(tmp_path, "mixed", "weather: {fog: {visibility: 50, top: {uniform: [-20, 10]}}}", count=6)
    seen = set()
    for k in range(6):
        meta = json.load(open(os.path.join(out, "meta", f"{k:06d}.json")))
        top = meta["sampled"]["weather.fog.top"]
        seen.add(top > 0)
        if top > 0:
            assert meta["weather"]["fog"]["top"] == top and "weather_notes" not in meta
            assert all("weather" in o for o in meta["objects"] if o.get("visible_pixels"))
        else:
            assert meta["weather"] is None, meta["weather"]
            assert meta["weather_notes"] == [f"fog: top {top:.3g} m was drawn, at or below the ground (y = 0, where "
                                             "the objects stand): the layer, from the ground up to top, would hold "
                                             "nothing of the scene: the frame has no fog"]
            assert not any("weather" in o for o in meta["objects"])
    assert seen == {True, False}  # both kinds of frame were drawn
