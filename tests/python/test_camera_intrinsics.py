"""Camera intrinsics and lens distortion: a cuboid at a known pose projects to the box computed
analytically (corners within 0.5 px), with and without OpenCV distortion, and the labels of a
distorted camera are rendered through the lens itself (no resampling)."""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P

# KITTI's P2 intrinsics (image 1242 x 375) and a car-sized cuboid 12 m ahead, turned 30 degrees.
K = dict(fx=721.5377, fy=721.5377, cx=609.5593, cy=172.854, width=1242, height=375)
SIZE = (1.8, 1.5, 4.2)  # width (x), height (y), length (z), metres
DISTORTIONS = {"none": (0.0, 0.0, 0.0, 0.0, 0.0),
               "barrel": (-0.30, 0.11, 0.0013, -0.0009, -0.02),
               "pincushion": (0.08, 0.01, -0.0005, 0.0007, 0.0)}


def _pose() -> np.ndarray:
    # Camera at the origin in OpenCV axes (x right, y down, z forward): world == camera space.
    return P.translate([1.2, 0.9, 12.0]) @ P.rotate([0, 1, 0], 30.0)


def _edges(world_from_object: np.ndarray, n: int = 4000) -> np.ndarray:
    """Points along the cuboid's 12 edges (a distorted edge bends: its extremes can lie inside)."""
    h = 0.5 * np.array(SIZE)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    pts = []
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(corners[i] != corners[j]) == 1:
                t = np.linspace(0.0, 1.0, n)[:, None]
                pts.append(corners[i] + t * (corners[j] - corners[i]))
    p = np.concatenate(pts)
    return (np.c_[p, np.ones(len(p))] @ world_from_object.T)[:, :3]


@pytest.mark.parametrize("name", list(DISTORTIONS))
def test_cuboid_projects_to_its_analytic_box(name):
    cam = sg.PinholeCamera(K["fx"], K["fy"], K["cx"], K["cy"], K["width"], K["height"], distortion=DISTORTIONS[name])
    s = sg.Scene()
    b = P.box(SIZE)
    wfo = _pose()
    inst = s.add_instance(s.add_mesh(b["positions"], b["indices"]), wfo.astype(np.float32), class_id=1)
    s.set_camera(cam)
    r = s.render(spp=1, labels_only=True)
    ys, xs = np.nonzero(np.asarray(r.instance_id) == inst + 1)
    mask_box = np.array([xs.min(), ys.min(), xs.max() + 1, ys.max() + 1], float)
    uv = np.array([cam.project(p.tolist()) for p in _edges(wfo)])
    analytic = np.array([uv[:, 0].min(), uv[:, 1].min(), uv[:, 0].max(), uv[:, 1].max()])
    if name == "none":
        # Without distortion the box is that of the 8 projected corners, by the pinhole formula.
        h = 0.5 * np.array(SIZE)
        c = np.array([[sx, sy, sz, 1.0] for sx in (-h[0], h[0]) for sy in (-h[1], h[1]) for sz in (-h[2], h[2])])
        pc = (c @ wfo.T)[:, :3]
        u = K["fx"] * pc[:, 0] / pc[:, 2] + K["cx"]
        v = K["fy"] * pc[:, 1] / pc[:, 2] + K["cy"]
        assert np.allclose(analytic, [u.min(), v.min(), u.max(), v.max()], atol=1e-3)
    # Pixel centres sample the silhouette: each side within half a pixel.
    assert np.abs(mask_box - analytic).max() <= 0.5 + 1e-3, (name, mask_box, analytic)


