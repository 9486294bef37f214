"""Levels of detail of library models (synthgen.scene.lod, docs/geometry_lod.md): exact surface
distances, the Hausdorff error of a level, the projected-error bound, the manifest's ``lods``, and
frames rendered with the coarsest level under half a pixel against the finest (mask IoU >= 0.98).
A sphere tessellated four ways stands in for a model with levels; the TORCS cars are tested
when they are in the cache."""
import math
import os

import numpy as np
import pytest
import yaml

from synthgen._core import PinholeCamera, surface_distances
from synthgen.frame.renderer import FrameRenderer
from synthgen.scenario import check_inputs, load_scenario
from synthgen.scene import assets
from synthgen.scene import primitives as P
from synthgen.scene.assets import AssetError
from synthgen.scene.lod import choose_level, geometric_error, projected_error_px

SQUARE = (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32), np.array([[0, 1, 2], [0, 2, 3]]))


def test_surface_distances_are_exact_against_a_square():
    pts = np.array([[0.5, 0.5, 2.0], [2.0, 0.5, 0.0], [2.0, 2.0, 1.0], [0.25, 0.75, -0.5], [-3, -4, 0]], np.float32)
    d, tri = surface_distances(*SQUARE, pts, return_triangles=True)
    expect = [2.0, 1.0, math.sqrt(3.0), 0.5, 5.0]
    assert np.allclose(d, expect, atol=1e-6), d
    assert tri[3] == 1  # (0.25, 0.75) lies over the second triangle (0, 2, 3)
    assert np.array_equal(surface_distances(*SQUARE, pts), d)


def test_surface_distances_bad_input_is_an_error():
    with pytest.raises(Exception, match="out of range"):
        surface_distances(SQUARE[0], np.array([[0, 1, 9]]), np.zeros((1, 3), np.float32))
    with pytest.raises(Exception, match="not finite"):
        surface_distances(*SQUARE, np.array([[np.nan, 0, 0]], np.float32))
    with pytest.raises(Exception, match=r"\(n, 3\)"):
        surface_distances(*SQUARE, np.zeros((2, 2), np.float32))


def test_geometric_error_of_nested_cubes_is_their_hausdorff_distance():
    box = P.box((1.0, 1.0, 1.0))
    small = (np.asarray(box["positions"]), np.asarray(box["indices"]))
    big = (1.1 * small[0], small[1])
    # Outer corner (0.55, 0.55, 0.55) to the inner cube's corner: 0.05 sqrt(3); the inner
    # surface is 0.05 from the outer everywhere.
    assert geometric_error(small, big, n=20000) == pytest.approx(0.05 * math.sqrt(3), abs=1e-5)
    assert geometric_error(small, small, n=2000) == pytest.approx(0.0, abs=1e-6)


