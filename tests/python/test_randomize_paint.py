"""The ``paint`` randomizer and material roles: the palette's colours come with their shares
(chi-square), a library vehicle's body takes the colour drawn (its albedo label), its glass is
dark, and paint on a model that names no paint material is refused."""
import json
import os
import re

import numpy as np
import pytest

from synthgen import run as runner
from synthgen.randomize.paint import CARS, draw
from synthgen.scene import assets

import OpenImageIO as oiio

from test_output_kitti import _asset

CAR = "mesh/sumo-car-normal-citrus"


def test_the_palette_draws_colours_by_their_shares():
    rng = np.random.default_rng(4)
    n = 20000
    names = [draw("cars", rng)[0] for _ in range(n)]
    observed = np.array([names.count(c[0]) for c in CARS], float)
    p = np.array([c[1] for c in CARS])
    expected = n * p / p.sum()
    chi2 = float(((observed - expected) ** 2 / expected).sum())
    # NOTE: 9 degrees of freedom; the 0.999 quantile of chi-square(9) is 27.88.
    assert chi2 < 27.88, (chi2, observed, expected)


def test_a_vehicle_takes_the_colour_drawn_and_has_dark_glass(tmp_path):
    _asset(CAR)
    scen = tmp_path / "s.yaml"
    scen.write_text(f"""
seed: 8
resolution: [240, 180]
camera: {{fov_y: 30, pose: {{type: orbit, target: [0, 0.7, 0], distance: 9, elevation: 10, azimuth: 35}}}}
lights: [{{type: environment, radiance: 1.0}}]
objects: [{{class: car, asset: {CAR}, yaw: 0, paint: {{palette: cars}}}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 1, max_depth: 1}}
outputs: [albedo, instance]
""")
    out = str(tmp_path / "ds")
    s = runner.run(str(scen), out, count=3, progress=False)
    assert not s["failures"], s.text()
    for k in range(3):
        meta = json.load(open(os.path.join(out, "meta", f"{k:06d}.json")))
        drawn = np.asarray(meta["objects"][0]["paint"]["albedo"])
        albedo = oiio.ImageBuf(os.path.join(out, "albedo", f"{k:06d}.exr")).get_pixels(oiio.FLOAT)
        ids = oiio.ImageBuf(os.path.join(out, "instance", f"{k:06d}.png")).get_pixels(oiio.UINT16)[..., 0]
        a = albedo[ids == 1]
        body = np.all(np.abs(a - drawn) < 1e-3, axis=1)
        glass = np.all(np.abs(a - 0.015) < 1e-3, axis=1)
        assert body.mean() > 0.3, (k, body.mean())  # the body is most of the car
        assert glass.mean() > 0.03, (k, glass.mean())  # and its windows are dark glass


def _refused_before_and_by_the_frame(path, tmp_path, key, words):
    """``synthgen run`` (and validate) refuse the scenario at the object's shape key before
    rendering; a frame rendered without that check fails with the same reason (one test, the
    randomizer's needs, in both)."""
    from synthgen import SceneFileError, Scenario, SynthgenError

    with pytest.raises(SceneFileError) as e:
        runner.run(str(path), str(tmp_path / "ds"), count=1, progress=False)
    assert e.value.key_path == "objects[0].primitive" and words in str(e.value), str(e.value)
    with pytest.raises(SynthgenError, match=re.escape(f"objects[0].{key}: its model {words}")):
        Scenario(str(path), check_inputs=False).frame(0)


def test_paint_on_a_model_without_a_paint_material_is_refused(tmp_path):
    scen = tmp_path / "s.yaml"
    scen.write_text("""
seed: 1
resolution: [64, 48]
objects: [{class: box, primitive: box, paint: {palette: cars}}]
render: {spp: 1}
outputs: [rgb]
""")
    _refused_before_and_by_the_frame(scen, tmp_path, "paint", "names no paint material")


def test_an_unknown_material_role_is_refused(tmp_path):
    import yaml

    (tmp_path / "m.yaml").write_text(yaml.safe_dump({"assets": [{
        "id": "mesh/x", "kind": "mesh", "licence": "CC0-1.0", "sha256": "0" * 64, "source": {"path": "x.obj"},
        "materials": {"body": "varnish"}}]}))
    with pytest.raises(assets.AssetError, match="the roles being paint, glass"):
        assets.load_manifest(str(tmp_path))
