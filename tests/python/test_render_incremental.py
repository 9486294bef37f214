"""Incremental commit: only new or edited meshes get a bottom-level BVH build; instance, material
and label edits touch nothing else, and every edit is visible in the next render. save()/load()
replays a scene bit-identically."""
from __future__ import annotations

import hashlib

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P

FX = FY = 200.0
W, H = 96, 64
CX, CY = 47.0, 31.0  # integers - 1 so that shifts of whole pixels keep the sampling pattern
Z = 5.0
OUTPUTS = ("rgb", "alpha", "depth", "distance", "normal", "albedo", "instance_id", "class_id")


def camera():
    # Camera at the origin looking along +z with x right and y down: world = camera space.
    return sg.PinholeCamera(fx=FX, fy=FY, cx=CX, cy=CY, width=W, height=H, world_from_camera=np.eye(4))


FACING_CAMERA = P.rotate([1, 0, 0], -90)  # plane normal +y -> -z


def build():
    """4 meshes, 5 instances (the box mesh is used twice)."""
    s = sg.Scene()
    box = s.add_mesh(**P.box((0.4, 0.4, 0.4)), name="box")
    sphere = s.add_mesh(**P.uv_sphere(0.25, 32, 16), name="sphere")
    wall = s.add_mesh(**P.plane(10, 10), name="wall")
    card = s.add_mesh(**P.plane(0.4, 0.4), name="card")
    grey = s.add_material("diffuse", {"albedo": [0.5, 0.5, 0.5]})
    red = s.add_material("diffuse", {"albedo": [0.9, 0.1, 0.1]})
    ids = dict(
        box_a=s.add_instance(box, P.translate([-0.7, -0.2, Z]), class_id=1, instance_id=10, material_id=red),
        box_b=s.add_instance(box, P.translate([0.7, -0.2, Z]), class_id=1, instance_id=11, material_id=grey),
        sphere=s.add_instance(sphere, P.translate([0.0, 0.45, Z]), class_id=2, instance_id=20, material_id=grey),
        # wall behind the objects, facing the camera (-z)
        wall=s.add_instance(wall, P.translate([0, 0, Z + 2]) @ FACING_CAMERA, class_id=9,
                            instance_id=90, material_id=grey),
    )
    s.add_light("environment", {"radiance": 0.5})
    s.set_camera(camera())
    # a fronto-parallel card at depth Z: its projection shifts by exactly fx dx / Z when moved by dx
    ids["card"] = s.add_instance(card, P.translate([-0.7, 0.5, Z]) @ FACING_CAMERA, class_id=3, instance_id=30,
                                 material_id=grey)
    return s, dict(box=box, sphere=sphere, wall=wall, card=card, grey=grey, red=red), ids


def render(s, **kw):
    kw = {**dict(spp=2, max_depth=2, seed=3), **kw}
    return s.render(**kw)


def test_first_commit_builds_every_mesh_once():
    s, m, ids = build()
    assert s.has_pending_edits()
    s.commit()
    st = s.commit_stats
    assert st["mesh_bvh_builds"] == 4 and st["mesh_bvh_builds_last_commit"] == 4 and st["commits"] == 1
    assert not s.has_pending_edits()
    r = render(s)
    assert r.stats["mesh_bvh_builds"] == 4 and r.stats["mesh_bvh_builds_last_commit"] == 4
    assert s.commit_stats["commits"] == 1, "render() without pending edits must not commit"
    assert set(np.unique(r.instance_id)) == {10, 11, 20, 30, 90}
    # One name per figure: the commit counters read the same in commit_stats and render stats.
    shared = {"mesh_bvh_builds", "mesh_bvh_builds_last_commit"}
    assert shared <= set(s.commit_stats) and shared <= set(r.stats)
    assert not {k for k in s.commit_stats if k.startswith("mesh_bvh")} - shared


def _committed(s):
    s.commit()
    return s.commit_stats


def test_moving_an_instance_rebuilds_no_mesh_and_moves_the_mask():
    s, m, ids = build()
    before = render(s)
    dx = 0.25  # world units at depth Z: fx * dx / Z = 10 pixels
    s.set_instance_transform(ids["card"], P.translate([-0.7 + dx, 0.5, Z]) @ FACING_CAMERA)
    assert s.has_pending_edits()
    st = _committed(s)
    assert st["mesh_bvh_builds_last_commit"] == 0 and st["mesh_bvh_builds"] == 4
    after = render(s)
    shift = int(round(FX * dx / Z))
    assert shift == 10
    mask_b, mask_a = before.instance_id == 30, after.instance_id == 30
    assert mask_b.sum() == 16 * 16  # 0.4 x 0.4 at depth 5 with f = 200: 16 x 16 pixels
    # A translation parallel to the image plane shifts the projection by exactly fx dx / Z.
    assert not mask_b[:, -shift:].any()
    np.testing.assert_array_equal(np.roll(mask_b, shift, axis=1), mask_a)
    np.testing.assert_allclose(after.depth[mask_a], Z, rtol=1e-5)
    # The other instances are untouched.
    for iid in (10, 11, 20):
        np.testing.assert_array_equal(before.instance_id == iid, after.instance_id == iid)


