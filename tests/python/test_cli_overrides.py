"""``synthgen run|validate --spp --resolution --seed --set KEY=VALUE``: scenario values from
the command line, validated like the file's, recorded in the run (manifest, metadata)."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

import synthgen as sg
from synthgen.scenario.load import load_scenario, parse_override

SCENARIO = """seed: 1
count: 2
resolution: [64, 48]
camera: {pose: {type: orbit, distance: 5}}
objects:
  - {class: box, primitive: box, count: 1}
render: {spp: 2, max_depth: 2}
outputs: [rgb, semantic]
"""


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "synthgen", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=300)


def test_run_with_overrides_renders_what_they_say(tmp_path):
    (tmp_path / "s.yaml").write_text(SCENARIO)
    r = _cli("run", "s.yaml", "-o", "ds", "--no-progress", "--spp", "3", "--resolution", "40x30", "--seed", "9",
             "--set", "objects[0].count=2", "--set", "camera.fov_y={uniform: [40, 41]}", cwd=tmp_path)
    assert r.returncode == 0, r.stderr + r.stdout
    meta = json.loads((tmp_path / "ds" / "meta" / "000000.json").read_text())
    assert meta["image_size"] == [40, 30] and meta["render"]["spp"] == 3 and meta["scenario_seed"] == 9
    assert len(meta["objects"]) == 2
    assert 40 <= meta["sampled"]["camera.fov_y"] <= 41
    # The overrides are part of the scenario: resuming with other values is refused.
    r = _cli("run", "s.yaml", "-o", "ds", "--no-progress", "--resume", "--spp", "4", "--resolution", "40x30",
             "--seed", "9", "--set", "objects[0].count=2", "--set", "camera.fov_y={uniform: [40, 41]}", cwd=tmp_path)
    assert r.returncode == 2 and "render.spp" in r.stderr, r.stderr


def test_bad_overrides_are_named(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text(SCENARIO)
    with pytest.raises(sg.SynthgenError, match=r"s.yaml \(--set render.spp\): render.spp: value 0 is out of range"):
        load_scenario(p, [("render.spp", 0)])
    with pytest.raises(sg.SynthgenError, match=r"objects\[3\].count: --set: there is no item 3 here"):
        load_scenario(p, [parse_override("objects[3].count=2")])
    with pytest.raises(sg.SynthgenError, match=r"rendr: unknown key.*did you mean 'render'"):
        load_scenario(p, [parse_override("rendr.spp=2")])
    with pytest.raises(sg.SynthgenError, match=r"expected KEY.PATH=VALUE"):
        parse_override("render.spp")
    r = _cli("validate", "s.yaml", "--resolution", "64by48", cwd=tmp_path)
    assert r.returncode == 2 and "expected WIDTHxHEIGHT" in r.stderr
    r = _cli("validate", "s.yaml", "--set", "resolution=[20000, 10]", cwd=tmp_path)
    assert r.returncode == 2 and "resolution" in r.stderr and "16384" in r.stderr, r.stderr
