"""The texture resolution estimate from Python and ``synthgen texres`` (docs/texture_lod.md):
a textured square seen head-on, whose footprint is the same at every pixel and known in
closed form; a scenario's frame; the table's totals."""
from __future__ import annotations

import math
import textwrap

import numpy as np
import OpenImageIO as oiio
import pytest

from synthgen import cli
from synthgen.scene.scene_file import load_scene
from synthgen.scene.texture_lod import memory_totals, pyramids

N = 512            # texture side, texels
SIDE = 6.0         # the square's side, metres (wider than the view)
HEIGHT = 5.0       # the camera's height above it, metres
W, H, FOV = 160, 120, 40.0


def scene_file(tmp_path, mirror: bool = False):
    tex = (np.arange(N * N * 3) % 251).reshape(N, N, 3).astype(np.uint8)
    out = oiio.ImageOutput.create(str(tmp_path / "checker.png"))
    out.open(str(tmp_path / "checker.png"), oiio.ImageSpec(N, N, 3, oiio.UINT8))
    out.write_image(tex)
    out.close()
    p = tmp_path / "scene.yaml"
    p.write_text(textwrap.dedent(f"""\
        camera: {{width: {W}, height: {H}, fov_y: {FOV}, look_at: {{eye: [0, {HEIGHT}, 0], target: [0, 0, 0],
                  up: [0, 0, 1]}}}}
        textures: {{checker: {{type: image, file: checker.png}}, unused: {{type: image, file: checker.png,
                   uv_scale: 3}}}}
        materials: {{tex: {{type: diffuse, albedo: {{texture: checker}}}}}}
        objects: [{{primitive: plane, size: {SIDE}, class_id: 1, material: tex}}]
        """))
    return p


def test_head_on_square_needs_the_level_of_its_closed_form_footprint(tmp_path):
    scene, _, _ = load_scene(scene_file(tmp_path))
    est = scene.estimate_texture_resolution()
    # Looking straight down at the plane y = 0 every pixel step moves HEIGHT / f metres on it
    # (f = H / 2 / tan(fov / 2) pixels): N / SIDE * HEIGHT / f texels, at every pixel.
    f = H / 2 / math.tan(math.radians(FOV / 2))
    rho = N / SIDE * HEIGHT / f
    level = math.floor(math.log2(rho))
    t = {r["texture_id"]: r for r in est["textures"]}
    checker = t[0]
    print(f"head-on square: {checker['min_rho']:.4f} texels per pixel (closed form {rho:.4f}), "
          f"level {checker['needed_level']}")
    assert checker["seen"] and checker["lookups"] == W * H
    assert checker["min_rho"] == pytest.approx(rho, rel=1e-4)
    assert checker["needed_level"] == level == 1
    assert (checker["needed_width"], checker["needed_height"]) == (N >> level, N >> level)
    assert est["camera_rays"] == W * H and est["bounce_rays"] == 0
    # The same file under another uv transform shares the pyramid (one decode), but is not
    # looked up itself: its own level is 0, the pyramid's is the checker's.
    assert t[1]["pyramid"] == checker["pyramid"] and t[1]["needed_level"] == level and t[1]["texture_level"] == 0
    # Memory: every level of a 512^2 RGB float pyramid, then levels 1..9.
    full = sum((N >> k) ** 2 for k in range(10)) * 3 * 4
    assert checker["bytes_full"] == full
    assert checker["bytes_needed"] == full - N * N * 3 * 4
    p = pyramids(est)
    assert len(p) == 1 and p[0]["texture_ids"] == [0, 1]
    m = memory_totals(est)
    assert m["bytes_full"] == full and m["ratio"] == pytest.approx(full / (full - N * N * 12))


def test_cli_prints_the_table_for_a_scene_file(tmp_path, capsys):
    assert cli.main(["texres", str(scene_file(tmp_path))]) == 0
    out = capsys.readouterr().out
    print(out)
    row = next(line for line in out.splitlines() if line.startswith("checker.png"))
    assert row.split()[1:] == ["0,1", "512x512", "10", "yes", row.split()[5], "1", "256x256", "16/16", "4.00", "1.00"]
    assert "1 pyramids: 4.00 MiB at full resolution, 1.00 MiB needed (ratio 4.00)" in out


def test_cli_estimates_a_scenario_frame(tmp_path, capsys):
    # Road signs: generated sign faces (in-memory images) on posts, seen from the scenario's camera.
    assert cli.main(["texres", "scenarios/road_signs.yaml", "--frame", "1"]) == 0
    out = capsys.readouterr().out
    print(out)
    assert out.startswith("scenarios/road_signs.yaml frame 1: ")
    assert "pyramids:" in out and "camera rays" in out
    rows = [line for line in out.splitlines() if line.startswith("memory:")]
    assert rows and any(line.split()[4] == "yes" for line in rows)
