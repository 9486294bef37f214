"""Heterogeneous media (ground_fog, clouds, grid: cpp/medium/tracking.h) in renders: a non-absorbing
medium keeps the furnace, light sampling with MIS and without agree, renders are bit-identical for
1 and 2 threads and after an XML save / load, the scene file's ``medium`` key (a raw grid file
relative to the scene file), deterministic camera transmittance for labels, and errors naming the
file or key."""
import subprocess
import sys

import numpy as np
import pytest

import synthgen as sg

from medium_checks import furnace_mean, furnace_scene, light_sampling_on_and_off, mis_scene, street


def _blob_grid(n=10, half=3.0, seed=4):
    """Random voxel densities (a quarter empty) over [-half, half]^3: the 'grid' medium's params."""
    rng = np.random.default_rng(seed)
    v = rng.uniform(0.0, 1.5, n ** 3) * (rng.uniform(size=n ** 3) > 0.25)
    return {"data": v.tolist(), "resolution": [n, n, n], "bounds_min": [-half] * 3, "bounds_max": [half] * 3}


SMALL_FOG = {"visibility": 4.0, "scale_height": 1.0, "base": -3.0, "feature_size": 1.5, "feature_height": 1.0,
             "extent": 3.0, "coverage": 0.6, "majorant_cells": [16, 8, 16]}


@pytest.mark.parametrize("medium", ["grid", "ground_fog"])
def test_non_absorbing_heterogeneous_medium_keeps_the_furnace(medium):
    """Inside a closed sphere whose wall emits 1 and reflects 0.5 the radiance is 2 everywhere; a
    non-absorbing heterogeneous medium (albedo 1) only scatters that uniform field: still 2, within
    1.5% of the image mean."""
    s = furnace_scene()
    if medium == "grid":
        s.set_medium("grid", {**_blob_grid(), "visibility": 2.0, "albedo": 1.0, "g": 0.5})
    else:
        s.set_medium("ground_fog", {**SMALL_FOG, "albedo": 1.0, "g": 0.5})
    mean = furnace_mean(s)
    print(f"\nfurnace with a non-absorbing {medium} medium (expect 2): {mean:.4f}")
    assert abs(mean - 2.0) < 0.03, mean


def _mis_scene():
    return mis_scene("ground_fog", {"visibility": 8.0, "scale_height": 1.5, "feature_size": 3.0,
                                    "feature_height": 1.5, "extent": 30.0, "coverage": 0.6, "g": 0.5,
                                    "majorant_cells": [32, 8, 32]}, 48, 36)


def test_light_sampling_on_and_off_agree_in_ground_fog():
    """Energy with MIS on and off: patchy ground fog over a ground, a glossy box, a spherical emitter
    and a 10-degree sun under a uniform sky, rendered with next-event estimation (decoupled points by
    conditioned delta tracking, shadow rays by ratio tracking) and MIS (64 spp), and with BSDF and
    phase sampling alone (1024 spp): image means agree within 4 standard errors per channel."""
    (m1, s1, v1), (m0, s0, v0), z = light_sampling_on_and_off(_mis_scene())
    print(f"\nground fog, light sampling on: mean {m1.round(5)} +- {s1.round(5)}; off: {m0.round(5)} +- "
          f"{s0.round(5)}; z {z.round(2)}; per-sample variance off / on {float((v0 / v1).mean()):.1f}")
    assert (z < 4.0).all(), z
    assert (v1 < v0).all(), (v1, v0)


def _street():
    return street(48, 36)


MEDIA = {
    "ground_fog": {"visibility": 30.0, "scale_height": 2.0, "feature_size": 8.0, "extent": 100.0, "seed": 2},
    "clouds": {"visibility": 10.0, "bottom": 3.0, "top": 12.0, "feature_size": 8.0, "feature_height": 5.0,
               "extent": 60.0},
    "grid": {**_blob_grid(8, 4.0), "visibility": 3.0},
}


