"""Scene.instance_coverage: every listed instance's amodal mask (or, with first_hit, its visible
mask) from one ray per pixel, bit for bit the masks of label-only renders -- of each instance
alone for amodal masks, of the scene as it is for visible ones -- and what the layout makes of it
(frame.layout.amodal_masks) against one render per object, as the layout did before."""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P
from synthgen.frame.layout import bit_counts, bit_mask

W, H = 96, 72


def _mesh(s: sg.Scene, m: dict) -> int:
    return s.add_mesh(m["positions"], m["indices"], normals=m.get("normals"), uvs=m.get("uvs"))


def _scene():
    """Overlapping objects on a ground: two boxes, one behind the other; a sphere in front of both;
    a box mostly left of the image; a cut-out quad (checker alpha) across the middle; a hidden box
    (instance ids: handle + 1). Returns (scene, the listed instances, the ground, the camera)."""
    s = sg.Scene()
    ground = s.add_instance(_mesh(s, P.plane(40.0, 40.0)), np.eye(4), class_id=9, instance_id=90)
    box, ball = _mesh(s, P.box((1.0, 1.0, 1.0))), _mesh(s, P.uv_sphere(0.5, 32, 16))
    quad = P.plane(2.0, 1.2)
    checks = (np.indices((6, 6)).sum(axis=0) % 2).astype(np.float32)
    alpha = s.add_image_texture(np.kron(checks, np.ones((4, 4), np.float32)))
    cutout = s.add_material("diffuse", {"albedo": [0.8, 0.2, 0.2], "alpha": sg.TextureRef(alpha)})
    placed = [
        s.add_instance(box, P.translate([0.0, 0.5, 0.0]), class_id=1),
        s.add_instance(box, P.translate([0.4, 0.7, 1.2]) @ P.rotate([0, 1, 0], 30.0), class_id=1),
        s.add_instance(ball, P.translate([-0.5, 0.5, -0.9]), class_id=2),
        s.add_instance(box, P.translate([-3.3, 0.6, 0.5]) @ P.scale([1.2, 1.2, 1.2]), class_id=1),
        s.add_instance(_mesh(s, quad), P.translate([0.2, 0.8, -1.6]) @ P.rotate([1, 0, 0], -80.0),
                       class_id=3, material_id=cutout),
        s.add_instance(box, P.translate([1.5, 0.5, -0.5]), class_id=1),
    ]
    s.set_instance_visible(placed[-1], False)
    s.add_light("environment", {"radiance": 0.5})
    wfc = sg.PinholeCamera.look_at([0.0, 2.2, -5.5], [0.0, 0.5, 0.0], [0.0, 1.0, 0.0])
    cam = sg.PinholeCamera.from_fov(45.0, W, H, wfc)
    s.set_camera(cam)
    return s, placed, ground, cam


def _alone(s: sg.Scene, camera, inst: int, others) -> np.ndarray:
    """The mask of `inst` (instance id inst + 1) in a label-only render of it alone, as the
    layout made amodal masks before (one render per object)."""
    shown = {i: s.instance_visible(i) for i in others}
    for i in others:
        s.set_instance_visible(i, i == inst)
    s.set_camera(camera)
    ids = np.asarray(s.render(spp=1, labels_only=True).instance_id)
    for i, v in shown.items():
        s.set_instance_visible(i, v)
    return ids == inst + 1


def _padded(cam, pad: int = 24):
    K = np.asarray(cam.K, np.float64)
    return sg.PinholeCamera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]) + pad, float(K[1, 2]) + pad,
                            cam.width + 2 * pad, cam.height + 2 * pad, np.asarray(cam.world_from_camera, np.float64))


@pytest.mark.parametrize("padded", [False, True])
def test_amodal_masks_equal_renders_alone(padded):
    s, placed, ground, cam = _scene()
    camera = _padded(cam) if padded else cam
    bits = s.instance_coverage(camera, placed)
    assert bits.shape == (camera.height, camera.width, 1) and bits.dtype == np.uint64
    assert s.commit_stats["alpha_tested_meshes"] == 1, "the quad is a cut-out"
    assert s.camera.width == W, "the scene's camera is not changed"
    everything = placed + [ground]
    for i, inst in enumerate(placed):
        mine = bit_mask(bits, i)
        if not s.instance_visible(inst):
            assert not mine.any(), "a hidden instance covers nothing"
            continue
        ref = _alone(s, camera, inst, everything)
        assert ref.sum() > 20, f"instance {inst} is seen"
        np.testing.assert_array_equal(mine, ref, err_msg=f"instance {inst}")
    np.testing.assert_array_equal(bit_counts(bits, len(placed)), [bit_mask(bits, i).sum() for i in range(len(placed))])