def test_distortion_moves_the_labels_as_the_lens_does():
    """With barrel distortion an off-centre object is drawn nearer the centre, by the amount
    OpenCV's model gives, and its mask stays one connected, hole-free region."""
    plain = sg.PinholeCamera(K["fx"], K["fy"], K["cx"], K["cy"], K["width"], K["height"])
    barrel = sg.PinholeCamera(K["fx"], K["fy"], K["cx"], K["cy"], K["width"], K["height"],
                              distortion=DISTORTIONS["barrel"])
    centres = []
    for cam in (plain, barrel):
        s = sg.Scene()
        b = P.box(SIZE)
        wfo = P.translate([6.0, 0.9, 10.0]) @ P.rotate([0, 1, 0], 30.0)  # well right of the centre
        inst = s.add_instance(s.add_mesh(b["positions"], b["indices"]), wfo.astype(np.float32), class_id=1)
        s.set_camera(cam)
        m = np.asarray(s.render(spp=1, labels_only=True).instance_id) == inst + 1
        ys, xs = np.nonzero(m)
        centres.append(xs.mean())
        rows = m[ys.min():ys.max() + 1]
        assert all(np.all(row[np.nonzero(row)[0][0]:np.nonzero(row)[0][-1] + 1]) for row in rows if row.any())
    assert centres[1] < centres[0] - 20  # barrel distortion pulls it towards the centre
    assert barrel.distortion == pytest.approx(DISTORTIONS["barrel"], abs=1e-7)
    x, y = 0.6, 0.2
    xd, yd = barrel.distort(x, y)
    assert barrel.undistort(xd, yd) == pytest.approx((x, y), abs=1e-6)


def test_folding_distortion_is_refused_with_the_reason():
    with pytest.raises(sg.SynthgenError, match="folds the image back"):
        sg.PinholeCamera(K["fx"], K["fy"], K["cx"], K["cy"], K["width"], K["height"], distortion=(-0.9, 0, 0, 0, 0))
    with pytest.raises(sg.SynthgenError, match="folds"):
        sg.PinholeCamera.from_params({"width": 640, "height": 480, "fov_y": 60, "k1": -1.5})


@pytest.mark.parametrize("name", list(DISTORTIONS))
def test_project_points_is_project_of_each_point(name):
    """project_points (N x 3 at once) gives exactly project() of every point, NaN behind the camera."""
    cam = sg.PinholeCamera(K["fx"], K["fy"], K["cx"], K["cy"], K["width"], K["height"], distortion=DISTORTIONS[name])
    rng = np.random.default_rng(4)
    pts = np.c_[rng.uniform(-20, 20, (500, 2)), rng.uniform(-5, 40, 500)]  # some behind (z < 0)
    uv = cam.project_points(pts)
    assert uv.shape == (500, 2) and uv.dtype == np.float64
    behind = 0
    for p, q in zip(pts, uv):
        one = cam.project([float(c) for c in p])
        if one is None:
            behind += 1
            assert np.isnan(q).all()
        else:
            assert (q[0], q[1]) == one
    assert 0 < behind < 500
    with pytest.raises(sg.SynthgenError, match="N x 3"):
        cam.project_points(np.zeros((4, 2)))


def test_image_points_go_through_the_lens():
    """outputs.render.image_points (plate corners, lamps) with a distorted camera: a small cube
    off the centre is drawn where image_points puts its centre, not where K alone would (the
    undistorted projection, tens of pixels away)."""
    from synthgen.outputs.render import image_points

    cam = sg.PinholeCamera(K["fx"], K["fy"], K["cx"], K["cy"], K["width"], K["height"],
                           distortion=DISTORTIONS["barrel"])
    wfo = P.translate([6.0, 1.5, 10.0])
    s = sg.Scene()
    b = P.box((0.06, 0.06, 0.06))
    inst = s.add_instance(s.add_mesh(b["positions"], b["indices"]), wfo.astype(np.float32), class_id=1)
    s.set_camera(cam)
    ys, xs = np.nonzero(np.asarray(s.render(spp=1, labels_only=True).instance_id) == inst + 1)
    centre = np.array([xs.mean() + 0.5, ys.mean() + 0.5])  # pixel centres at +0.5
    uv, z = image_points(cam, wfo, np.zeros((1, 3)))
    assert z[0] == pytest.approx(10.0)
    assert np.abs(uv[0] - centre).max() < 1.0, (uv, centre)
    plain = K["fx"] * 6.0 / 10.0 + K["cx"], K["fy"] * 1.5 / 10.0 + K["cy"]
    assert np.abs(np.asarray(plain) - centre).max() > 20.0