def test_adding_an_instance_of_an_existing_mesh_rebuilds_no_mesh():
    s, m, ids = build()
    render(s)
    new = s.add_instance(m["sphere"], P.translate([0.0, -0.5, Z - 1]), class_id=2, instance_id=21)
    st = _committed(s)
    assert st["mesh_bvh_builds_last_commit"] == 0 and st["mesh_bvh_builds"] == 4
    r = render(s)
    assert (r.instance_id == 21).sum() > 100
    # projected centre of the new sphere
    assert r.instance_id[int(FY * -0.5 / (Z - 1) + CY), int(CX)] == 21
    assert s.instance_count() == 6 and new == 5


def test_changing_a_material_rebuilds_no_mesh_and_changes_albedo():
    s, m, ids = build()
    before = render(s)
    box_a = before.instance_id == 10
    np.testing.assert_array_equal(before.albedo[box_a], np.float32([0.9, 0.1, 0.1])[None].repeat(box_a.sum(), 0))
    s.update_material(m["red"], "diffuse", {"albedo": [0.2, 0.7, 0.3]})
    st = _committed(s)
    assert st["mesh_bvh_builds_last_commit"] == 0
    r = render(s)
    assert np.all(r.albedo[box_a] == np.float32([0.2, 0.7, 0.3]))
    assert not np.array_equal(r.rgb[box_a], before.rgb[box_a])
    # Re-assigning an instance's material: box_b (grey) gets the edited material.
    s.set_instance_material(ids["box_b"], m["red"])
    assert _committed(s)["mesh_bvh_builds_last_commit"] == 0
    r2 = render(s)
    assert np.all(r2.albedo[r2.instance_id == 11] == np.float32([0.2, 0.7, 0.3]))


def test_changing_labels_rebuilds_no_mesh_and_relabels_the_same_pixels():
    s, m, ids = build()
    before = render(s)
    s.set_instance_labels(ids["sphere"], 5, 555)
    st = _committed(s)
    assert st["mesh_bvh_builds_last_commit"] == 0
    r = render(s)
    was = before.instance_id == 20
    np.testing.assert_array_equal(r.instance_id == 555, was)
    assert np.all(r.class_id[was] == 5)
    assert not np.any(r.instance_id == 20)
    for name in ("rgb", "depth", "normal", "albedo"):
        np.testing.assert_array_equal(getattr(r, name), getattr(before, name))


def test_removing_an_instance():
    s, m, ids = build()
    before = render(s)
    s.remove_instance(ids["sphere"])
    assert _committed(s)["mesh_bvh_builds_last_commit"] == 0
    r = render(s)
    assert not np.any(r.instance_id == 20)
    # the wall behind becomes visible where the sphere was
    assert np.all(r.instance_id[before.instance_id == 20] == 90)


def test_update_mesh_rebuilds_exactly_one_mesh():
    s, m, ids = build()
    before = render(s)
    s.update_mesh(m["sphere"], **P.uv_sphere(0.15, 32, 16))
    st = _committed(s)
    assert st["mesh_bvh_builds_last_commit"] == 1 and st["mesh_bvh_builds"] == 5
    r = render(s)
    area_before, area_after = (before.instance_id == 20).sum(), (r.instance_id == 20).sum()
    # Projected area scales with the radius squared: (0.15 / 0.25)^2 = 0.36.
    assert abs(area_after / area_before - 0.36) < 0.05
    # The box mesh, shared by two instances, was not touched.
    for iid in (10, 11):
        np.testing.assert_array_equal(before.instance_id == iid, r.instance_id == iid)


def test_edits_without_commit_are_committed_by_render():
    s, m, ids = build()
    render(s)
    commits = s.commit_stats["commits"]
    s.set_instance_transform(ids["box_b"], P.translate([0.7, 0.2, Z]))
    r = render(s)
    assert s.commit_stats["commits"] == commits + 1
    assert r.stats["mesh_bvh_builds_last_commit"] == 0


def _digest(r):
    return {n: hashlib.sha256(np.ascontiguousarray(getattr(r, n)).tobytes()).hexdigest() for n in OUTPUTS}


def test_save_load_replays_bit_identically(tmp_path):
    s, m, ids = build()
    # Make the history non-trivial: removed instance (a hole in the ids), edited material,
    # updated mesh, a texture and extra lights.
    s.remove_instance(ids["box_b"])
    s.update_material(m["grey"], "diffuse", {"albedo": [0.6, 0.55, 0.5]})
    s.update_mesh(m["sphere"], **P.uv_sphere(0.3, 24, 12))
    s.add_light("sun", {"direction": [0.2, -1.0, -0.5], "irradiance": 3.0})
    s.add_light("point", {"position": [0.0, -1.0, Z - 1.5], "intensity": 2.0})
    tex = s.add_texture("constant", {"value": [0.3, 0.2, 0.1]})
    s.set_instance_material(ids["sphere"], s.add_material("diffuse", {"albedo": sg.TextureRef(tex)}))
    original = render(s, spp=4, max_depth=4)

    path = str(tmp_path / "scene.xml")
    s.save(path)
    loaded = sg.Scene.load(path)
    assert loaded.instance_count() == s.instance_count() == 4
    replay = render(loaded, spp=4, max_depth=4)
    assert _digest(replay) == _digest(original)
    # Ids are preserved: editing by the original handles still works on the loaded scene.
    loaded.set_instance_labels(ids["sphere"], 2, 777)
    assert np.array_equal(render(loaded).instance_id == 777, original.instance_id == 20)
    with pytest.raises(sg.SynthgenError):
        loaded.set_instance_labels(ids["box_b"], 1, 1)  # removed before saving
