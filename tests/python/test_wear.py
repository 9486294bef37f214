"""Wear presets (synthgen.wear): deterministic, calibrated coverage, relative-local bias, and
wear on models without uvs."""
from __future__ import annotations

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P
from synthgen import wear

from test_output_kitti import _asset


def _mask_texture(scene: sg.Scene, mix_id: int) -> int:
    info = scene.material_info(mix_id)
    w = info["params"]["weight"]
    assert w[0] == "texture"
    return int(w[1])


def _points(n=20000, seed=0):
    return np.random.default_rng(seed).random((n, 3)).astype(np.float32)


@pytest.mark.parametrize("effect", ["rust", "ice", "dirt"])
@pytest.mark.parametrize("amount", [0.2, 0.6])
def test_amount_is_the_covered_fraction(effect, amount):
    s = sg.Scene()
    base = s.add_material("diffuse", {"albedo": 0.5})
    m = getattr(wear, effect)(s, base, amount=amount, seed=4)
    v = s.texture_values(_mask_texture(s, m), _points())[:, 0]
    assert np.all((v >= 0.0) & (v <= 1.0))
    covered = float((v > 0.5).mean())
    assert abs(covered - amount) < 0.03, f"{effect}: covered {covered:.3f}, asked {amount}"


def test_same_seed_same_mask_other_seed_other_mask():
    def mask(seed):
        s = sg.Scene()
        m = wear.rust(s, s.add_material("diffuse", {}), seed=seed)
        return s.texture_values(_mask_texture(s, m), _points(4000))[:, 0]

    np.testing.assert_array_equal(mask(3), mask(3))
    assert np.mean(np.abs(mask(3) - mask(4))) > 0.05


def test_rust_grows_from_the_bottom_whatever_the_object_size():
    s = sg.Scene()
    m = wear.rust(s, s.add_material("diffuse", {}), amount=0.4, bottom_bias=1.0)
    tex = _mask_texture(s, m)
    for lo, hi in (((0, 0, 0), (1, 1, 1)), ((-5, 10, 3), (15, 14, 9))):
        lo, hi = np.array(lo, np.float32), np.array(hi, np.float32)
        p = lo + _points() * (hi - lo)
        v = s.texture_values(tex, p, object_lo=lo.tolist(), object_hi=hi.tolist())[:, 0]
        rel_y = (p[:, 1] - lo[1]) / (hi[1] - lo[1])
        bottom, top = (v[rel_y < 0.3] > 0.5).mean(), (v[rel_y > 0.7] > 0.5).mean()
        assert bottom > 2.0 * top, (bottom, top)


def test_parameters_are_range_checked():
    s = sg.Scene()
    base = s.add_material("diffuse", {})
    with pytest.raises(ValueError, match="amount"):
        wear.rust(s, base, amount=1.5)
    with pytest.raises(ValueError, match="direction"):
        wear.scratches(s, base, direction="w")