def _sphere(segments):
    s = P.uv_sphere(1.0, segments, segments // 2)
    return np.asarray(s["positions"]), np.asarray(s["indices"])


def test_geometric_error_of_a_coarser_sphere_is_its_sagitta():
    # A uv sphere of n segments lies inside the unit sphere; its faces sag from it by at most
    # about 1 - cos(pi / n) (the sagitta of an edge, larger at the face centres).
    fine, coarse = _sphere(256), _sphere(16)
    err = geometric_error(fine, coarse, n=50000)
    sagitta = 1 - math.cos(math.pi / 16)
    assert sagitta < err < 2.2 * sagitta, (err, sagitta)


def _camera(w=320, h=240, fov=40.0, eye=(0, 0, 0), target=(0, 0, 1)):
    return PinholeCamera.from_fov(fov, w, h, PinholeCamera.look_at(list(eye), list(target), [0.0, 1.0, 0.0]))


def _project(camera, pts):
    wfc = np.asarray(camera.world_from_camera, np.float64)
    c = (pts - wfc[:3, 3]) @ wfc[:3, :3]
    return np.stack([camera.fx * c[:, 0] / c[:, 2] + camera.cx, camera.fy * c[:, 1] / c[:, 2] + camera.cy], 1)


def test_projected_error_bounds_every_displacement_in_view():
    rng = np.random.default_rng(3)
    cam = _camera(eye=(0.3, 1.2, -2.0), target=(0.0, 0.5, 9.0))
    lo, hi = np.array([-1.0, -0.5, -2.0]), np.array([1.0, 0.5, 2.0])
    for trial in range(20):
        m = np.eye(4)
        m[:3, :3] = np.diag(rng.uniform(0.5, 2.0, 3))
        m[:3, 3] = [rng.uniform(-4, 4), rng.uniform(-1, 2), rng.uniform(8, 30)]
        err = 0.05
        bound = projected_error_px(err, m, lo, hi, cam)
        pts = rng.uniform(lo, hi, (4000, 3))
        d = rng.normal(size=(4000, 3))
        d *= err / np.linalg.norm(d, axis=1, keepdims=True)
        world = lambda x: x @ m[:3, :3].T + m[:3, 3]  # noqa: E731
        a, b = _project(cam, world(pts)), _project(cam, world(pts + d))
        inside = (a[:, 0] >= 0) & (a[:, 0] <= 320) & (a[:, 1] >= 0) & (a[:, 1] <= 240)
        if inside.any():
            moved = np.linalg.norm(a - b, axis=1)[inside].max()
            assert moved <= bound, (trial, moved, bound)
            assert moved > 0.2 * bound, (trial, moved, bound)  # a bound, not a wild one


def test_choose_level_takes_the_coarsest_under_the_limit():
    cam = _camera()
    f, corner = max(cam.fx, cam.fy), 1 + (160 / cam.fx) ** 2 + (120 / cam.fy) ** 2
    lo, hi = np.full(3, -1.0), np.full(3, 1.0)
    m = np.eye(4)
    m[2, 3] = 20.0
    z = 20.0 - math.sqrt(3.0)
    assert projected_error_px(0.01, m, lo, hi, cam) == pytest.approx(f * 0.01 * math.sqrt(corner) / z)
    errors = [0.0, 0.004, 0.01, 0.04, 0.2]
    px = [projected_error_px(e, m, lo, hi, cam) for e in errors]
    assert choose_level(errors, m, lo, hi, cam, 0.5) == max(k for k, p in enumerate(px) if p < 0.5)
    assert choose_level(errors, m, lo, hi, cam, 0.0) == 0
    m[2, 3] = 0.5  # the camera inside the bounds: the finest
    assert projected_error_px(0.001, m, lo, hi, cam) == math.inf
    assert choose_level(errors, m, lo, hi, cam, 8.0) == 0


def _write_obj(path, mesh):
    pos, tri = mesh
    with open(path, "w") as f:
        f.writelines(f"v {x:.7f} {y:.7f} {z:.7f}\n" for x, y, z in pos)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in np.asarray(tri).reshape(-1, 3))


@pytest.fixture
def sphere_library(tmp_path, monkeypatch):
    """A library with one model, a ball (1 m radius) of four levels of detail."""
    src = tmp_path / "src"
    src.mkdir()
    levels = [_sphere(n) for n in (128, 80, 40, 12)]
    for k, m in enumerate(levels):
        _write_obj(src / f"ball{k}.obj", m)
    lods = [{"path": str(src / f"ball{k}.obj"), "sha256": assets.file_sha256(str(src / f"ball{k}.obj")),
             "error": round(geometric_error(levels[0], levels[k], n=20000) * 1.0001 + 1e-6, 6)} for k in (1, 2, 3)]
    entry = {"id": "mesh/test-ball", "kind": "mesh", "class": "ball", "licence": "CC0-1.0",
             "sha256": assets.file_sha256(str(src / "ball0.obj")), "source": {"path": str(src / "ball0.obj")},
             "lods": lods}
    mdir = tmp_path / "manifest"
    mdir.mkdir()
    (mdir / "balls.yaml").write_text(yaml.safe_dump({"assets": [entry]}))
    monkeypatch.setenv("SYNTHGEN_MANIFEST", str(mdir))
    monkeypatch.setenv("SYNTHGEN_CACHE", str(tmp_path / "cache"))
    return tmp_path, [0.0] + [lod["error"] for lod in lods]


def _renderer(tmp_path, max_px, distance, min_iou=0.98):
    scen = tmp_path / f"s{max_px}.yaml"
    scen.write_text(f"""
seed: 4
resolution: [320, 240]
camera: {{fov_y: 40, pose: {{type: orbit, target: [0, 1, 0], distance: {distance}, elevation: 3, azimuth: 0}}}}
lights: [{{type: environment, radiance: 1.0}}]
objects: [{{class: ball, asset: mesh/test-ball}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 1, max_depth: 1, geometry_lod: {max_px}, geometry_lod_iou: {min_iou}}}
""")
    sc = load_scenario(str(scen))
    check_inputs(sc)
    return FrameRenderer(sc)


