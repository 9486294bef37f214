"""Resource limits are checked in validation, fast, with the limit in the message; every
defaulted key renders; a scalar range on a colour draws a grey; --debug shows tracebacks."""
import os
import time

import numpy as np
import pytest

from synthgen import SceneFileError, build_scene, cli
from synthgen.frame import FrameRenderer
from synthgen.scenario import load_scenario, parse_scenario, sample_frame
from synthgen.schema import limits
from synthgen.schema.yaml_io import parse_yaml


def write(tmp_path, text):
    p = tmp_path / "s.yaml"
    p.write_text(text)
    return str(p)


def test_alias_bomb_is_refused_fast(tmp_path):
    lines = ["a0: &a0 {choice: [1, 1, 1, 1, 1, 1, 1, 1, 1]}"]
    for i in range(1, 9):
        lines.append(f"a{i}: &a{i} {{choice: [" + ", ".join([f"*a{i - 1}"] * 9) + "]}")
    text = "\n".join(lines) + "\nobjects: [{class: a, primitive: box, count: *a8}]\n"
    assert len(text) < 1000
    t0 = time.perf_counter()
    with pytest.raises(SceneFileError, match=f"more than {limits.MAX_YAML_VALUES:,} values"):
        load_scenario(write(tmp_path, text))
    assert time.perf_counter() - t0 < 1.0


def test_objects_per_frame_are_bounded(tmp_path):
    entries = ", ".join(f"{{class: c{i}, primitive: box, count: {{int: [0, 1000]}}}}" for i in range(11))
    with pytest.raises(SceneFileError, match="up to 11000 object instances per frame.*at most 10,000"):
        load_scenario(write(tmp_path, f"objects: [{entries}]\n"))


def test_memory_of_a_frame_is_checked(tmp_path, monkeypatch):
    monkeypatch.setattr(limits, "available_memory", lambda: 4 << 30)
    with pytest.raises(SceneFileError, match=r"resolution: 8192 x 8192 pixels need about 25.0 GiB.*4.0 GiB available"):
        load_scenario(write(tmp_path, "resolution: [8192, 8192]\nobjects: [{class: a, primitive: box}]\n"))
    with pytest.raises(SceneFileError, match=r"camera: 65536 x 65536 pixels need"):
        build_scene({"camera": {"width": 65536, "height": 65536, "look_at": {"eye": [0, 0, -3], "target": [0, 0, 0]}},
                     "objects": [{"primitive": "box", "class_id": 1}]})
    # Workers of a local run share the memory.
    from synthgen import SynthgenError
    from synthgen import run as runner

    path = write(tmp_path, "resolution: [2048, 2048]\nobjects: [{class: a, primitive: box}]\n")
    with pytest.raises(SynthgenError, match="x 4 workers"):
        runner.run(path, str(tmp_path / "ds"), count=1, workers=4, progress=False)


def test_every_defaulted_key_renders():
    text = "objects: [{class: a, primitive: box}]\nresolution: [48, 36]\nrender: {spp: 1, max_depth: 2}\n"
    sc = parse_scenario(parse_yaml(text), "min.yaml", os.getcwd(), text)
    arrays, meta, _ = FrameRenderer(sc).render(0)
    assert (arrays["instance_id"] == 1).sum() > 0 and np.isfinite(arrays["rgb"]).all()
    assert meta["lights"] == [{"type": "sky", "params": {"strength": 0.02}}]


def test_a_scalar_range_on_a_colour_draws_a_grey():
    text = ("objects: [{class: a, primitive: box, size: {uniform: [0.2, 1]},\n"
            "           material: {type: diffuse, albedo: {uniform: [0.2, 0.8]}}},\n"
            "          {class: b, primitive: box, material: {type: diffuse, albedo: {uniform: [[0, 0, 0], [1, 1, 1]]}}}]\n")
    sc = parse_scenario(parse_yaml(text), "c.yaml", os.getcwd(), text)
    for k in range(5):
        f = sample_frame(sc, k)
        grey = f.objects[0].material.params["albedo"]
        assert grey[0] == grey[1] == grey[2] and 0.2 <= grey[0] <= 0.8
        assert f.objects[0].size[0] == f.objects[0].size[1] == f.objects[0].size[2]
        rgb = f.objects[1].material.params["albedo"]
        assert len(set(rgb)) == 3, "vector bounds draw each channel"


def test_debug_shows_tracebacks_only_when_asked(tmp_path, capsys):
    path = write(tmp_path, "objects: [{class: a, primitive: box}]\nresolution: [16, 12]\nrender: {spp: 1}\n"
                           "placement: {min_pixels: 100000}\n")
    # (no traceback without --debug on an input error: one line)
    assert cli.main(["run", str(tmp_path / "nope.yaml"), "-o", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("synthgen: error:") and "Traceback" not in err
    with pytest.raises(SceneFileError):
        cli.main(["--debug", "run", str(tmp_path / "nope.yaml"), "-o", str(tmp_path / "x")])


def test_debug_shows_a_failed_frames_traceback(tmp_path, capsys, monkeypatch):
    from synthgen import SynthgenError

    def broken(self, frame):
        raise SynthgenError("frame trouble")

    monkeypatch.setattr(FrameRenderer, "render", broken)
    path = write(tmp_path, "objects: [{class: a, primitive: box}]\nresolution: [16, 12]\n")
    # (--in-process: the monkeypatch is in this process)
    assert cli.main(["run", path, "-o", str(tmp_path / "a"), "-n", "1", "--no-progress", "--in-process"]) == 1
    out = capsys.readouterr().out
    assert "frame trouble" in out and "Traceback" not in out
    assert cli.main(["--debug", "run", path, "-o", str(tmp_path / "b"), "-n", "1", "--no-progress",
                     "--in-process"]) == 1
    out = capsys.readouterr().out
    assert "Traceback" in out and "in broken" in out