def test_masks_are_not_trivial():
    """The scene tests what it should: overlaps hide parts, one object leaves the image, the
    cut-out has holes (the quad's mask is not its silhouette)."""
    s, placed, ground, cam = _scene()
    s.commit()
    ids = np.asarray(s.render(spp=1, labels_only=True).instance_id)
    amodal = s.instance_coverage(cam, placed)
    counts = bit_counts(amodal, len(placed))
    visible = np.array([(ids == inst + 1).sum() for inst in placed])
    assert np.all(visible[:5] > 0) and np.all(visible[:5] <= counts[:5]) and counts[5] == 0
    assert np.all(visible[:3] < counts[:3] - 50), "the boxes and the ball hide each other"
    wide = bit_counts(s.instance_coverage(_padded(cam, 48), placed), len(placed))
    assert wide[3] > counts[3] + 50, "the left box leaves the image"
    # The quad alone, opaque: its silhouette is larger than its cut-out mask.
    opaque = s.add_material("diffuse", {})
    s.set_instance_material(placed[4], opaque)
    assert bit_counts(s.instance_coverage(cam, [placed[4]]), 1)[0] > counts[4] + 50
    assert s.commit_stats["alpha_tested_meshes"] == 0


def test_first_hit_is_the_label_render():
    s, placed, ground, cam = _scene()
    ids = np.asarray(s.render(spp=1, labels_only=True).instance_id)
    bits = s.instance_coverage(cam, placed, first_hit=True)
    for i, inst in enumerate(placed):
        np.testing.assert_array_equal(bit_mask(bits, i), ids == inst + 1)
    # Instances not listed still hide the listed ones.
    only = s.instance_coverage(cam, [placed[1]], first_hit=True)
    np.testing.assert_array_equal(bit_mask(only, 0), ids == placed[1] + 1)


def test_distorted_camera_traces_every_pixel():
    s, placed, ground, cam = _scene()
    lens = sg.PinholeCamera(cam.fx, cam.fy, cam.cx, cam.cy, W, H, np.asarray(cam.world_from_camera),
                            distortion=(-0.2, 0.05, 0.001, -0.001, 0.0))
    bits = s.instance_coverage(lens, placed)
    for i in (0, 3, 4):
        np.testing.assert_array_equal(bit_mask(bits, i), _alone(s, lens, placed[i], placed + [ground]))


def test_more_than_64_instances_and_threads():
    s = sg.Scene()
    ball = _mesh(s, P.uv_sphere(0.12, 16, 8))
    rng = np.random.default_rng(5)
    insts = [s.add_instance(ball, P.translate([x, y, z]), class_id=1, instance_id=k + 1)
             for k, (x, y, z) in enumerate(rng.uniform([-1.5, -1.0, -0.5], [1.5, 1.0, 1.5], (70, 3)))]
    s.add_light("environment", {"radiance": 1.0})
    cam = sg.PinholeCamera.from_fov(50.0, 80, 60, sg.PinholeCamera.look_at([0, 0, -4], [0, 0, 0], [0, 1, 0]))
    s.set_camera(cam)
    order = insts[::-1]  # bits need not follow instance ids
    one, two = (s.instance_coverage(cam, order, threads=t) for t in (1, 2))
    assert one.shape == (60, 80, 2)
    np.testing.assert_array_equal(one, two)
    counts = bit_counts(one, len(order))
    assert np.all(counts > 0)
    for i in (0, 5, 63, 64, 69):
        np.testing.assert_array_equal(bit_mask(one, i), _alone(s, cam, order[i], insts))
    first = s.instance_coverage(cam, order, threads=1, first_hit=True)
    np.testing.assert_array_equal(first, s.instance_coverage(cam, order, threads=2, first_hit=True))
    ids = np.asarray(s.render(spp=1, labels_only=True).instance_id)
    visible = bit_counts(first, len(order))
    np.testing.assert_array_equal(visible, [(ids == order[i] + 1).sum() for i in range(70)])
    assert visible.sum() < counts.sum() - 20, "balls overlap"


