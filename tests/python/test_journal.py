"""The change journal (api/journal.h, synthgen.scene.journal): a replayed journal renders
bit-identically to the scene that recorded it; a run leaves failed frames' journals that
`synthgen replay` renders again."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P, wear
from synthgen.scene import extensions

HERE = os.path.dirname(os.path.abspath(__file__))
TINY = os.path.join(HERE, "scenarios", "tiny.yaml")


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("SYNTHGEN_CACHE", str(tmp_path_factory.mktemp("cache")))


def _mesh(s, m):
    return s.add_mesh(m["positions"], m["indices"], normals=m.get("normals"), uvs=m.get("uvs"))


def _same(a, b):
    for k in ("rgb", "depth", "instance_id", "class_id", "normal", "albedo"):
        assert np.array_equal(np.asarray(getattr(a, k)), np.asarray(getattr(b, k)), equal_nan=True), k


def _edit_a_scene(s):
    """Every kind of edit, with removals, hidden instances and material maps."""
    ground = _mesh(s, P.plane(20.0, 20.0))
    s.add_instance(ground, np.eye(4), material_id=s.add_material("diffuse", {"albedo": 0.4}))
    box = _mesh(s, P.box((1.0, 1.0, 1.0)))
    ball = _mesh(s, P.uv_sphere(0.5, segments=24, rings=12))
    grey = s.add_material("principled", {"base_color": [0.5, 0.5, 0.5], "roughness": 0.4})
    red = s.add_material("diffuse", {"albedo": [0.7, 0.1, 0.1]})
    rust = wear.rust(s, grey, seed=2)
    px = np.random.default_rng(3).random((16, 16, 3)).astype(np.float32)
    img = s.add_image_texture(px, {"colorspace": "linear"})
    pic = s.add_material("diffuse", {"albedo": sg.TextureRef(img)})
    a = s.add_instance(box, P.translate([0, 0.5, 0]), class_id=1, material_id=rust)
    b = s.add_instance(ball, P.translate([1.4, 0.5, 0]), class_id=2, material_id=red)
    c = s.add_instance(box, P.translate([-1.4, 0.5, 0]), class_id=1, material_id=pic)
    d = s.add_instance(ball, P.translate([0, 0.5, 1.5]), class_id=2)
    sun = s.add_light("sun", {"direction": [0.3, 1.0, -0.4], "irradiance": 2.0})
    s.add_light("sky", {"elevation": 40.0})
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 96, 64, sg.PinholeCamera.look_at((0, 2.2, -5), (0, 0.5, 0.3),
                                                                                   (0, 1, 0))))
    s.render(spp=2, seed=1)  # a commit in between
    s.set_instance_visible(d, False)
    s.remove_instance(b)
    s.set_instance_transform(a, P.translate([0.2, 0.5, 0]) @ P.rotate([0, 1, 0], 20.0))
    s.set_instance_labels(c, 3, 33)
    s.set_instance_material_map(a, {grey: red})
    s.update_material(red, "diffuse", {"albedo": [0.1, 0.6, 0.2]})
    s.update_light(sun, "sun", {"direction": [-0.3, 1.0, -0.2], "irradiance": 3.0})
    tmp = s.add_material("diffuse", {"albedo": 0.9})
    s.remove_material(tmp)
    s.set_medium("homogeneous", {"visibility": 400.0})
    return s


def test_replay_renders_bit_identically(tmp_path):
    s = sg.Scene()
    s.begin_journal()
    _edit_a_scene(s)
    ref = s.render(spp=4, seed=7)
    path = str(tmp_path / "scene.journal")
    s.save_journal(path)
    r, settings = sg.journal.replay(path)
    assert settings["spp"] == 4 and settings["seed"] == 7
    _same(ref, r.render(**settings))
    assert r.instance_count() == s.instance_count()


def test_replay_prints_and_records_the_scene_it_replays(tmp_path, capsys):
    """`synthgen replay` counts the replayed scene's objects and lights (it printed "0 objects,
    0 lights" for every journal): the instances that render (not hidden ones), the lights."""
    from synthgen import cli

    s = sg.Scene()
    s.begin_journal()
    _edit_a_scene(s)  # 4 instances left, one of them hidden; a sun and a sky
    s.render(spp=1, seed=3)
    path = str(tmp_path / "scene.journal")
    s.save_journal(path)
    assert cli.main(["replay", path, "-o", str(tmp_path / "r"), "--spp", "1"]) == 0
    assert f"{path}: 3 objects, 2 lights, 96x64" in capsys.readouterr().out
    scene = json.loads((tmp_path / "r" / "meta.json").read_text())["scene"]
    assert scene["objects"] == [i for i in s.instances() if i["visible"]]
    assert [(o["class_id"], o["instance_id"]) for o in scene["objects"]][1:] == [(1, 2), (3, 33)]
    assert scene["hidden_instances"] == 1
    assert [li["type"] for li in scene["lights"]] == ["sun", "sky"]


def test_a_journal_begun_mid_life_starts_with_the_scene_as_it_is(tmp_path):
    s = _edit_a_scene(sg.Scene())
    s.render(spp=1)
    s.begin_journal()  # removed slots before this point stay holes: later ids must match
    box = _mesh(s, P.box((0.4, 0.4, 0.4)))
    extra = s.add_instance(box, P.translate([0.8, 0.2, -1.0]), class_id=4)
    s.set_instance_catcher(extra, False)
    ref = s.render(spp=4, seed=2)
    path = str(tmp_path / "mid.journal")
    s.save_journal(path)
    _same(ref, sg.Scene.replay(path).render(spp=4, seed=2))
    # Only what the frame did after the state is recorded, besides the state itself.
    text = open(path).read()
    assert text.count('kind="commit"') == 1 and 'kind="slot_counts"' in text


