"""``synthgen bench``: the quick mode's outputs (chart, table, last line), the scene-name error,
and the time-to-target / speedup arithmetic (synthgen.bench.speed)."""
from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys

import pytest

from synthgen.bench.speed import METHODS, SCENES, speedup_vs_cycles, time_to_target
from synthgen.cli.bench import QUICK

LAST_LINE = re.compile(r"^time_to_35db_speedup_vs_cycles=(nan|[0-9]+\.[0-9]+)$")


def run(*args):
    return subprocess.run([sys.executable, "-m", "synthgen", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


def table_rows(path):
    """The rows of the first table of benchmarks_table.md as dicts."""
    lines = [l for l in path.read_text().splitlines() if l.startswith("|")]
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    rows = []
    for l in lines[2:]:
        cells = [c.strip() for c in l.strip("|").split("|")]
        if cells[0] == "scene":  # the second table starts
            break
        rows.append(dict(zip(head, cells)))
    return rows


def check_outputs(out, r, scene):
    import OpenImageIO as oiio

    assert r.returncode == 0, r.stderr + r.stdout
    png = out / "speed_accuracy.png"
    spec = oiio.ImageInput.open(str(png))
    assert spec is not None, oiio.geterror()
    assert spec.spec().width > 100 and spec.spec().height > 100 and spec.format_name() == "png"
    spec.close()
    rows = table_rows(out / "benchmarks_table.md")
    assert rows and all(row["scene"] == scene for row in rows)
    budgets = [f"{b} spp" for b in QUICK["budgets"]]
    by_method = {}
    for row in rows:
        by_method.setdefault(row["method"], []).append(row)
    assert {"uniform", "adaptive"} <= set(by_method)
    for name, mrows in by_method.items():
        assert [row["budget"] for row in mrows] == budgets, name
        assert all(float(row["seconds"]) > 0 for row in mrows)
    uniform = [float(row["PSNR (dB)"]) for row in by_method["uniform"]]
    assert all(b > a for a, b in zip(uniform, uniform[1:])), uniform
    lines = r.stdout.strip().splitlines()
    assert LAST_LINE.match(lines[-1]), lines[-1]
    assert "time to 35 dB" in r.stdout
    return by_method, lines[-1]


def test_quick_synthgen_only(tmp_path):
    """--no-peers: synthgen's methods, a row per method and budget, nan as the speedup; the
    denoise method runs or is skipped with a printed reason."""
    out = tmp_path / "bench"
    r = run("bench", "--quick", "--no-peers", "--scenes", "sunlit", "-o", out)
    by_method, last = check_outputs(out, r, "sunlit")
    assert set(by_method) <= {m.name for m in METHODS if m.renderer == "synthgen"}
    assert last == "time_to_35db_speedup_vs_cycles=nan"
    assert "adaptive+denoise" in by_method or "adaptive+denoise: skipped" in r.stdout
    assert "peers: skipped (--no-peers)" in r.stdout


@pytest.mark.skipif(shutil.which("blender") is None, reason="blender not installed")
def test_quick_with_cycles(tmp_path):
    """With Blender: a Cycles row per budget as well; the last line is a float or nan."""
    out = tmp_path / "bench"
    r = run("bench", "--quick", "--scenes", "sunlit", "-o", out)
    by_method, _ = check_outputs(out, r, "sunlit")
    assert "cycles" in by_method


def test_bad_scene_names_the_valid_ones():
    r = run("bench", "--scenes", "sunlit,nope")
    assert r.returncode == 2
    assert "nope" in r.stderr and all(s in r.stderr for s in SCENES), r.stderr


def test_time_to_target_interpolates_in_log_time():
    t, status = time_to_target([(1.0, 20.0), (2.0, 30.0), (8.0, 40.0)], 35.0)
    assert status == "interpolated" and t == pytest.approx(4.0)  # halfway between 2 and 8 in log time
    assert time_to_target([(1.0, 36.0), (2.0, 40.0)], 35.0) == (1.0, "at_first_budget")
    assert time_to_target([(1.0, 20.0), (2.0, 30.0)], 35.0) == (None, "not_reached")


def test_speedup_is_a_geometric_mean_of_bracketed_scenes():
    ttt = {"a": {"uniform": (2.0, "interpolated"), "adaptive": (1.0, "interpolated"), "cycles": (4.0, "interpolated")},
           "b": {"uniform": (1.0, "interpolated"), "cycles": (16.0, "interpolated")},
           "c": {"uniform": (1.0, "interpolated"), "cycles": (None, "not_reached")},
           "d": {"uniform": (1.0, "at_first_budget"), "cycles": (3.0, "interpolated")},
           "e": {"uniform": (1.0, "interpolated")}}
    s, notes = speedup_vs_cycles(ttt)
    assert s == pytest.approx(math.sqrt(4.0 * 16.0))
    assert len(notes) == len(ttt)
    s, _ = speedup_vs_cycles({"e": ttt["e"]})
    assert math.isnan(s)
