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


# Files a journal names: recorded by content (sha256), small ones embedded, large ones in the
# resource store ($SYNTHGEN_CACHE/resources) ------------------------------------------------

def _resources(path):
    """The <resource> elements of a journal: [(operation type, {attributes})]."""
    import xml.etree.ElementTree as ET

    return [(op.get("type"), dict(r.attrib)) for op in ET.parse(path).getroot().iter("op")
            for r in op.iter("resource")]


def _envmap_scene(map_path, rgb):
    from synthgen.outputs.files import write_exr

    write_exr(map_path, rgb)
    s = sg.Scene()
    s.begin_journal()
    ball = _mesh(s, P.uv_sphere(0.5, segments=24, rings=12))
    s.add_instance(ball, P.translate([0, 0.5, 0]), class_id=1,
                   material_id=s.add_material("conductor", {"metal": "silver", "roughness": 0.1}))
    s.add_light("envmap", {"file": map_path, "strength": 1.5})
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 48, 32, sg.PinholeCamera.look_at((0, 1.0, -3), (0, 0.5, 0),
                                                                                   (0, 1, 0))))
    return s


def test_a_small_file_is_embedded_and_replays_after_it_is_gone(tmp_path):
    rgb = np.random.default_rng(1).random((16, 32, 3)).astype(np.float32)
    m = str(tmp_path / "sky.exr")
    s = _envmap_scene(m, rgb)
    ref = s.render(spp=4, seed=3)
    path = str(tmp_path / "small.journal")
    s.save_journal(path)
    from synthgen.scene.assets import file_sha256

    sha, size = file_sha256(m), os.path.getsize(m)
    os.remove(m)
    scene, settings = sg.journal.replay(path)
    _same(ref, scene.render(**settings))
    (kind, r), = _resources(path)
    assert kind == "envmap" and r["param"] == "file" and r["path"] == m and r["sha256"] == sha
    assert "offset" in r and int(r["size"]) == size <= 1 << 20


def test_a_large_file_is_stored_by_its_hash_and_a_missing_one_is_named(tmp_path):
    rgb = np.random.default_rng(2).random((384, 768, 3)).astype(np.float32)  # noise: > 1 MiB compressed
    m = str(tmp_path / "big.exr")
    s = _envmap_scene(m, rgb)
    ref = s.render(spp=2, seed=3)
    path = str(tmp_path / "big.journal")
    s.save_journal(path)
    from synthgen.scene.assets import file_sha256

    sha = file_sha256(m)
    os.remove(m)
    scene, settings = sg.journal.replay(path)  # from the store
    _same(ref, scene.render(**settings))
    (_, r), = _resources(path)
    assert r["sha256"] == sha and int(r["size"]) > 1 << 20 and "offset" not in r and r["store"] == "cache"
    stored = os.path.join(os.environ["SYNTHGEN_CACHE"], "resources", sha + ".exr")
    assert os.path.isfile(stored)
    os.remove(stored)
    with pytest.raises(sg.FileError) as e:
        sg.journal.replay(path)
    msg = str(e.value)
    assert all(x in msg for x in ("big.journal", "add_light", "envmap parameter 'file'", m, r["sha256"], "missing",
                                  stored)), msg
    # A file found at the recorded path with other content is a changed scene, not a replay.
    from synthgen.outputs.files import write_exr

    write_exr(m, rgb[::-1].copy())
    with pytest.raises(sg.FileError, match=r"has changed since the journal was written"):
        sg.journal.replay(path)
    write_exr(m, rgb)  # the same content again: found by its path
    scene, settings = sg.journal.replay(path)
    _same(ref, scene.render(**settings))


def test_hostile_resources_are_refused(tmp_path):
    m = str(tmp_path / "sky.exr")
    s = _envmap_scene(m, np.full((8, 16, 3), 0.5, np.float32))
    path = str(tmp_path / "h.journal")
    s.save_journal(path)
    text = open(path).read()
    (_, r), = _resources(path)
    for old, new, error in [
            (r["sha256"], "../../../etc/passwd", r"sha256 '\.\./\.\./\.\./etc/passwd' is not 64 lowercase hex"),
            (f'size="{r["size"]}"', 'size="99999999999"', r"embedded file of 99999999999 bytes \(at most 1048576"),
            (r["sha256"], "0" * 64, r"embedded copy does not have its recorded sha256"),
            ('param="file"', 'param="strength"', r"not a file parameter")]:
        (tmp_path / "bad.journal").write_text(text.replace(old, new))
        with pytest.raises(sg.FileError, match=error):
            sg.Scene.replay(str(tmp_path / "bad.journal"))


def test_a_file_unreadable_when_the_journal_is_written_is_named_at_replay(tmp_path):
    m = str(tmp_path / "sky.exr")
    s = _envmap_scene(m, np.full((8, 16, 3), 0.5, np.float32))
    s.render(spp=1)
    os.remove(m)  # the light has its pixels; the journal cannot have them
    path = str(tmp_path / "gone.journal")
    s.save_journal(path)
    with pytest.raises(sg.FileError, match=r"gone\.journal: operation \d+ \(add_light 0\): envmap parameter 'file' "
                                           r"\(file '.*sky\.exr'\): the file could not be read when the journal was "
                                           r"written"):
        sg.journal.replay(path)