@pytest.mark.parametrize("distance", [6.0, 15.0, 30.0, 50.0])
def test_levels_of_detail_keep_masks_and_save_triangles(sphere_library, distance):
    tmp_path, errors = sphere_library
    fine, coarse = _renderer(tmp_path, 0.0, distance), _renderer(tmp_path, 0.5, distance)
    a, meta_a, _ = fine.render(0)
    b, meta_b, _ = coarse.render(0)
    g = meta_b["geometry_lod"]
    level = g["levels"]["0"]
    assert meta_a["geometry_lod"]["levels"] == {"0": 0}
    o = coarse.objects[0]
    assert projected_error_px(errors[level], o.world, o.shape.lo, o.shape.hi, coarse.camera) < 0.5
    assert level >= 1 and g["triangles"] < g["triangles_finest"], g
    ma, mb = a["instance_id"] == 1, b["instance_id"] == 1
    assert ma.sum() > 100
    iou = (ma & mb).sum() / (ma | mb).sum()
    assert iou >= 0.98, (distance, level, iou)
    assert g["mask_iou"]["0"] >= 0.98  # measured on the amodal mask when the level was chosen


def test_without_the_mask_guard_the_coarsest_level_under_half_a_pixel(sphere_library):
    # (as for unlabelled objects: no mask to keep)
    tmp_path, errors = sphere_library
    for distance, expect in [(6.0, 1), (400.0, 3)]:
        r = _renderer(tmp_path, 0.5, distance, min_iou=0.0)
        _, meta, _ = r.render(0)
        o = r.objects[0]
        assert meta["geometry_lod"]["levels"]["0"] == expect
        px = [projected_error_px(e, o.world, o.shape.lo, o.shape.hi, r.camera) for e in errors]
        assert px[expect] < 0.5 and (expect + 1 == len(errors) or px[expect + 1] >= 0.5), px


def test_manifest_lods_are_checked(tmp_path):
    base = {"id": "mesh/x", "kind": "mesh", "licence": "CC0-1.0", "sha256": "0" * 64, "source": {"path": "x.obj"}}
    for lods, message in [([], "expected a list"), ([{"path": "a.obj", "sha256": "0" * 64}], "exactly the keys"),
                          ([{"path": "a.obj", "sha256": "0" * 64, "error": -1}], "positive number"),
                          ([{"path": "a.obj", "sha256": "abc", "error": 0.1}], "64 hex")]:
        (tmp_path / "m.yaml").write_text(yaml.safe_dump({"assets": [dict(base, lods=lods)]}))
        with pytest.raises(AssetError, match=message):
            assets.load_manifest(str(tmp_path))


def test_torcs_car_levels_keep_its_masks():
    """A TORCS car with levels at distances where they apply: its mask against the finest."""
    aid = "mesh/torcs-p406"
    e = assets.load_manifest()[aid]
    cached = os.path.join(assets.cache_dir(), aid, os.path.basename(e["source"]["path"]))
    if not os.path.isfile(cached):
        pytest.skip(f"{aid} is optional and not in the cache (synthgen assets fetch {aid})")
    assets.resolve(aid)
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        for distance in (25.0, 40.0):
            rs = []
            for max_px in (0.0, 0.5):
                path = os.path.join(tmp, f"s{max_px}.yaml")
                with open(path, "w") as f:
                    f.write(f"""
seed: 1
resolution: [640, 480]
camera: {{fov_y: 30, pose: {{type: orbit, target: [0, 0.8, 0], distance: {distance}, elevation: 6, azimuth: 35}}}}
lights: [{{type: environment, radiance: 1.0}}]
objects: [{{class: car, asset: {aid}}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 1, max_depth: 1, geometry_lod: {max_px}}}
""")
                sc = load_scenario(path)
                check_inputs(sc)
                rs.append(FrameRenderer(sc).render(0))
            (a, _, _), (b, meta, _) = rs
            assert meta["geometry_lod"]["levels"]["0"] >= 1, meta["geometry_lod"]
            ma, mb = a["instance_id"] == 1, b["instance_id"] == 1
            assert (ma & mb).sum() / (ma | mb).sum() >= 0.98
