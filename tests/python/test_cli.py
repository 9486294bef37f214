"""The synthgen command: render / demo / schema / --version / --help, exit statuses and
one-line errors."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

import synthgen
from synthgen import cli
from synthgen import SceneFileError
from synthgen.outputs.render import OUTPUT_FILES

TINY = textwrap.dedent("""\
    camera: {width: 32, height: 24, fov_y: 45, look_at: {eye: [0, 1.5, -4], target: [0, 0.5, 0]}}
    materials: {red: {type: diffuse, albedo: [0.8, 0.1, 0.1]}}
    objects:
      - {name: ball, primitive: sphere, radius: 0.5, translate: [0, 0.5, 0], material: red, class_id: 2}
      - {name: floor, primitive: plane, size: 10, class_id: 1}
    lights:
      - {type: sun, direction: [0.3, 1, 0.2], irradiance: 3}
      - {type: environment, radiance: 0.3}
    render: {spp: 4, seed: 5}
    """)


def run(*args, cwd=None):
    """Runs the command in a fresh interpreter (real exit status, stdout and stderr)."""
    return subprocess.run([sys.executable, "-m", "synthgen", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=120)


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.yaml"
    p.write_text(TINY)
    return p


def test_version():
    r = run("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"synthgen {synthgen.__version__}"


def test_console_script_is_installed():
    exe = Path(sys.executable).with_name("synthgen")
    if not exe.exists():
        pytest.skip(f"console script not installed next to {sys.executable}")
    r = subprocess.run([str(exe), "--version"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and synthgen.__version__ in r.stdout


def test_render_writes_every_file(tiny, tmp_path):
    out = tmp_path / "out"
    r = run("render", tiny, "-o", out)
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(out)) == sorted(OUTPUT_FILES)
    for name in OUTPUT_FILES:
        assert f"wrote {out / name}" in r.stdout
    assert "samples/s" in r.stdout and "rays/s" in r.stdout and "rendered in" in r.stdout
    meta = json.loads((out / "meta.json").read_text())
    assert meta["settings"]["spp"] == 4 and meta["seed"] == 5
    assert meta["stats"]["samples"] == 32 * 24 * 4
    assert [o["name"] for o in meta["scene"]["objects"]] == ["ball", "floor"]
    buf = oiio.ImageBuf(str(out / "class.png"))
    assert buf.spec().format == oiio.UINT16 and (buf.spec().width, buf.spec().height) == (32, 24)
    assert set(np.unique(buf.get_pixels(oiio.UINT16))) == {0, 1, 2}


def test_flags_override_the_yaml(tiny, tmp_path, capsys):
    out = tmp_path / "o"
    assert cli.main(["render", str(tiny), "-o", str(out), "--spp", "2", "--seed", "9", "--max-depth", "3",
                     "--threads", "1", "--rr-depth", "2"]) == 0
    meta = json.loads((out / "meta.json").read_text())
    assert {k: meta["settings"][k] for k in ("spp", "seed", "max_depth", "threads", "rr_depth")} == \
        {"spp": 2, "seed": 9, "max_depth": 3, "threads": 1, "rr_depth": 2}
    assert meta["stats"]["samples"] == 32 * 24 * 2 and meta["stats"]["threads"] == 1
    assert "2 spp" in capsys.readouterr().out


def test_default_output_directory(tiny, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["render", str(tiny), "--spp", "1"]) == 0
    assert sorted(os.listdir(tmp_path / "out" / "tiny")) == sorted(OUTPUT_FILES)


def test_demo(tmp_path, capsys):
    out = tmp_path / "demo"
    assert cli.main(["demo", "-o", str(out), "--width", "48", "--height", "32", "--spp", "1"]) == 0
    assert sorted(os.listdir(out)) == sorted(OUTPUT_FILES)
    meta = json.loads((out / "meta.json").read_text())
    assert (meta["camera"]["width"], meta["camera"]["height"]) == (48, 32)
    assert meta["scene"]["classes"] == {"1": "ground", "2": "sphere", "3": "box"}
    ids = oiio.ImageBuf(str(out / "class.png")).get_pixels(oiio.UINT16)
    assert {1, 2, 3} <= set(np.unique(ids))
    assert "demo: 7 objects, 1 light, 48x32" in capsys.readouterr().out


def test_demo_default_output_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["demo", "--width", "16", "--height", "12", "--spp", "1"]) == 0
    assert (tmp_path / "out" / "demo" / "meta.json").is_file()


def test_bad_yaml_exits_2_with_location(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(TINY.replace("class_id: 2", "clas_id: 2"))
    r = run("render", bad, "-o", tmp_path / "o")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr
    assert f"{bad}:4:" in lines[0] and "did you mean 'class_id'?" in lines[0]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("args, fragment", [
    (["render", "{tmp}/absent.yaml"], "cannot read the scene file"),
    (["render", "{tmp}/tiny.yaml", "--seed", str(1 << 64)], "command line: render.seed"),
    (["demo", "--width", "70000", "-o", "{tmp}/d"], "camera.width"),
])
def test_input_errors_exit_2(tiny, tmp_path, capsys, args, fragment):
    assert cli.main([a.format(tmp=tmp_path) for a in args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("synthgen: error: ") and fragment in err and len(err.strip().splitlines()) == 1


def test_debug_shows_the_exception(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("camera: {}\n")
    with pytest.raises(SceneFileError):
        cli.main(["--debug", "render", str(bad)])
    with pytest.raises(SceneFileError):
        cli.main(["render", str(bad), "--debug"])
    r = run("render", bad, "--debug")
    assert r.returncode != 0 and "Traceback" in r.stderr and "SceneFileError" in r.stderr


@pytest.mark.parametrize("args", [["--help"], ["render", "--help"], ["demo", "--help"], ["schema", "--help"]])
def test_help_on_every_command(args, capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(args)
    assert info.value.code == 0
    assert "usage: synthgen" in capsys.readouterr().out


def test_usage_errors_exit_2(capsys):
    assert cli.main([]) == 2
    for args in (["render"], ["render", "x.yaml", "--spp", "0"], ["frobnicate"]):
        with pytest.raises(SystemExit) as info:
            cli.main(args)
        assert info.value.code == 2


def test_schema_command(capsys):
    assert cli.main(["schema"]) == 0
    out = capsys.readouterr().out
    assert "fov_y: number in (0, 180)" in out and "[type: sun]" in out


def test_demo_shows_metal_glass_and_coated_under_a_sun_and_sky():
    """The materials issue: the demo shows at least a metal, a glass and a coated object
    under a physical sun-sky."""
    from synthgen.scene.demo import DEMO_SCENE

    used = {o["material"] for o in DEMO_SCENE["objects"]}
    types = {DEMO_SCENE["materials"][m]["type"] for m in used}
    assert {"conductor", "dielectric", "coated"} <= types
    assert any(l["type"] == "sky" for l in DEMO_SCENE["lights"])