def _photo_scenario(tmp_path, material="{type: diffuse, albedo: [0.7, 0.1, 0.1]}", extra=""):
    """An augmented-photo scenario (the photo: a render of the empty world, 96 x 64)."""
    from synthgen.background.calibration import Calibration
    from synthgen.outputs.files import write_exr

    cal = dict(width=96, height=64, fx=85.0, fy=85.0, cx=48.0, cy=30.0, camera_height=1.6, pitch=6.0, roll=0.0)
    s = sg.Scene()
    s.add_instance(_mesh(s, P.ground()), np.eye(4), material_id=s.add_material("diffuse", {"albedo": 0.15}))
    s.add_light("sky", {"elevation": 35.0, "azimuth": 230.0, "strength": 0.02})
    s.set_camera(Calibration(**cal).camera())
    photos = tmp_path / "photos"
    photos.mkdir()
    write_exr(str(photos / "street.exr"), np.array(s.render(spp=16, seed=0).rgb))
    (photos / "calibration.yaml").write_text("intrinsics: {fx: 85.0, cx: 48.0, cy: 30.0}\n"
                                             "ground: {camera_height: 1.6, pitch: 6.0}\n"
                                             "sun: {azimuth: 230.0, elevation: 35.0}\nobjects: []\n")
    p = tmp_path / "aug.yaml"
    p.write_text(f"""seed: 5
count: 1
resolution: [96, 64]
background:
  photos: [photos]
  ground_albedo: 0.15
objects:
  - class: box
    primitive: box
    size: [1.6, 1.2, 1.6]
    material: {material}
render: {{spp: 4}}
{extra}""")
    return str(p)


def _dome(journal):
    """The photo's dome a photo frame's journal names: a temporary file of the run."""
    import xml.etree.ElementTree as ET

    files = [p.get("value") for op in ET.parse(journal).getroot().iter("op") if op.get("type") == "envmap"
             for p in op.iter("param") if p.get("name") == "file"]
    assert len(files) == 1 and os.path.basename(os.path.dirname(files[0])).startswith("synthgen-dome-"), files
    return files[0]


def test_a_photo_frames_journal_replays_after_the_runs_temporary_files_are_gone(tmp_path):
    import shutil

    from synthgen import run as runner

    out = str(tmp_path / "ds")
    s = runner.run(_photo_scenario(tmp_path), out, count=1, progress=False, journal=True)
    assert s["rendered"] == 1 and not s["failures"], s.text()
    path = os.path.join(out, "journals", "000000.journal")
    scene, settings = sg.journal.replay(path)
    before = scene.render(**settings)
    dome = _dome(path)
    shutil.rmtree(os.path.dirname(dome), ignore_errors=True)  # what the run's end does (atexit)
    assert not os.path.exists(dome)
    scene, settings = sg.journal.replay(path)
    _same(before, scene.render(**settings))


def test_a_failed_photo_frames_journal_replays_the_failure_after_the_run(tmp_path):
    """The journal the run summary tells users to replay (failed/) replays the frame's failure
    after the run's temporary dome is gone, in a fresh process -- not a missing file."""
    import shutil

    from synthgen import run as runner

    src = tmp_path / "nan.c"
    src.write_text("#include <synthgen_ext.h>\n#include <math.h>\n"
                   "static void f(const sg_ext_point* q, const float* a, const sg_ext_host* h, float* out) {\n"
                   "  out[0] = q->p[0] < -0.01f ? NAN : 0.5f; }\n"  # the average's points are >= 0
                   "static const sg_ext_texture t[] = {{\"nan_albedo\", \"d\", 1, 0, 0, 0, f, 0}};\n"
                   "SG_EXT_EXPORT const sg_ext_library* synthgen_extension(void) {\n"
                   "  static const sg_ext_library l = {SG_EXT_ABI_VERSION, t, 1, 0, 0}; return &l; }\n")
    scenario = _photo_scenario(tmp_path, "{type: diffuse, albedo: {texture: {type: nan_albedo}}}",
                               f"allow_extensions: true\nextensions: [{src}]\n")
    s = runner.run(scenario, str(tmp_path / "ds"), count=1, progress=False, allow_extensions=True)
    assert len(s["failures"]) == 1
    f = s["failures"][0]
    assert "returned NaN" in f["error"] and f["journal"].endswith("failed/000000.journal"), f
    dome = _dome(f["journal"])
    shutil.rmtree(os.path.dirname(dome), ignore_errors=True)
    assert not os.path.exists(dome)
    proc = subprocess.run([sys.executable, "-m", "synthgen", "replay", f["journal"], "-o", str(tmp_path / "r"),
                           "--allow-extensions"], capture_output=True, text=True, env=dict(os.environ), timeout=300)
    assert proc.returncode != 0 and "returned NaN" in proc.stderr, proc.stderr
