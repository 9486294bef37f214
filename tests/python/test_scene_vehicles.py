"""synthgen.scene.vehicles: wheels built for a body that comes without them stand where the car
file says (axles, track, radius), touch the ground, and the body rides at its height; smooth
normals keep creases; a bad wheels block in the manifest is refused with its key."""
import math

import numpy as np
import pytest

from synthgen.scene import assets
from synthgen.scene.vehicles import build_vehicle, crease_normals, model_axes, wheel_mesh


def test_a_wheel_has_its_radius_width_and_rim():
    m, part = wheel_mesh(0.33, 0.235, 0.2)
    p = m["positions"]
    r = np.hypot(p[:, 0], p[:, 1])
    assert r.max() == pytest.approx(0.33, abs=1e-6)
    assert np.ptp(p[:, 2]) == pytest.approx(0.235, abs=1e-6)
    rim = np.unique(m["indices"][part == 1])
    assert r[rim].max() == pytest.approx(0.2, abs=1e-6)
    # Normals are unit and point away from the wheel's centre on the tread.
    n = m["normals"]
    assert np.allclose(np.linalg.norm(n, axis=1), 1, atol=1e-5)
    tread = r > 0.3299
    assert (np.sum(n[tread, :2] * p[tread, :2], axis=1) > 0).all()


def test_crease_normals_keep_a_cubes_edges_and_smooth_a_sphere():
    # A cube: every corner keeps its face's normal (6 faces x 4 corners).
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tri = np.array([t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))])
    corner, src, n = crease_normals(v, tri)
    assert len(src) == 24
    for t, (i, j, k) in zip(corner, tri):
        fn = np.cross(v[j] - v[i], v[k] - v[i])
        fn /= np.linalg.norm(fn)
        assert np.allclose(n[t], fn, atol=1e-6)
    # A fine sphere: the normals are the radial directions (within the facets' angle).
    from synthgen.scene import primitives as P

    s = P.uv_sphere(1.0, 48, 24)
    corner, src, n = crease_normals(np.asarray(s["positions"]), np.asarray(s["indices"]))
    p = np.asarray(s["positions"])[src]
    assert np.degrees(np.arccos(np.clip(np.sum(n * p / np.linalg.norm(p, axis=1, keepdims=True), 1), -1, 1))).max() < 5


def test_wheels_stand_at_the_axles_and_the_body_at_its_ride_height():
    # A box body 4 x 1 x 1.6 m (x forward, y up), its bottom at y = 0.3 before the lift.
    v = np.array([[x, y, z] for x in (-2, 2) for y in (0.3, 1.3) for z in (-0.8, 0.8)], float)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tri = np.array([t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))], np.uint32)
    body = {"positions": v.astype(np.float32), "indices": tri, "material_ids": np.full(len(tri), 7, np.int32)}
    entry = {"forward": "+x", "up": "+y", "ride_height": 0.15,
             "wheels": {"axles": [1.3, -1.25], "track": [1.5, 1.55], "radius": 0.33, "width": 0.22}}
    out = build_vehicle(body, entry, 1.0, tyre_material=1, rim_material=2)
    p, mids, t = out["positions"], out["material_ids"], out["indices"]
    body_v = np.unique(t[mids == 7])
    assert p[body_v, 1].min() == pytest.approx(0.15, abs=1e-5)
    assert p[:, 1].min() == pytest.approx(0.0, abs=1e-5)  # the tyres touch the ground
    wheel_v = np.unique(t[(mids == 1) | (mids == 2)])
    # Four wheels: cluster the wheel vertices by their centre.
    q = p[wheel_v]
    for ax, tr in ((1.3, 1.5), (-1.25, 1.55)):
        for side in (-1, 1):
            sel = (np.abs(q[:, 0] - ax) < 0.4) & (np.sign(q[:, 2]) == side)
            c = 0.5 * (q[sel].min(0) + q[sel].max(0))
            assert c == pytest.approx([ax, 0.33, side * tr / 2], abs=1e-4)
            assert np.ptp(q[sel][:, 2]) == pytest.approx(0.22, abs=1e-4)
    assert len(out["normals"]) == len(p) and out["uvs"] is None


def test_model_axes_refuse_parallel_axes():
    assert np.allclose(model_axes("+z", "+y")[2], [-1, 0, 0])  # right = forward x up
    with pytest.raises(ValueError):
        model_axes("+x", "-x")


@pytest.mark.parametrize("wheels, message", [
    ({"axles": [1.3], "track": 1.5, "radius": 0.3}, "missing key 'width'"),
    ({"axles": [1.3], "track": 1.5, "radius": 0.3, "width": 0.2, "rim_radus": 0.2}, "did you mean 'rim_radius'"),
    ({"axles": [1.3, -1.3], "track": [1.5, 1.5, 1.5], "radius": 0.3, "width": 0.2}, "one per axle"),
    ({"axles": [1.3], "track": 1.5, "radius": 0.3, "width": 0.2, "rim_radius": 0.4}, "less than radius"),
])
def test_a_bad_wheels_block_is_refused(tmp_path, wheels, message):
    import yaml

    (tmp_path / "m.yaml").write_text(yaml.safe_dump({"assets": [{
        "id": "mesh/x", "kind": "mesh", "licence": "CC0-1.0", "sha256": "0" * 64, "source": {"path": "x.obj"},
        "wheels": wheels}]}))
    with pytest.raises(assets.AssetError, match=message):
        assets.load_manifest(str(tmp_path))


def test_revolve_closes_at_the_axis():
    from synthgen.scene.vehicles import revolve

    m = revolve([(0.0, 0.0), (1.0, 0.0)], 16)  # a disc
    p = m["positions"][m["indices"]]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
    assert area == pytest.approx(0.5 * 16 * math.sin(2 * math.pi / 16), rel=1e-5)