@pytest.mark.parametrize("medium", sorted(MEDIA))
def test_deterministic_across_threads_and_xml_round_trip(medium, tmp_path):
    """Bit-identical for 1 and 2 threads and after save / load; labels as without the medium; the
    camera transmittance (deterministic quadrature) is the same on every call and lies in [0, 1]."""
    s = _street()
    clear = s.render(spp=4, max_depth=4, seed=9)
    s.set_medium(medium, MEDIA[medium])
    a = s.render(spp=4, max_depth=4, seed=9, threads=1)
    b = s.render(spp=4, max_depth=4, seed=9, threads=2)
    assert np.array_equal(np.asarray(a.rgb), np.asarray(b.rgb))
    assert not np.array_equal(np.asarray(a.rgb), np.asarray(clear.rgb))
    path = str(tmp_path / "m.xml")
    s.save(path)
    loaded = sg.Scene.load(path)
    assert loaded.medium_type() == medium
    c = loaded.render(spp=4, max_depth=4, seed=9, threads=2)
    assert np.array_equal(np.asarray(a.rgb), np.asarray(c.rgb))
    for k in ("depth", "distance", "class_id", "instance_id"):
        assert np.array_equal(np.asarray(getattr(a, k)), np.asarray(getattr(clear, k))), k
    dist = np.asarray(a.distance)
    t1, t2 = s.camera_transmittance(dist), s.camera_transmittance(dist)
    assert np.array_equal(t1, t2)
    assert (t1 >= 0).all() and (t1 <= 1).all()
    print(f"\n{medium}: camera transmittance {float(t1.min()):.3f}..{float(t1.max()):.3f}")


def test_scene_file_grid_with_a_raw_file(tmp_path):
    """The scene file's medium key makes a grid medium from a raw float32 file named relative to the
    scene file; a wrong size names the file."""
    from synthgen.scene.scene_file import load_scene

    v = np.full((4, 5, 6), 0.5, np.float32)  # z, y, x: x fastest on disk
    (tmp_path / "fog.raw").write_bytes(v.tobytes())
    base = """
camera: {fov_y: 45, width: 16, height: 12, look_at: {eye: [0, 1.5, -5], target: [0, 1, 10]}}
objects: [{primitive: box, translate: [0, 0.5, 10], class_id: 1}]
lights: [{type: environment, radiance: 0.5}]
"""
    f = tmp_path / "grid.yaml"
    f.write_text(base + "medium: {type: grid, file: fog.raw, resolution: [6, 5, 4], bounds_min: [-3, 0, 0], "
                 "bounds_max: [3, 5, 4], extinction: 0.4}\n")
    scene, settings, meta = load_scene(str(f))
    assert scene.medium_type() == "grid"
    scene.render(spp=1)
    f.write_text(base + "medium: {type: grid, file: fog.raw, resolution: [6, 5, 5], bounds_min: [-3, 0, 0], "
                 "bounds_max: [3, 5, 4], extinction: 0.4}\n")
    with pytest.raises(sg.SynthgenError, match=r"fog\.raw.*480 bytes"):
        load_scene(str(f))
    f.write_text(base + "medium: {type: ground_fog, visibility: 50, coverage: 0.5, scale_height: 3}\n")
    scene, settings, meta = load_scene(str(f))
    assert meta["medium"]["type"] == "ground_fog"


def test_bad_heterogeneous_parameters_are_errors(tmp_path):
    s = sg.Scene()
    with pytest.raises(sg.SynthgenError, match="missing.vdb"):
        s.set_medium("grid", {"file": str(tmp_path / "missing.vdb"), "visibility": 10.0})
    with pytest.raises(sg.SynthgenError, match="no grid named 'smoke'"):
        path = str(tmp_path / "one.vdb")
        sg._core.write_vdb_grid(path, "density", np.ones((2, 2, 2), np.float32), [0, 0, 0], [1, 1, 1])
        s.set_medium("grid", {"file": path, "grid_name": "smoke", "visibility": 10.0})
    with pytest.raises(sg.SynthgenError, match="coverage"):
        s.set_medium("ground_fog", {"visibility": 10.0, "coverage": 2.0})
    with pytest.raises(sg.SynthgenError, match="did you mean"):
        s.set_medium("clouds", {"visibility": 10.0, "botom": 3.0})
    with pytest.raises(sg.SynthgenError, match="finite"):
        s.set_medium("grid", {"data": [0.0, float("nan")], "resolution": [2, 1, 1], "bounds_min": [0, 0, 0],
                              "bounds_max": [1, 1, 1], "visibility": 1.0})


def test_openvdb_loads_on_first_use(tmp_path):
    """OpenVDB's libraries stay out of `import synthgen` until a .vdb file is read or written."""
    script = (
        "import numpy as np, synthgen as sg\n"
        "def vdb_mapped():\n"
        "    return any('libopenvdb' in line for line in open('/proc/self/maps'))\n"
        "before = vdb_mapped()\n"
        f"path = {str(tmp_path / 'g.vdb')!r}\n"
        "sg._core.write_vdb_grid(path, 'density', np.ones((2, 2, 2), np.float32), [0, 0, 0], [1, 1, 1])\n"
        "print(before, vdb_mapped())\n")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "True"]