def _scenario_box(tmp_path, name, extra_camera, outputs="[rgb, coco]"):
    import json

    import yaml

    from synthgen import run as runner

    sc = yaml.safe_load(f"""
seed: 1
count: 1
resolution: [192, 108]
camera: {{fx: 96, pose: {{type: look_at, eye: [0, 1.45, 0], target: [0, 1.45, 100]}}}}
objects: [{{class: car, primitive: box, size: [1.8, 1.5, 4.2], region: [-4.51, 7.99, -4.49, 8.01]}}]
outputs: {outputs}
render: {{spp: 1, max_depth: 1}}
""")
    sc["camera"].update(extra_camera)
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(sc))
    s = runner.run(str(path), str(tmp_path / name), progress=False, isolate=False)
    assert not s["failures"], s["failures"]
    meta = json.load(open(tmp_path / name / "meta" / "000000.json"))
    coco = json.load(open(tmp_path / name / "annotations" / "coco.json"))
    return meta, coco["annotations"][0]["bbox"]


def test_scenario_camera_renders_through_its_lens(tmp_path):
    """camera k1..k3 in a scenario: the frame is drawn through the lens (a box off to the side
    moves towards the centre, its box as the lens's projection of its edges gives; its amodal
    pixels through the same lens), the metadata records the coefficients, and KITTI's outputs
    (no lens in P2) are refused."""
    plain_meta, plain = _scenario_box(tmp_path, "plain", {})
    meta, box = _scenario_box(tmp_path, "barrel", {"k1": -0.3, "k2": 0.08})
    assert "distortion" not in plain_meta["camera"]
    assert meta["camera"]["distortion"] == pytest.approx([-0.3, 0.08, 0.0, 0.0, 0.0])
    obj = next(o for o in meta["objects"] if o.get("class") == "car")
    # Whole and alone: all of it visible, its amodal pixels counted through the same lens.
    assert obj["visible_pixels"] == obj["amodal_pixels"] and obj["visible_fraction"] == 1.0
    assert obj["world_from_object"] == next(o for o in plain_meta["objects"]
                                            if o.get("class") == "car")["world_from_object"]
    c = meta["camera"]
    cam = sg.PinholeCamera(c["fx"], c["fy"], c["cx"], c["cy"], c["width"], c["height"],
                           np.asarray(c["world_from_camera"]), distortion=tuple(c["distortion"]))
    # The edges of the unit box primitive, placed by its world_from_object (size and pose).
    t = np.linspace(-0.5, 0.5, 200)
    edges = []
    for a in (-0.5, 0.5):
        for b in (-0.5, 0.5):
            ca, cb = np.full_like(t, a), np.full_like(t, b)
            edges += [np.c_[t, ca, cb], np.c_[ca, t, cb], np.c_[ca, cb, t]]
    p = np.concatenate(edges)
    pts = (np.c_[p, np.ones(len(p))] @ np.asarray(obj["world_from_object"]).T)[:, :3]
    uv = cam.project_points(np.asarray(pts))
    lens = [uv[:, 0].min(), uv[:, 1].min(), uv[:, 0].max(), uv[:, 1].max()]
    got = [box[0], box[1], box[0] + box[2], box[1] + box[3]]
    assert np.abs(np.asarray(got) - lens).max() <= 1.0, (got, lens)
    # Barrel distortion pulls the off-centre box towards the image centre (96).
    assert abs(box[0] + 0.5 * box[2] - 96) < abs(plain[0] + 0.5 * plain[2] - 96) - 3
    import synthgen.scenario as scn

    bad = tmp_path / "k.yaml"
    bad.write_text((tmp_path / "barrel.yaml").read_text().replace("- rgb\n- coco", "- rgb\n- kitti"))
    with pytest.raises(sg.SynthgenError, match="camera.k1: lens distortion with the kitti output: KITTI's P2"):
        scn.load_scenario(str(bad))