def test_errors_and_empty_lists():
    s, placed, ground, cam = _scene()
    with pytest.raises(sg.SynthgenError, match="listed twice"):
        s.instance_coverage(cam, [placed[0], placed[0]])
    with pytest.raises(sg.SynthgenError, match="does not exist"):
        s.instance_coverage(cam, [999])
    assert s.instance_coverage(cam, []).shape == (H, W, 0)
    assert bit_counts(s.instance_coverage(cam, []), 0).shape == (0,)


def test_instances_reaching_behind_the_camera_and_user_shapes(tmp_path, monkeypatch):
    """A wall from behind the camera to far in front (no projected bounds: every pixel traced)
    and a user shape of an extension (hits reported by its own callback, not by a filter)."""
    from synthgen.scene import extensions

    monkeypatch.setenv("SYNTHGEN_CACHE", str(tmp_path / "cache"))
    s, placed, ground, cam = _scene()
    s.load_extension(extensions.example("shapes"))
    wall = s.add_instance(_mesh(s, P.box((0.2, 3.0, 20.0))), P.translate([1.4, 1.0, 0.0]), class_id=4)
    torus = s.add_instance(s.add_shape("torus", {"major_radius": 0.5, "minor_radius": 0.15}),
                           P.translate([0.3, 1.0, -0.4]) @ P.rotate([1, 0, 0], 60.0), class_id=5)
    listed = placed + [wall, torus]
    bits = s.instance_coverage(cam, listed)
    everything = listed + [ground]
    for i in (0, 1, 2, len(placed), len(placed) + 1):
        ref = _alone(s, cam, listed[i], everything)
        assert ref.sum() > 20
        np.testing.assert_array_equal(bit_mask(bits, i), ref, err_msg=f"instance {listed[i]}")
    s.set_camera(cam)
    ids = np.asarray(s.render(spp=1, labels_only=True).instance_id)
    first = s.instance_coverage(cam, listed, first_hit=True)
    for i, inst in enumerate(listed):
        np.testing.assert_array_equal(bit_mask(first, i), ids == inst + 1)
    assert (ids == torus + 1).sum() < bit_mask(bits, len(placed) + 1).sum(), "the torus is partly hidden"


def _render_alone(view, camera, k):
    """frame.layout.amodal_pixels as it was: object k alone (the others, posts and ground
    hidden) in a label-only render of the padded canvas."""
    from synthgen.frame.layout import TRUNCATION_PAD

    w, h = view.resolution
    pw, ph = int(round(TRUNCATION_PAD * w)), int(round(TRUNCATION_PAD * h))
    K = np.asarray(camera.K, np.float64)
    padded = sg.PinholeCamera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]) + pw, float(K[1, 2]) + ph,
                              w + 2 * pw, h + 2 * ph, np.asarray(camera.world_from_camera, np.float64))
    for i, o in enumerate(view.objects):
        view.scene.set_instance_visible(o.instance, i == k)
    for d in view.decor:
        view.scene.set_instance_visible(d, False)
    view.scene.set_instance_visible(view.ground, False)
    pixels = np.asarray(view.labels(padded).instance_id) == k + 1
    return int(pixels[ph:ph + h, pw:pw + w].sum()), int(pixels.sum()), pixels


def test_frame_amodal_masks_equal_one_render_per_object(tmp_path):
    """The default scenario's frames: every object's amodal figures and mask from one pass
    (frame.layout.amodal_masks) equal one label-only render of it alone."""
    import os

    import yaml

    from synthgen.frame import FrameRenderer
    from synthgen.frame.layout import FrameView, amodal_masks
    from synthgen.scenario import load_scenario

    root = os.path.join(os.path.dirname(__file__), "..", "..")
    with open(os.path.join(root, "scenarios", "default.yaml")) as f:
        spec = yaml.safe_load(f)
    spec["resolution"] = [160, 120]
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(spec))
    fr = FrameRenderer(load_scenario(str(tmp_path / "s.yaml")))
    seen = 0
    for frame in range(12):
        f = fr.prepare(frame)
        view = FrameView(fr.scene, f.objects, fr.decor.ids, fr.ground, (160, 120), 0)
        ks = [k for k in range(len(f.objects)) if f.keep[k]]
        fast = amodal_masks(view, f.camera, ks, ks)
        assert {k: v[:2] for k, v in fast.items()} == {k: f.amodal[k] for k in ks}
        for k in ks:
            inside, total, mask = _render_alone(view, f.camera, k)
            assert fast[k][:2] == (inside, total)
            np.testing.assert_array_equal(fast[k][2], mask)
            seen += total > inside  # truncated objects
    assert seen >= 1
