"""Cylinder and cone primitives: closed, outward-facing solids with the exact volume of
their polygonal cross-section, outward normals, and the silhouette their size says, in
scene files and scenarios."""
from collections import Counter

import numpy as np
import pytest

import synthgen as sg
from synthgen.scene import primitives as P


def _volume(m):
    p = m["positions"].astype(np.float64)
    a, b, c = (p[m["indices"][:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _open_edges(m):
    p = np.round(m["positions"].astype(np.float64), 6)
    e = Counter()
    for t in m["indices"]:
        for x, y in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            e[(tuple(p[x]), tuple(p[y]))] += 1
    return [k for k, v in e.items() if e.get((k[1], k[0]), 0) != v]


@pytest.mark.parametrize("n", [3, 7, 64])
def test_closed_with_the_polygon_volume(n):
    area = 0.5 * n * 0.3 ** 2 * np.sin(2 * np.pi / n)  # the regular n-gon of radius 0.3
    cyl, cone = P.cylinder(0.3, 1.2, n), P.cone(0.3, 1.2, n)
    assert not _open_edges(cyl) and not _open_edges(cone), "every edge shared by two faces, opposite ways"
    assert _volume(cyl) == pytest.approx(area * 1.2, rel=1e-6)  # positive: outward winding
    assert _volume(cone) == pytest.approx(area * 1.2 / 3.0, rel=1e-6)
    for m, (lo, hi) in ((cyl, (-0.6, 0.6)), (cone, (-0.6, 0.6))):
        y = m["positions"][:, 1]
        assert y.min() == pytest.approx(lo) and y.max() == pytest.approx(hi)


def test_normals_point_outwards():
    for m in (P.cylinder(0.5, 1.0, 32), P.cone(0.5, 1.0, 32)):
        p, n = m["positions"], m["normals"]
        assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
        # Faces' geometric normals agree with the vertex normals (same side).
        a, b, c = (p[m["indices"][:, k]] for k in range(3))
        g = np.cross(b - a, c - a)
        vn = n[m["indices"]].sum(axis=1)
        assert np.all(np.einsum("ij,ij->i", g, vn) > 0)
    cone = P.cone(0.5, 1.0, 32)
    side = cone["normals"][np.abs(cone["normals"][:, 1]) < 0.99]
    assert np.allclose(side[:, 1], 0.5 / np.hypot(0.5, 1.0), atol=1e-5), "the slant of the side"


def test_silhouettes_in_a_scene_file():
    """Seen from the front, far away with a narrow field of view: the cylinder's mask is a
    rectangle 2r x h, the cone's a triangle of the same box with half its area."""
    data = {
        "camera": {"fov_y": 4.0, "width": 200, "height": 200, "look_at": {"eye": [0, 0, -40], "target": [0, 0, 0]}},
        "objects": [{"primitive": "cylinder", "radius": 0.5, "height": 1.0, "translate": [-0.6, 0, 0], "class_id": 1},
                    {"primitive": "cone", "radius": 0.5, "height": 1.0, "translate": [0.6, 0, 0], "class_id": 2}],
        "render": {"spp": 1},
    }
    scene, settings, meta = sg.build_scene(data)
    r = scene.render(**{**settings, "spp": 1})
    cls = np.asarray(r.class_id)
    px = 40 * np.tan(np.radians(2.0)) * 2 / 200  # metres per pixel at the objects
    for c, area in ((1, 1.0), (2, 0.5)):
        ys, xs = np.nonzero(cls == c)
        assert (xs.max() - xs.min() + 1) * px == pytest.approx(1.0, abs=2 * px)
        assert (ys.max() - ys.min() + 1) * px == pytest.approx(1.0, abs=2 * px)
        assert len(xs) * px * px == pytest.approx(area, rel=0.03)
    # The cone's apex is up: its top rows are narrower than its bottom rows.
    ys, xs = np.nonzero(cls == 2)
    top, bottom = ys.min(), ys.max()
    assert (cls[top + 2] == 2).sum() < (cls[bottom - 2] == 2).sum()


def test_scenario_primitives_have_the_size_they_are_given(tmp_path):
    from synthgen import scenario
    from synthgen.frame.renderer import FrameRenderer

    p = tmp_path / "s.yaml"
    p.write_text("seed: 3\ncount: 1\nresolution: [64, 48]\n"
                 "camera: {pose: {type: orbit, distance: 5, elevation: 15}}\n"
                 "objects:\n  - {class: can, primitive: cylinder, size: [0.3, 0.8, 0.3]}\n"
                 "  - {class: cone, primitive: cone, size: [0.5, 1.0, 0.5]}\n"
                 "render: {spp: 1}\n")
    fr = FrameRenderer(scenario.load_scenario(p))
    arrays, meta, _ = fr.render(0)
    dims = {o["class"]: o["dimensions_hwl"] for o in meta["objects"]}
    assert np.allclose(dims["can"], [0.8, 0.3, 0.3]) and np.allclose(dims["cone"], [1.0, 0.5, 0.5])  # h, w, l
    assert set(np.unique(arrays["class_id"])) == {0, 1, 2}
