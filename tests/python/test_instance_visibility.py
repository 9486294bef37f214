"""Scene.set_instance_visible and labels-only renders (used for amodal masks)."""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P


def _scene():
    s = sg.Scene()
    b = P.box((1.0, 1.0, 1.0))
    m = s.add_mesh(b["positions"], b["indices"])
    front = s.add_instance(m, P.translate([0.3, 0.0, 0.0]), class_id=1)   # partly hides `back`
    back = s.add_instance(m, P.translate([-0.3, 0.2, 1.5]), class_id=2)
    lamp = s.add_mesh(*(lambda q: (q["positions"], q["indices"]))(P.plane(0.5, 0.5)))
    emit = s.add_material("emissive", {"radiance": 50.0, "two_sided": True})
    light = s.add_instance(lamp, P.translate([0.0, 2.0, 0.0]), class_id=3, material_id=emit)
    s.add_light("environment", {"radiance": 0.2})
    wfc = sg.PinholeCamera.look_at([0.0, 0.5, -5.0], [0.0, 0.3, 0.5], [0.0, 1.0, 0.0])
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 96, 72, wfc))
    return s, front, back, light


def test_hidden_instance_gives_the_amodal_mask_without_bvh_builds():
    s, front, back, light = _scene()
    s.commit()
    both = s.render(spp=1, labels_only=True)
    assert both.stats["samples"] == 0 and float(np.abs(both.rgb).max()) == 0.0
    visible_back = both.instance_id == back + 1
    builds = s.commit_stats["mesh_bvh_builds"]
    s.set_instance_visible(front, False)
    s.commit()
    assert s.commit_stats["mesh_bvh_builds"] == builds, "hiding rebuilt a mesh BVH"
    alone = s.render(spp=1, labels_only=True)
    amodal_back = alone.instance_id == back + 1
    assert not np.any(alone.instance_id == front + 1)
    # The amodal mask contains the visible one and is larger (the front box hides part of it).
    assert np.all(amodal_back[visible_back]) and amodal_back.sum() > visible_back.sum() + 50
    # Reference: a scene without the front box at all.
    ref, _, back2, _ = _scene()
    ref.remove_instance(0)
    ref.commit()
    np.testing.assert_array_equal(ref.render(spp=1, labels_only=True).instance_id == back2 + 1, amodal_back)
    # Shown again: identical to the first render.
    s.set_instance_visible(front, True)
    s.commit()
    np.testing.assert_array_equal(s.render(spp=1, labels_only=True).instance_id, both.instance_id)


def test_hidden_emitter_is_not_a_light_and_visibility_survives_save(tmp_path):
    s, front, back, light = _scene()
    s.commit()
    first = s.render(spp=16, max_depth=3, seed=1)
    lit_boxes = first.rgb[(first.instance_id > 0) & (first.instance_id != light + 1)].mean()
    s.set_instance_visible(light, False)
    s.commit()
    assert not s.instance_visible(light)
    dark = s.render(spp=16, max_depth=3, seed=1)
    boxes = (dark.instance_id > 0) & (dark.instance_id != light + 1)
    assert dark.rgb[boxes].mean() < 0.8 * lit_boxes, \
        "a hidden emitter still lights the scene"
    # Hidden is exactly removed: the same image as a scene without that instance.
    ref, _, _, ref_light = _scene()
    ref.remove_instance(ref_light)
    ref.commit()
    np.testing.assert_array_equal(ref.render(spp=16, max_depth=3, seed=1).rgb, dark.rgb)
    path = str(tmp_path / "scene.xml")
    s.save(path)
    t = sg.Scene.load(path)
    t.commit()
    assert not t.instance_visible(light)
    np.testing.assert_array_equal(t.render(spp=16, max_depth=3, seed=1).rgb, dark.rgb)


def test_textures_and_materials_can_be_removed_when_unused(tmp_path):
    s = sg.Scene()
    t = s.add_texture("noise", {"mapping": "object"})
    b = s.add_texture("blend", {"a": sg.TextureRef(t), "b": 0.5, "op": "mix"})
    base = s.add_material("diffuse", {"albedo": sg.TextureRef(b)})
    other = s.add_material("diffuse", {"albedo": 0.3})
    mix = s.add_material("mix", {"material_a": base, "material_b": other, "weight": 0.5})
    m = s.add_mesh(*(lambda q: (q["positions"], q["indices"]))(P.box((1.0, 1.0, 1.0))))
    inst = s.add_instance(m, None, material_id=mix)
    with pytest.raises(ValueError, match="used by texture"):
        s.remove_texture(t)
    with pytest.raises(ValueError, match="used by material"):
        s.remove_texture(b)
    with pytest.raises(ValueError, match="used by instance"):
        s.remove_material(mix)
    with pytest.raises(ValueError, match="used by material"):
        s.remove_material(base)
    s.set_instance_material(inst, other)
    for mid in (mix, base):
        s.remove_material(mid)
    for tid in (b, t):
        s.remove_texture(tid)
    with pytest.raises(ValueError):
        s.remove_texture(t)  # already gone
    s.add_light("environment", {"radiance": 1.0})
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 16, 16, sg.PinholeCamera.look_at([0, 0, -4], [0, 0, 0], [0, 1, 0])))
    s.commit()
    r = s.render(spp=2, seed=1)
    path = str(tmp_path / "s.xml")
    s.save(path)
    t2 = sg.Scene.load(path)
    np.testing.assert_array_equal(t2.render(spp=2, seed=1).rgb, r.rgb)


def test_label_only_render_leaves_colour_buffers_out():
    """A label-only render allocates its labels only; the colour, noise and feature buffers read
    as zeros of their shapes (as they were when they were allocated and left at 0)."""
    s, front, back, light = _scene()
    r = s.render(spp=1, labels_only=True)
    for name, shape in (("rgb", (72, 96, 3)), ("rgb_even", (72, 96, 3)), ("variance", (72, 96, 3)),
                        ("albedo_odd", (72, 96, 3)), ("depth_odd", (72, 96)), ("sample_count", (72, 96))):
        a = np.asarray(getattr(r, name))
        assert a.shape == shape and not a.any(), name
    assert np.asarray(r.sample_count).dtype == np.uint32
    assert np.asarray(r.instance_id).any() and np.isfinite(np.asarray(r.depth)).any() and np.asarray(r.albedo).any()
    full = s.render(spp=2, max_depth=2)
    assert np.asarray(full.rgb_even).any() and np.asarray(full.sample_count).min() == 2
