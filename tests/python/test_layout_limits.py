"""Layout failures are failures: visibility limits per object entry, and objects that still
break them after the retries are reported (summary, metadata, exit status), never silently."""
import json
import os

import pytest

from synthgen import cli
from synthgen import run as runner

BASE = """
seed: 4
resolution: [64, 48]
camera: {fov_y: 40, pose: {type: orbit, target: [0, 0.4, 0], distance: 7, elevation: 15}}
lights: [{type: environment, radiance: 1}]
objects:
  - {class: big, primitive: box, size: 1.2, count: 1}
  - {class: small, primitive: box, size: 0.3, count: 2%s}
placement: {region: [-1.5, -1.5, 1.5, 1.5], max_retries: 3, min_pixels: 2}
render: {spp: 1, max_depth: 1}
"""


def write(tmp_path, extra=""):
    p = tmp_path / "s.yaml"
    p.write_text(BASE % extra)
    return str(p)


def test_limits_are_per_entry_and_drops_are_reported(tmp_path, capsys):
    # The small boxes must be at most 20% visible (i.e. mostly hidden): rarely possible, so
    # some are dropped -- and the big box, with no such limit, never is.
    scen = write(tmp_path, ", max_visible_fraction: 0.2")
    out = str(tmp_path / "ds")
    s = runner.run(scen, out, count=3, progress=False)
    assert not s["failures"]
    assert s["dropped"], "objects that break their limits are reported"
    for d in s["dropped"]:
        assert all(o["class"] == "small" and "visible" in o["reason"] for o in d["objects"])
        with open(os.path.join(out, "meta", f"{d['frame']:06d}.json")) as f:
            meta = json.load(f)
        dropped = [o for o in meta["objects"] if o.get("dropped")]
        assert [o["index"] for o in dropped] == [o["index"] for o in d["objects"]]
    assert "objects dropped" in s.text()
    # The command's exit status says so (3: written, with objects dropped).
    assert cli.main(["run", scen, "-o", str(tmp_path / "ds2"), "-n", "3", "--no-progress"]) == 3
    assert "objects dropped" in capsys.readouterr().out
    # Unless the scenario expects drops (crowded photos): reported, exit status 0.
    assert cli.main(["run", scen, "-o", str(tmp_path / "ds3"), "-n", "3", "--no-progress",
                     "--set", "placement.allow_drops=true"]) == 0
    assert "(placement.allow_drops)" in capsys.readouterr().out


def test_a_run_without_drops_exits_0(tmp_path):
    scen = write(tmp_path)
    assert cli.main(["run", scen, "-o", str(tmp_path / "ds"), "-n", "2", "--no-progress"]) == 0


def test_limits_are_checked_per_entry(tmp_path):
    from synthgen import SceneFileError
    from synthgen.scenario import load_scenario

    with pytest.raises(SceneFileError, match="max_visible_fraction 0.1 < min_visible_fraction 0.5"):
        load_scenario(write(tmp_path, ", min_visible_fraction: 0.5, max_visible_fraction: 0.1"))