def test_extensions_are_embedded_and_need_consent_to_replay(tmp_path):
    s = sg.Scene()
    s.begin_journal()
    s.load_extension(extensions.example("shapes"))
    s.add_instance(s.add_shape("torus", {"major_radius": 0.5, "minor_radius": 0.2}), P.translate([0, 0.5, 0]),
                   class_id=1)
    s.add_light("sun", {"direction": [0.2, 1.0, -0.3], "irradiance": 2.0})
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 64, 48, sg.PinholeCamera.look_at((0, 1.5, -3), (0, 0.4, 0),
                                                                                   (0, 1, 0))))
    ref = s.render(spp=4, seed=1)
    path = str(tmp_path / "ext.journal")
    s.save_journal(path)
    exts = sg.journal.journal_extensions(path)
    assert [os.path.basename(e["source"]) for e in exts] == ["shapes.c"]
    assert bytes(exts[0]["text"]) == open(extensions.example("shapes"), "rb").read()
    with pytest.raises(sg.SynthgenError, match=r"needs the C extensions shapes\.c .*--allow-extensions"):
        sg.journal.replay(path)
    r, settings = sg.journal.replay(path, allow_extensions=True)
    _same(ref, r.render(**settings))


def test_bad_journals_name_the_file_and_operation(tmp_path):
    s = sg.Scene()
    s.begin_journal()
    _mesh(s, P.box((1.0, 1.0, 1.0)))
    path = str(tmp_path / "bad.journal")
    s.save_journal(path)
    with open(path + ".bin", "r+b") as f:
        f.truncate(100)
    with pytest.raises(sg.FileError, match=r"bad\.journal.*operation 1 \(add_mesh 0\).*truncated"):
        sg.Scene.replay(path)
    (tmp_path / "op.journal").write_text('<synthgen_journal version="1" bin="bad.journal.bin">'
                                         '<op kind="explode" id="0"/></synthgen_journal>')
    with pytest.raises(sg.FileError, match=r"op\.journal.*unknown operation 'explode'"):
        sg.Scene.replay(str(tmp_path / "op.journal"))
    (tmp_path / "v.journal").write_text('<synthgen_journal version="7" bin="x"/>')
    with pytest.raises(sg.FileError, match=r"journal version 7"):
        sg.Scene.replay(str(tmp_path / "v.journal"))
    with pytest.raises(sg.SynthgenError, match=r"not recording"):
        sg.Scene().save_journal(str(tmp_path / "none.journal"))


def test_run_journals_replay_to_the_frames_images(tmp_path):
    from synthgen import run as runner

    out = str(tmp_path / "ds")
    s = runner.run(TINY, out, count=2, progress=False, journal=True)
    assert s["rendered"] == 2 and not s["failures"], s.text()
    for k in range(2):
        path = os.path.join(out, "journals", f"{k:06d}.journal")
        scene, settings = sg.journal.replay(path)
        r = scene.render(**settings)
        exr = sg.read_image(os.path.join(out, "images", f"{k:06d}.exr"))
        assert np.array_equal(np.asarray(r.rgb), exr[..., :3]), k
        depth = sg.read_image(os.path.join(out, "depth", f"{k:06d}.exr"), finite=False)
        assert np.array_equal(np.asarray(r.depth), depth[..., 0]), k


def test_a_failed_frame_leaves_a_journal_that_replays_the_failure(tmp_path):
    """A frame failing inside a worker (here: a user texture returning NaN) leaves its scene's
    journal; `synthgen replay` in a fresh process fails the same way."""
    from synthgen import run as runner

    src = tmp_path / "nan.c"
    src.write_text("#include <synthgen_ext.h>\n#include <math.h>\n"
                   "static void f(const sg_ext_point* q, const float* a, const sg_ext_host* h, float* out) {\n"
                   "  out[0] = q->p[0] < -0.01f ? NAN : 0.5f; }\n"  # the average's points are >= 0
                   "static const sg_ext_texture t[] = {{\"nan_albedo\", \"d\", 1, 0, 0, 0, f, 0}};\n"
                   "SG_EXT_EXPORT const sg_ext_library* synthgen_extension(void) {\n"
                   "  static const sg_ext_library l = {SG_EXT_ABI_VERSION, t, 1, 0, 0}; return &l; }\n")
    text = open(TINY, encoding="utf-8").read().replace(
        "material: {type: diffuse, albedo: {uniform: [[0.2, 0.2, 0.2], [0.5, 0.5, 0.5]]}}",
        "material: {type: diffuse, albedo: {texture: {type: nan_albedo}}}")
    scenario = tmp_path / "nan.yaml"
    scenario.write_text(text + f"allow_extensions: true\nextensions: [{src}]\n")
    out = str(tmp_path / "ds2")
    s = runner.run(str(scenario), out, count=1, progress=False, allow_extensions=True)
    assert len(s["failures"]) == 1
    f = s["failures"][0]
    assert "returned NaN" in f["error"] and f["journal"].endswith("failed/000000.journal"), f
    assert "synthgen replay" in s.text()
    env = dict(os.environ)
    proc = subprocess.run([sys.executable, "-m", "synthgen", "replay", f["journal"], "-o", str(tmp_path / "r"),
                           "--allow-extensions"], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode != 0 and "returned NaN" in proc.stderr, proc.stderr
