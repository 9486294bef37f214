"""The ``lamps`` randomizer and the library's lamp positions: every library vehicle's lamps lie
on its body at the heights its entry declares, in mirrored pairs, facing out; lit lamps glow
where the metadata puts them (and unlit ones do not: a left indicator lights the left side
only); a model without lamps, or an entry with a bad lamp, is a clear error."""
import json
import re

import numpy as np
import pytest

import synthgen as sg
from synthgen import SynthgenError
from synthgen import run as runner
from synthgen.scene import assets
from synthgen.scene.vehicles import LAMP_KINDS, lamp_lenses, model_axes, ray_mesh

import OpenImageIO as oiio

from test_output_kitti import _asset

CAR = "mesh/sumo-car-normal-citrus"


def _library_vehicles():
    out = []
    for aid, e in sorted(assets.load_manifest().items()):
        if e.get("lamps"):
            try:
                assets.resolve(aid)
            except Exception:  # noqa: BLE001 - an optional asset not in the cache
                continue
            out.append(aid)
    return out


def test_every_library_lamp_sits_on_its_body():
    """For each library vehicle available here (the SUMO and Kenney ones always): each lamp's
    lens centre is at its declared height and offset, within 1 cm of the body surface behind
    it; pairs mirror each other; every lens faces out of its end of the vehicle."""
    ids = _library_vehicles()
    assert {"mesh/sumo-car-normal-citrus", "mesh/kenney-vehicle-motorcycle"} <= set(ids)
    print()
    for aid in ids:
        e = assets.entry(aid)
        unit = float(e.get("scale", 1.0))
        fwd, up, right = model_axes(e.get("forward", "+x"), e.get("up", "+y"))
        s = sg.Scene()
        arr = s.mesh_arrays(s.load_mesh_file(assets.resolve(aid))["mesh_id"])
        pos = np.asarray(arr["positions"], np.float64)
        tri = np.asarray(arr["indices"], np.int64)
        pos = pos + (float(e.get("ride_height", 0.0)) / unit - float((pos @ up).min())) * up
        lenses = lamp_lenses(pos, tri, e, unit)
        kinds = sorted({v["kind"] for v in lenses.values()})
        print(f"{aid}: {len(lenses)} lamps ({', '.join(kinds)})")
        assert len(lenses) >= 2
        for name, lens in lenses.items():
            spec = e["lamps"][lens["kind"]]
            c = np.asarray(lens["centre"])
            assert np.sign(lens["normal"] @ fwd) == LAMP_KINDS[lens["kind"]]["end"], name
            assert (c @ up) * unit == pytest.approx(spec["height"], abs=1e-3), name
            lat = {"left": -1.0, "right": 1.0, "centre": 0.0}[lens["side"]] * spec.get("offset", 0.0)
            assert (c @ right) * unit == pytest.approx(lat, abs=1e-3), name
            # The body behind the lens: a ray from the lens centre inwards meets it within 1 cm.
            t = ray_mesh(pos, tri, c[None], -np.asarray(lens["normal"]))[0] * unit
            assert t < 0.01, (aid, name, t)
            if lens["side"] == "left":
                other = np.asarray(lenses[name.replace(".left", ".right")]["centre"])
                # Mirrored: same height and depth, opposite lateral position.
                assert (other @ up) == pytest.approx(c @ up, abs=1e-4)
                assert (other @ right) == pytest.approx(-(c @ right), abs=1e-4)
                assert (other @ fwd) * unit == pytest.approx((c @ fwd) * unit, abs=0.03)


def _render(tmp_path, name, lamps):
    d = tmp_path / name
    d.mkdir()
    (d / "s.yaml").write_text(f"""
seed: 4
resolution: [480, 320]
camera: {{fov_y: 24, pose: {{type: orbit, target: [0, 0.7, 0], distance: 8, elevation: 6, azimuth: 290}}}}
lights: [{{type: environment, radiance: 0.002}}]
ground: {{material: {{type: diffuse, albedo: 0.2}}}}
objects: [{{class: car, asset: {CAR}, yaw: 0, lamps: {lamps}}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 16, max_depth: 3}}
outputs: [rgb, instance, depth]
""")
    s = runner.run(str(d / "s.yaml"), str(d / "ds"), count=1, progress=False)
    assert not s["failures"], s.text()
    meta = json.load(open(d / "ds" / "meta" / "000000.json"))
    rgb = oiio.ImageBuf(str(d / "ds" / "images" / "000000.png")).get_pixels(oiio.FLOAT)[..., :3]
    ids = oiio.ImageBuf(str(d / "ds" / "instance" / "000000.png")).get_pixels(oiio.UINT16)[..., 0]
    return meta, rgb, ids


