"""Bad input is refused before anything renders: every file a scenario names is loaded once
(by `synthgen validate` and at the start of `synthgen run`) and a broken one is reported at
its YAML line with what is wrong; constant materials and lights are created once too; a run
whose frames all fail the same way stops early. Library warnings stay off stderr."""
import os
import re
import shutil

import numpy as np
import pytest

from synthgen import SceneFileError, SynthgenError, cli
from synthgen import run as runner
from synthgen.scenario import check_inputs, load_scenario

KENNEY = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "assets", "kenney", "vehicle-truck-red.glb")


def scenario(tmp_path, obj, extra=""):
    p = tmp_path / "s.yaml"
    p.write_text(f"""
resolution: [32, 24]
objects:
  - {obj}
render: {{spp: 1, max_depth: 1}}
{extra}""")
    return str(p)


def error_of(path):
    sc = load_scenario(path)
    with pytest.raises(SceneFileError) as e:
        check_inputs(sc)
    return e.value


def test_truncated_glb_is_named_with_its_line(tmp_path):
    if not os.path.exists(KENNEY):
        pytest.skip("../shared is absent")
    with open(KENNEY, "rb") as f:
        (tmp_path / "car.glb").write_bytes(f.read()[:3000])
    e = error_of(scenario(tmp_path, "{class: car, mesh: car.glb}"))
    assert (e.line, e.key_path) == (4, "objects[0].mesh") and "truncated" in str(e) and "3000" in str(e), str(e)


@pytest.mark.parametrize("coord, words", [("nan", "NaN"), ("1e39", "beyond the float range")])
def test_non_finite_obj_coordinates(tmp_path, coord, words):
    (tmp_path / "m.obj").write_text(f"v 0 0 0\nv 1 0 0\nv {coord} 1 0\nf 1 2 3\n")
    e = error_of(scenario(tmp_path, "{class: m, mesh: m.obj}"))
    assert "line 3" in str(e) and words in str(e), str(e)


def test_corrupt_images_are_named_and_libraries_stay_quiet(tmp_path, capfd):
    from synthgen.outputs.files import write_srgb_png

    good = str(tmp_path / "good.png")
    write_srgb_png(good, np.full((16, 16, 3), 0.5))
    (tmp_path / "bad.png").write_bytes(open(good, "rb").read()[:60])
    (tmp_path / "bad.jpg").write_bytes(b"\xff\xd8\xff\xe0" + bytes(range(256)))
    for name in ("bad.png", "bad.jpg"):
        e = error_of(scenario(tmp_path, f"{{class: b, primitive: box, decals: [{{image: {name}}}]}}"))
        assert e.key_path == "objects[0].decals[0].image" and "cannot use this image" in str(e), str(e)
    err = capfd.readouterr().err
    assert "libpng" not in err and "JPEG" not in err, err


def test_impossible_material_is_refused_at_its_entry(tmp_path):
    e = error_of(scenario(tmp_path, "{class: g, primitive: sphere, material: {type: dielectric, ior: 1.0}}"))
    assert e.key_path == "objects[0].material" and "must differ" in str(e), str(e)


def test_run_stops_before_rendering_on_a_broken_input(tmp_path):
    (tmp_path / "m.obj").write_text("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")
    path = scenario(tmp_path, "{class: m, mesh: m.obj}")
    out = str(tmp_path / "ds")
    with pytest.raises(SceneFileError, match="line 2"):
        runner.run(path, out, count=50, progress=False)
    assert not os.path.exists(os.path.join(out, "meta"))
    assert cli.main(["validate", path]) == 2


def test_validate_reports_what_it_loaded(tmp_path, capsys):
    if not os.path.exists(KENNEY):
        pytest.skip("../shared is absent")
    assert cli.main(["validate", scenario(tmp_path, f"{{class: car, mesh: {os.path.abspath(KENNEY)}}}")]) == 0
    assert "loaded 1 mesh" in capsys.readouterr().out


def test_a_run_whose_frames_all_fail_alike_stops_early(tmp_path, monkeypatch):
    from synthgen.frame import FrameRenderer

    def broken(self, frame):
        raise SynthgenError("the same problem every time")

    monkeypatch.setattr(FrameRenderer, "render", broken)
    s = runner.run(scenario(tmp_path, "{class: b, primitive: box}"), str(tmp_path / "ds"), count=40, progress=False,
                   isolate=False)  # (the monkeypatch is in this process)
    assert len(s["failures"]) == runner.ABORT_AFTER and "stopped after 3 frames" in s.text()