def test_model_without_uvs_carries_rust_scratches_ice_and_dirt():
    """A uv-less mesh (a box without uvs) rendered with each effect: the objects' pixels
    differ from the unworn render, and the labels are unchanged."""
    def render(effect):
        s = sg.Scene()
        b = P.box((1.0, 1.0, 1.0))
        mesh = s.add_mesh(b["positions"], b["indices"], normals=b["normals"])  # no uvs
        paint = s.add_material("diffuse", {"albedo": [0.1, 0.3, 0.7]})
        mat = getattr(wear, effect)(s, paint, seed=1) if effect else paint
        s.add_instance(mesh, P.rotate([0, 1, 0], 30), class_id=1, material_id=mat)
        s.add_light("environment", {"radiance": 1.0})
        pose = sg.PinholeCamera.look_at((0.0, 1.2, -3.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
        s.set_camera(sg.PinholeCamera.from_fov(35.0, 64, 64, pose))
        return s.render(spp=4, max_depth=3, seed=2)

    plain = render(None)
    obj = plain.instance_id > 0
    for effect in ("rust", "scratches", "ice", "dirt"):
        r = render(effect)
        np.testing.assert_array_equal(r.instance_id, plain.instance_id)
        changed = np.abs(r.albedo - plain.albedo).max(axis=-1) > 0.05
        frac = changed[obj].mean()
        assert 0.02 < frac < 0.98, f"{effect}: {frac:.3f} of the object's pixels changed albedo"


def test_gallery_renders_every_effect_on_every_object():
    from synthgen.frame import gallery

    img = gallery.render_gallery(tile_w=48, tile_h=36, spp=1)
    rows, cols = len(gallery.OBJECTS), len(gallery.EFFECTS)
    assert img.shape == (rows * (36 + 32), cols * 48, 3)
    tiles = img.reshape(rows, 36 + 32, cols, 48, 3)[:, :36]
    # Every worn tile differs from the clean one of its row.
    for r in range(rows):
        for c in range(1, cols):
            assert np.abs(tiles[r, :, c] - tiles[r, :, 0]).mean() > 1e-3, (gallery.OBJECTS[r], gallery.EFFECTS[c][0])


def test_dirt_gathers_in_creases_by_ambient_occlusion():
    """A box standing on a ground plane, both dirty (AO-driven, no gravity bias, no noise
    variation that matters): the ground's albedo label is dirtier next to the box (crease)
    than far from it; without the AO term it is not."""
    def ground_albedo(ao_weight):
        s = sg.Scene()
        g = P.plane(6.0, 6.0)
        gm = s.add_mesh(g["positions"], g["indices"], normals=g["normals"])
        b = P.box((1.0, 1.0, 1.0))
        bm = s.add_mesh(b["positions"], b["indices"], normals=b["normals"])
        base = s.add_material("diffuse", {"albedo": 0.8})
        dirty = wear.dirt(s, base, amount=0.05, scale=0.5, bottom_bias=0.0, ao_radius=0.5, ao_weight=ao_weight,
                          seed=1)
        s.add_instance(gm, None, class_id=1, material_id=dirty)
        s.add_instance(bm, P.translate([0.0, 0.5, 0.0]), class_id=2, material_id=base)
        s.add_light("environment", {"radiance": 1.0})
        pose = sg.PinholeCamera.look_at((0.0, 4.0, -0.01), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
        s.set_camera(sg.PinholeCamera.from_fov(70.0, 96, 96, pose))
        r = s.render(spp=1, max_depth=2, seed=3)
        return np.asarray(r.albedo)[..., 0], np.asarray(r.class_id), np.asarray(r.depth)

    alb, cls, depth = ground_albedo(1.0)
    # Ground pixels: near the box (within ~0.25 m of its footprint edge) vs far (> 1.2 m away).
    K = sg.PinholeCamera.from_fov(70.0, 96, 96, None).K
    y, x = np.mgrid[0:96, 0:96] + 0.5
    wx = (x - K[0][2]) / K[0][0] * depth  # camera x; looking straight down, |x|, |y| ~ world footprint
    wz = (y - K[1][2]) / K[1][1] * depth
    dist = np.maximum(np.abs(wx), np.abs(wz)) - 0.5  # distance outside the box's square footprint
    ground = cls == 1
    near = ground & (dist > 0.02) & (dist < 0.25)
    far = ground & (dist > 1.2)
    assert near.sum() > 50 and far.sum() > 200
    dirty = lambda a: a < 0.5  # noqa: E731  (dirt colour is dark, the base 0.8)
    assert dirty(alb[near]).mean() > dirty(alb[far]).mean() + 0.3
    alb0, _, _ = ground_albedo(0.0)
    assert abs(dirty(alb0[near]).mean() - dirty(alb0[far]).mean()) < 0.2


def test_scratch_depth_tilts_the_normal_only_inside_the_scratches():
    """scratches(depth > 0): the metal in a scratch follows the groove's walls (bump map of the
    line profile). Rendered with and without depth: pixels showing only the paint (albedo of
    the base) are identical (to float rounding); pixels in the scratches' walls change."""
    def render(depth):
        s = sg.Scene()
        g = P.plane(4.0, 4.0)
        mesh = s.add_mesh(g["positions"], g["indices"], normals=g["normals"])  # no uvs needed
        base = s.add_material("diffuse", {"albedo": [0.6, 0.1, 0.1]})
        # (The cellular style: lines wider than a pixel here, so that paint pixels see no groove.)
        mat = wear.scratches(s, base, density=3.0, width=0.05, seed=3, roughness=0.2, depth=depth, style="cells")
        s.add_instance(mesh, np.eye(4), class_id=1, material_id=mat)
        s.add_light("sun", {"direction": [0.4, 1.0, 0.2], "irradiance": 3.0, "angular_diameter": 0.0})
        pose = sg.PinholeCamera.look_at((0.0, 2.5, -0.8), (0.0, 0.0, 0.2), (0.0, 1.0, 0.0))
        s.set_camera(sg.PinholeCamera.from_fov(50.0, 96, 96, pose))
        r = s.render(spp=4, max_depth=2, seed=5)
        return np.asarray(r.rgb, np.float64), np.asarray(s.render(spp=1, labels_only=True).albedo, np.float64)

    flat, albedo = render(0.0)
    grooved, _ = render(0.002)
    at_paint = np.all(np.abs(albedo - [0.6, 0.1, 0.1]) < 1e-6, axis=-1)
    scratch = ~at_paint & (albedo.sum(axis=-1) > 0)
    # Pixels whose neighbours show paint too (a pixel's samples spread over its footprint).
    paint = at_paint.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            paint &= np.roll(np.roll(at_paint, dy, axis=0), dx, axis=1)
    assert paint.sum() > 1000 and scratch.sum() > 300, (paint.sum(), scratch.sum())
    # (Within float rounding: a zero bump still renormalizes the normal, to the last bit.)
    np.testing.assert_allclose(flat[paint], grooved[paint], rtol=2e-6, atol=0, err_msg="the paint is unchanged")
    changed = np.abs(flat[scratch] - grooved[scratch]).max(axis=-1) > 1e-3
    print(f"\n[scratch depth] {paint.sum()} paint pixels unchanged, {changed.mean():.2f} of {scratch.sum()} scratch pixels changed")
    assert changed.mean() > 0.3, f"only {changed.mean():.2f} of the scratch pixels changed"
    with pytest.raises(sg.SynthgenError, match="depth"):
        wear.scratches(sg.Scene(), 0, depth=0.5)


CAR = "mesh/sumo-car-normal-citrus"


def _car_views(tmp_path, effect, params, distance, elevation, azimuths):
    """The library car (a palette paint) from four sides, with the wear ``effect`` of ``params``
    (YAML) and clean (the same frames: the effect's probability 0), 8 frames each. Yields, per frame, (meta, worn albedo,
    clean albedo at the car's pixels, the car's pixels as world points (4 x N))."""
    import json
    import os

    import OpenImageIO as oiio

    from synthgen import run as runner

    _asset(CAR)

    def render(name, wear):
        d = tmp_path / name
        d.mkdir(parents=True)
        (d / "s.yaml").write_text(f"""
seed: 5
resolution: [320, 240]
camera: {{fov_y: 30, pose: {{type: orbit, target: [0, 0.8, 0], distance: {distance}, elevation: {elevation},
  azimuth: {{choice: {list(azimuths)}}}}}}}
lights: [{{type: environment, radiance: 1.0}}]
objects: [{{class: car, asset: {CAR}, yaw: 0, paint: {{palette: cars}}, wear: {{{effect}: {wear}}}}}]
placement: {{region: [-0.01, -0.01, 0.01, 0.01]}}
render: {{spp: 1, max_depth: 1}}
outputs: [albedo, instance, depth]
""")
        s = runner.run(str(d / "s.yaml"), str(d / "ds"), count=8, progress=False)
        assert not s["failures"], s.text()
        return str(d / "ds")

    worn, clean = render("worn", params), render("clean", "{probability: 0}")
    for k in range(8):
        meta = json.load(open(os.path.join(worn, "meta", f"{k:06d}.json")))
        a1 = oiio.ImageBuf(os.path.join(worn, "albedo", f"{k:06d}.exr")).get_pixels(oiio.FLOAT)
        a0 = oiio.ImageBuf(os.path.join(clean, "albedo", f"{k:06d}.exr")).get_pixels(oiio.FLOAT)
        ids = oiio.ImageBuf(os.path.join(worn, "instance", f"{k:06d}.png")).get_pixels(oiio.UINT16)[..., 0]
        depth = oiio.ImageBuf(os.path.join(worn, "depth", f"{k:06d}.exr")).get_pixels(oiio.FLOAT)[..., 0]
        K, W = np.asarray(meta["camera"]["K"]), np.asarray(meta["camera"]["world_from_camera"])
        ys, xs = np.nonzero(ids == 1)
        z = depth[ys, xs]
        cam = np.stack([(xs + 0.5 - K[0, 2]) / K[0, 0] * z, (ys + 0.5 - K[1, 2]) / K[1, 1] * z, z, np.ones_like(z)])
        yield meta, a1[ys, xs], a0[ys, xs], W @ cam


def test_dirt_on_a_library_car_is_densest_low(tmp_path):
    """Road grime on a library car, measured on its renders from four sides (albedo labels of
    the dirty car against the clean one: how far each pixel moved towards the dirt): the
    bottom fifth of the body carries at least 3x the dirt of the top fifth."""
    bands = np.zeros((5, 2))
    for meta, c1, c0, world in _car_views(tmp_path, "dirt", "{amount: 0.25}", 9, 12, (0, 90, 180, 270)):
        col = np.asarray(meta["objects"][0]["wear"]["dirt"]["color"])
        height = world[1] / meta["objects"][0]["dimensions_hwl"][0]
        band = np.clip((height * 5).astype(int), 0, 4)
        towards = np.linalg.norm(col - c0, axis=1)
        w = np.where(towards > 0.05, np.clip(np.linalg.norm(c1 - c0, axis=1) / np.maximum(towards, 1e-6), 0, 1), 0.0)
        for i in range(5):
            bands[i] += (w[band == i].sum(), (band == i).sum())
    cover = bands[:, 0] / np.maximum(bands[:, 1], 1)
    print(f"\ndirt by fifth of the car's height (bottom to top): {np.round(cover, 3).tolist()}")
    assert cover[0] >= 3.0 * cover[4], cover


def _crease_edges(pos, tri, min_angle_deg=35.0):
    """Segments (E x 2 x 3) of a mesh's sharp edges: borders (one face) and edges whose faces
    meet at more than ``min_angle_deg``."""
    fn = np.cross(pos[tri[:, 1]] - pos[tri[:, 0]], pos[tri[:, 2]] - pos[tri[:, 0]])
    fn /= np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-30)
    faces = {}
    for f, t in enumerate(tri):
        for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            # Welded by position (imported meshes split vertices at uv seams).
            ka, kb = tuple(np.round(pos[a], 5)), tuple(np.round(pos[b], 5))
            faces.setdefault((min(ka, kb), max(ka, kb)), []).append(f)
    cos_max = np.cos(np.radians(min_angle_deg))
    out = [k for k, fs in faces.items() if len(fs) == 1 or (len(fs) == 2 and fn[fs[0]] @ fn[fs[1]] < cos_max)]
    return np.asarray(out, np.float64)


def _distance_to_segments(p, seg, chunk=4096):
    out = np.full(len(p), np.inf)
    a, b = seg[:, 0], seg[:, 1]
    ab = b - a
    L2 = np.maximum((ab * ab).sum(1), 1e-30)
    for i in range(0, len(p), chunk):
        q = p[i:i + chunk, None, :]
        t = np.clip(((q - a) * ab).sum(-1) / L2, 0, 1)
        d = np.linalg.norm(q - (a + t[..., None] * ab), axis=-1)
        out[i:i + chunk] = d.min(1)
    return out


def _near_edges_and_open(tmp_path, effect, params):
    """Fractions of the library car's pixels the wear ``effect`` changed (albedo labels against
    the clean car, four sides): within 2 cm of the mesh's sharp edges (borders, and faces meeting
    at over 35 degrees), and on open panels (over 10 cm from them)."""
    from synthgen.frame.resources import Shapes
    from synthgen.scene import assets

    _asset(CAR)
    scene = sg.Scene()
    shape = Shapes(scene).get("asset", CAR)
    arrays = scene.mesh_arrays(shape.mesh_id)
    seg = _crease_edges(np.asarray(arrays["positions"], np.float64), np.asarray(arrays["indices"], np.int64))
    unit = float(assets.entry(CAR).get("scale", 1.0))
    near, open_ = [], []
    for meta, c1, c0, world in _car_views(tmp_path, effect, params, 8, 20, (30, 120, 210, 300)):
        obj = np.linalg.inv(np.asarray(meta["objects"][0]["world_from_object"])) @ world
        dist = _distance_to_segments(obj[:3].T, seg) * unit  # metres
        worn = np.abs(c1 - c0).max(axis=1) > 0.05
        near.append(worn[dist < 0.02])
        open_.append(worn[dist > 0.10])
    near, open_ = np.concatenate(near), np.concatenate(open_)
    assert near.size > 500 and open_.size > 500
    return near, open_


def test_rust_starts_at_the_edges_of_a_library_car(tmp_path):
    """Rust on a library car: within 2 cm of the mesh's sharp edges it covers at least twice
    what it covers on open panels (over 10 cm from them)."""
    near, open_ = _near_edges_and_open(tmp_path, "rust", "{amount: 0.1, bottom_bias: 0}")
    print(f"\nrust within 2 cm of sharp edges: {near.mean():.3f} of {near.size} px; on open panels (over 10 cm "
          f"from them): {open_.mean():.3f} of {open_.size} px")
    assert near.mean() >= 2.0 * open_.mean()


def test_scratch_clusters_gather_at_the_edges_of_a_library_car(tmp_path):
    """Scratches in clusters (amount < 1) on a library car gather at its edges and handles: near
    its sharp edges they cover at least 1.5x what they cover on open panels, and without the
    edge term (edges: 0) they do not."""
    params = "{amount: 0.25, density: 4, width: 0.12}"
    near, open_ = _near_edges_and_open(tmp_path / "edges", "scratches", params)
    near0, open0 = _near_edges_and_open(tmp_path / "anywhere", "scratches", params[:-1] + ", edges: 0}")
    print(f"\nscratched within 2 cm of sharp edges / on open panels: {near.mean():.3f} / {open_.mean():.3f} "
          f"(edges: 0: {near0.mean():.3f} / {open0.mean():.3f})")
    assert near.mean() >= 1.5 * open_.mean()
    assert near0.mean() < 1.5 * open0.mean()


def test_the_car_row_shows_every_effect_on_the_library_car():
    """The gallery's car row (docs/gallery_car.png): the library car, clean and with each effect;
    every effect changes its tile (rendered small here)."""
    from synthgen.frame import gallery

    _asset(CAR)
    w, h = 160, 120
    img = gallery.render_car_row(tile_w=w, tile_h=h, spp=2)
    n = len(gallery.CAR_EFFECTS)
    assert img.shape == (h + 32, n * w, 3)
    tiles = [img[:h, i * w:(i + 1) * w] for i in range(n)]
    for (name, _), t in zip(gallery.CAR_EFFECTS[1:], tiles[1:]):
        # The car is a third of the width: a part of the tile changes, clearly.
        changed = (np.abs(t - tiles[0]).max(axis=2) > 0.02).mean()
        assert changed > 0.002, (name, changed)


def test_rust_creeps_out_from_the_scratches():
    """Rust given the scratches' lines (the wear randomizer passes them when an instance gets
    both) covers the scratched paint and a halo around it far more than the rest: measured on a
    plane through the object, against the same rust without the scratches."""
    n = 400
    ys, xs = np.mgrid[0:n, 0:n] / n
    pts = np.stack([xs.ravel(), ys.ravel(), np.full(n * n, 0.5)], 1).astype(np.float32)
    lines = {"seed": 3, "density": 8.0, "width": 0.04}  # the scratches' line parameters
    s = sg.Scene()
    on_line = s.texture_values(wear.add_scratch_lines(s, **lines), pts)[:, 0] > 0.0

    def coverage(**kw):
        m = wear.rust(s, s.add_material("diffuse", {}), seed=2, amount=0.15, bottom_bias=0.0, streaks=0.0,
                      edges=0.0, **kw)
        v = s.texture_values(_mask_texture(s, m), pts)[:, 0] > 0.5
        return v[on_line].mean(), v[~on_line].mean()

    with_lines, without = coverage(scratch_lines=lines), coverage()
    print(f"\nrust on scratch lines / elsewhere: with the scratches {with_lines[0]:.3f} / {with_lines[1]:.3f}, "
          f"without {without[0]:.3f} / {without[1]:.3f}; scratched {on_line.mean():.3f} of the plane")
    assert 0.01 < on_line.mean() < 0.3
    assert with_lines[0] >= 3.0 * with_lines[1]
    assert without[0] < 1.5 * without[1]  # the noise alone does not follow the lines
    off = coverage(scratch_lines=lines, from_scratches=0.0)
    assert off == pytest.approx(without)