def test_lit_lamps_glow_where_the_metadata_puts_them(tmp_path):
    """At night, from behind the car: with tail, brake and left indicators on, each
    visible lit lamp's centre (as the metadata gives it) is on the car's mask and far brighter
    than the same pixel with every lamp off; the right indicator stays dark."""
    _asset(CAR)
    meta_on, on, ids = _render(tmp_path, "on", "{head: off, tail: true, brake: true, indicators: left, strength: 0.02}")
    _, off, _ = _render(tmp_path, "off", "{head: off, tail: false, brake: false, indicators: off}")
    rec = meta_on["objects"][0]["lamps"]
    assert "tail.left" in rec["lit"] and "indicator_rear.left" in rec["lit"]
    assert "indicator_rear.right" not in rec["lit"] and "head.left" not in rec["lit"]
    lum = lambda img, u, v: float(img[int(v) - 1:int(v) + 2, int(u) - 1:int(u) + 2].mean())  # noqa: E731
    seen = {r["name"]: r for r in rec["image"] if r["visible"]}
    assert {"tail.left", "tail.right", "indicator_rear.left", "indicator_rear.right"} <= set(seen), sorted(seen)
    assert not any(r["visible"] for r in rec["image"] if r["kind"] in ("head", "indicator_front"))
    print()
    for name, r in sorted(seen.items()):
        u, v = r["centre"]
        assert ids[int(v), int(u)] == meta_on["objects"][0]["instance_id"], name
        x0, y0, x1, y1 = r["bbox"]
        assert x0 <= u <= x1 and y0 <= v <= y1
        ratio = lum(on, u, v) / max(lum(off, u, v), 1e-6)
        print(f"{name}: lit {r['lit']}, on / off {ratio:.1f}")
        if r["lit"]:
            assert ratio > 20.0, (name, ratio)
        else:
            assert ratio < 3.0, (name, ratio)


def test_lamps_on_a_model_without_lamps_is_an_error(tmp_path):
    (tmp_path / "s.yaml").write_text("""
seed: 1
resolution: [64, 48]
camera: {fov_y: 40, pose: {type: orbit, target: [0, 0.5, 0], distance: 5}}
lights: [{type: environment, radiance: 1}]
objects: [{class: box, primitive: box, lamps: {}}]
render: {spp: 1}
outputs: [rgb]
""")
    from test_randomize_paint import _refused_before_and_by_the_frame

    _refused_before_and_by_the_frame(tmp_path / "s.yaml", tmp_path, "lamps", "declares no lamps")


@pytest.mark.parametrize("lamps, message", [
    ({"headlight": {"height": 0.7}}, "unknown lamp 'headlight'"),
    ({"head": {"offset": 0.5}}, "expected {height"),
    ({"head": {"height": 0.7, "size": [0.2]}}, "size: expected [width, height]"),
    ({"tail": {"height": -1}}, "expected a number"),
])
def test_manifest_lamps_are_checked(tmp_path, lamps, message):
    import yaml

    (tmp_path / "m.yaml").write_text(yaml.safe_dump({"assets": [{
        "id": "mesh/x", "kind": "mesh", "licence": "CC0-1.0", "sha256": "0" * 64,
        "source": {"path": "x.obj"}, "lamps": lamps}]}))
    with pytest.raises(SynthgenError, match=re.escape("m.yaml: assets[0] (mesh/x): lamps") + ".*" + re.escape(message)):
        assets.load_manifest(str(tmp_path))


def test_a_lamp_off_the_body_is_an_error():
    e = dict(assets.entry(CAR), lamps={"head": {"height": 0.77, "offset": 1.5}})
    s = sg.Scene()
    arr = s.mesh_arrays(s.load_mesh_file(_asset(CAR))["mesh_id"])
    with pytest.raises(ValueError, match="lamp head.left at 0.77 m, offset 1.5 m"):
        lamp_lenses(np.asarray(arr["positions"], np.float64), np.asarray(arr["indices"], np.int64), e,
                    float(e["scale"]))