def _library(tmp_path, monkeypatch, body_role="paint"):
    """A manifest of its own with two small models (OBJ with a material 'body'): test/painted
    names 'body' as its paint (``body_role``), test/plain names no roles, plates or lamps."""
    import hashlib

    import yaml

    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "car.obj").write_text("mtllib car.mtl\nv -2 0 -1\nv 2 0 -1\nv 2 1.4 1\nv -2 1.4 1\nusemtl body\n"
                                 "f 1 2 3\nf 1 3 4\n")
    (lib / "car.mtl").write_text("newmtl body\nKd 0.5 0.5 0.5\n")

    def sha(name):
        return hashlib.sha256((lib / name).read_bytes()).hexdigest()

    def entry(asset_id, **extra):
        return dict({"id": asset_id, "kind": "mesh", "licence": "CC0-1.0", "source": {"path": str(lib / "car.obj")},
                     "sha256": sha("car.obj"), "companions": [{"path": str(lib / "car.mtl"), "sha256": sha("car.mtl")}]},
                    **extra)

    (tmp_path / "manifest").mkdir()
    (tmp_path / "manifest" / "cars.yaml").write_text(yaml.safe_dump({"assets": [
        entry("test/painted", materials={"body": "paint"} if body_role == "paint" else {body_role: "paint"}),
        entry("test/plain")]}))
    monkeypatch.setenv("SYNTHGEN_MANIFEST", str(tmp_path / "manifest"))
    monkeypatch.setenv("SYNTHGEN_CACHE", str(tmp_path / "cache"))


@pytest.mark.parametrize("obj, key, words", [
    # A choice that can draw a model without a paint material: its frames would fail (issue 33.7).
    ("{class: car, asset: {choice: [test/painted, test/plain]}, paint: {}}", "objects[0].asset",
     "asset 'test/plain' cannot take objects[0].paint: its model names no paint material"),
    ("{class: car, asset: {choice: [test/painted, test/plain]}, plates: {country: de}}", "objects[0].asset",
     "asset 'test/painted' cannot take objects[0].plates: its model declares no plate mounts"),
    ("{class: car, asset: test/painted, lamps: {head: {choice: [\"off\", low]}}}", "objects[0].asset",
     "asset 'test/painted' cannot take objects[0].lamps: its model declares no lamps"),
    ("{class: car, asset: test/painted, paint: {}, material: {type: diffuse}}", "objects[0].asset",
     "objects[0].material replaces the model's own materials, which paint needs"),
    ("{class: b, primitive: box, paint: {}}", "objects[0].primitive",
     "primitive 'box' cannot take objects[0].paint: its model names no paint material"),
])
def test_every_model_an_entry_can_draw_is_checked_against_its_randomizers(tmp_path, monkeypatch, obj, key, words):
    _library(tmp_path, monkeypatch)
    path = scenario(tmp_path, obj)
    e = error_of(path)
    assert (e.line, e.key_path) == (4, key) and words in str(e), str(e)
    # The run refuses it before rendering anything (it would have failed the frames drawing it).
    with pytest.raises(SceneFileError, match=re.escape(words)):
        runner.run(path, str(tmp_path / "ds"), count=4, progress=False)


def test_models_that_can_take_the_randomizers_pass(tmp_path, monkeypatch):
    _library(tmp_path, monkeypatch)
    # The control: only the painted model can be drawn (the other option has weight 0).
    sc = load_scenario(scenario(tmp_path, "{class: car, asset: {choice: [test/painted, test/plain], weights: [1, 0]}, "
                                          "paint: {}, wear: {dirt: {}}}"))
    assert check_inputs(sc) == {"mesh": 2}   # both files are loaded, as before


def test_a_material_role_naming_no_material_of_the_model_is_refused(tmp_path, monkeypatch):
    _library(tmp_path, monkeypatch, body_role="carbody")
    e = error_of(scenario(tmp_path, "{class: car, asset: {choice: [test/plain, test/painted]}}"))
    assert e.key_path == "objects[0].asset" and \
        "asset 'test/painted': materials: the model has no material 'carbody' (it has 'DefaultMaterial', 'body')" \
        in str(e), str(e)
