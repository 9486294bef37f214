"""Label outputs against analytic ground truth computed with numpy.

The camera has a non-trivial pose (look_at) and asymmetric intrinsics (fx != fy, principal point
off the image centre). Every expectation is derived here from K and world_from_camera in float64,
never through the library's project() / generate_ray(): labels come from one camera ray through
each pixel centre (i + 0.5, j + 0.5), whose camera-space direction is ((i+0.5-cx)/fx, (j+0.5-cy)/fy, 1).
"""
from __future__ import annotations

import numpy as np

import synthgen as sg
from synthgen import primitives as P

FX, FY, CX, CY, W, H = 310.0, 345.0, 71.3, 52.9, 150, 110
EYE, TARGET, UP = (1.2, 0.8, -3.5), (-0.3, 0.2, 1.0), (0.1, 1.0, 0.05)
REL = 1e-5


def make_camera() -> sg.PinholeCamera:
    wfc = sg.PinholeCamera.look_at(EYE, TARGET, UP)
    return sg.PinholeCamera(fx=FX, fy=FY, cx=CX, cy=CY, width=W, height=H, world_from_camera=wfc)


def pose(cam):
    """(R, t) of world_from_camera in float64."""
    m = np.asarray(cam.world_from_camera, dtype=np.float64)
    return m[:3, :3], m[:3, 3]


def pixel_rays_cam() -> np.ndarray:
    """H x W x 3 camera-space directions with z = 1 through the pixel centres."""
    j, i = np.mgrid[0:H, 0:W].astype(np.float64)
    return np.stack([(i + 0.5 - CX) / FX, (j + 0.5 - CY) / FY, np.ones_like(i)], axis=-1)


def quad(center, axis_u, axis_v, half: float, normal):
    """Two triangles spanning center +- half*axis_u +- half*axis_v, wound so that the geometric
    normal is `normal` (which is also stored as the vertex normal)."""
    c, u, v, n = (np.asarray(a, dtype=np.float64) for a in (center, axis_u, axis_v, normal))
    p = np.array([c - half * u - half * v, c + half * u - half * v, c + half * u + half * v, c - half * u + half * v])
    idx = np.array([[0, 1, 2], [0, 2, 3]])
    if np.dot(np.cross(p[1] - p[0], p[2] - p[0]), n) < 0:
        idx = idx[:, ::-1]
    return dict(positions=p.astype(np.float32), indices=idx.astype(np.uint32),
                normals=np.tile(n / np.linalg.norm(n), (4, 1)).astype(np.float32))


def test_look_at_matches_numpy():
    """look_at's pose is the OpenCV frame: z towards the target, x = z cross up, y = z cross x (down)."""
    cam = make_camera()
    R, t = pose(cam)
    z = np.subtract(TARGET, EYE)
    z /= np.linalg.norm(z)
    x = np.cross(z, UP)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    np.testing.assert_allclose(R, np.stack([x, y, z], axis=1), atol=1e-6)
    np.testing.assert_allclose(t, EYE, atol=1e-6)
    assert np.dot(y, UP) < 0, "image y must point along -up"


def test_fronto_parallel_plane_depth_distance_normal():
    cam = make_camera()
    R, t = pose(cam)
    d = 4.0
    x, y, z = R[:, 0], R[:, 1], R[:, 2]
    s = sg.Scene()
    mesh = s.add_mesh(**quad(t + d * z, x, y, 20.0, -z))
    mat = s.add_material("diffuse", {"albedo": [0.3, 0.6, 0.9]})
    s.add_instance(mesh, None, class_id=5, instance_id=77, material_id=mat)
    s.set_camera(cam)
    r = s.render(spp=1, max_depth=1)

    rays = pixel_rays_cam()
    assert np.all(r.instance_id == 77) and np.all(r.class_id == 5), "the plane covers the whole image"
    np.testing.assert_allclose(r.depth, d, rtol=REL, atol=0)
    # distance = d / cos(angle between the pixel-centre ray and the optical axis) = d * |r| for r_z = 1
    np.testing.assert_allclose(r.distance, d * np.linalg.norm(rays, axis=-1), rtol=REL, atol=0)
    np.testing.assert_allclose(r.normal, np.broadcast_to(-z, r.normal.shape), atol=1e-5, rtol=0)
    np.testing.assert_allclose(r.albedo, np.broadcast_to(np.float32([0.3, 0.6, 0.9]), r.albedo.shape), rtol=0, atol=1e-7)
    assert np.all(r.alpha == 1.0)
    # The plane is not trivially constant: distance grows towards the image corners.
    assert r.distance.max() > 1.01 * d


def test_tilted_plane_depth_matches_ray_plane_intersection():
    cam = make_camera()
    R, t = pose(cam)
    # Plane through the camera-space point (0.2, -0.1, 5), normal tilted by 40 degrees from -z.
    q_c = np.array([0.2, -0.1, 5.0])
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    n_c = np.asarray(P.rotate(axis, 40.0), dtype=np.float64)[:3, :3] @ np.array([0.0, 0.0, -1.0])
    u_c = np.cross(n_c, [0.0, 1.0, 0.0])
    u_c /= np.linalg.norm(u_c)
    v_c = np.cross(n_c, u_c)
    n_w, q_w = R @ n_c, R @ q_c + t
    s = sg.Scene()
    s.add_instance(s.add_mesh(**quad(q_w, R @ u_c, R @ v_c, 30.0, n_w)), None, instance_id=9)
    s.set_camera(cam)
    r = s.render(spp=1, max_depth=1)

    rays = pixel_rays_cam()
    depth = np.dot(q_c, n_c) / (rays @ n_c)  # camera-space z of the hit of X = Z * ray
    # The setup is meaningful: every pixel-centre ray hits the quad in front of the camera, and
    # the depth varies substantially across the image.
    hit = depth[..., None] * rays - q_c
    assert np.all(depth > 0) and np.abs(hit @ u_c).max() < 30 and np.abs(hit @ v_c).max() < 30
    assert depth.max() / depth.min() > 1.3
    assert np.all(r.instance_id == 9)
    np.testing.assert_allclose(r.depth, depth, rtol=REL, atol=0)
    np.testing.assert_allclose(r.distance, depth * np.linalg.norm(rays, axis=-1), rtol=REL, atol=0)
    np.testing.assert_allclose(r.normal, np.broadcast_to(n_w, r.normal.shape), atol=1e-5, rtol=0)


def _ray_line_distance(center_w, t, dirs_w):
    """Distance of each ray's line from a point, and the ray parameter of the closest approach."""
    oc = center_w - t
    along = dirs_w @ oc
    perp = oc[None, None, :] - along[..., None] * dirs_w
    return np.linalg.norm(perp, axis=-1), along


def test_sphere_mask_matches_projected_disc():
    cam = make_camera()
    R, t = pose(cam)
    radius = 0.8
    mesh = P.uv_sphere(radius, segments=256, rings=128)
    center = t + 4.0 * R @ (np.array([0.1, -0.05, 1.0]) / np.linalg.norm([0.1, -0.05, 1.0]))
    # Bounds of the tessellated sphere from the actual float32 vertices: every vertex lies within
    # r_out of the centre, and the (convex) polyhedron contains the ball of radius r_in, the
    # smallest distance from the centre to a face plane.
    pos = mesh["positions"].astype(np.float64)
    tri = pos[mesh["indices"].astype(np.int64)]
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    r_in = np.abs(np.einsum("ij,ij->i", nrm, tri[:, 0])).min()
    r_out = np.linalg.norm(pos, axis=1).max()
    assert 0.999 * radius < r_in < r_out < 1.001 * radius

    s = sg.Scene()
    s.add_instance(s.add_mesh(**mesh), P.translate(center), class_id=7, instance_id=4242,
                   material_id=s.add_material("diffuse", {"albedo": [0.5, 0.4, 0.3]}))
    s.set_camera(cam)
    r = s.render(spp=16, max_depth=1)

    rays = pixel_rays_cam()
    dirs = rays @ R.T
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    h, along = _ray_line_distance(center, t, dirs)
    inside = h < r_in * (1 - 1e-6)
    outside = h > r_out * (1 + 1e-6)
    band = ~inside & ~outside
    assert inside.sum() > 2000 and outside.sum() > 5000, "sphere must be large in the image and leave background"
    # The boundary band is the projected width r_out - r_in: far below a pixel here.
    assert band.sum() < 20

    mask = r.instance_id == 4242
    assert np.all(mask[inside]), f"{(~mask[inside]).sum()} pixels inside the inscribed disc are not labelled"
    assert not np.any(mask[outside]), f"{mask[outside].sum()} pixels outside the circumscribed disc are labelled"
    assert set(np.unique(r.instance_id[band])) <= {0, 4242}
    np.testing.assert_array_equal(r.class_id[mask], 7)

    # Background pixels: id 0, depth and distance +inf, normal and albedo 0, alpha 0 where the
    # whole pixel footprint misses (see below).
    bg = ~mask
    assert np.all(r.instance_id[bg] == 0) and np.all(r.class_id[bg] == 0)
    assert np.all(np.isposinf(r.depth[bg])) and np.all(np.isposinf(r.distance[bg]))
    assert np.all(r.normal[bg] == 0) and np.all(r.albedo[bg] == 0)
    assert np.all(np.isfinite(r.depth[mask])) and np.all(np.isfinite(r.distance[mask]))

    # Depth inside: the first hit of the polyhedron lies between the entry points of the
    # circumscribed and the inscribed sphere.
    cos = 1.0 / np.linalg.norm(rays, axis=-1)
    t_out = along - np.sqrt(np.maximum(r_out ** 2 - h ** 2, 0))
    t_in = along - np.sqrt(np.maximum(r_in ** 2 - h ** 2, 0))
    assert np.all(r.distance[inside] >= t_out[inside] * (1 - REL))
    assert np.all(r.distance[inside] <= t_in[inside] * (1 + REL))
    np.testing.assert_allclose(r.depth[inside], r.distance[inside] * cos[inside], rtol=REL)

    # Shading normal: unit length and close to the radial direction (smooth normals of a
    # 256 x 128 tessellation deviate by well under a degree).
    p_hit = t + r.distance[inside][:, None].astype(np.float64) * dirs[inside]
    radial = (p_hit - center) / np.linalg.norm(p_hit - center, axis=1, keepdims=True)
    n = r.normal[inside].astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    assert np.einsum("ij,ij->i", n, radial).min() > 0.9995

    # Alpha (fraction of the 16 jittered samples that hit): h changes by at most |C - o| times the
    # angle between two rays, and that angle is at most their distance on the z = 1 plane, which
    # within a pixel is at most the half-diagonal. So pixels whose centre is that far inside the
    # inscribed disc have alpha 1, and that far outside the circumscribed disc alpha 0.
    margin = np.linalg.norm(center - t) * np.hypot(0.5 / FX, 0.5 / FY) * 1.001
    full = h < r_in - margin
    empty = h > r_out + margin
    assert full.sum() > 1000
    assert np.all(r.alpha[full] == 1.0)
    assert np.all(r.alpha[empty] == 0.0)


def _sphere_at_camera_point(scene, cam, p_cam, instance_id, mesh_id):
    R, t = pose(cam)
    world = R @ np.asarray(p_cam, dtype=np.float64) + t
    scene.add_instance(mesh_id, P.translate(world), instance_id=instance_id)
    return world


def test_opencv_projection_convention():
    cam = make_camera()
    R, t = pose(cam)
    s = sg.Scene()
    m = s.add_mesh(**P.uv_sphere(0.12, segments=48, rings=24))
    rng = np.random.default_rng(1234)
    points = {}
    # Four spheres on the camera axes (+x right, -x, +y down, -y) and eight at random positions,
    # all fully inside the image and not overlapping in the image.
    named = {11: (0.9, 0.0, 5.0), 12: (-0.9, 0.0, 5.0), 13: (0.0, 0.5, 5.0), 14: (0.0, -0.5, 5.0)}
    discs = []  # (u, v, radius in pixels, with a safety factor)
    for iid, p in named.items():
        points[iid] = _sphere_at_camera_point(s, cam, p, iid, m)
        discs.append((FX * p[0] / p[2] + CX, FY * p[1] / p[2] + CY, 1.2 * 0.12 * FY / p[2]))
    while len(points) < 12:
        z = rng.uniform(4.0, 8.0)
        rad = 1.2 * 0.12 * FY / z
        u, v = rng.uniform([rad, rad], [W - rad, H - rad])
        if any(np.hypot(u - a, v - b) < rad + c for a, b, c in discs):
            continue
        discs.append((u, v, rad))
        iid = 100 + len(points)
        points[iid] = _sphere_at_camera_point(s, cam, ((u - CX) / FX * z, (v - CY) / FY * z, z), iid, m)
    s.set_camera(cam)
    r = s.render(spp=1, max_depth=1)

    K = np.array([[FX, 0, CX], [0, FY, CY], [0, 0, 1.0]])
    np.testing.assert_allclose(cam.K, K, rtol=1e-6)
    centroids = {}
    for iid, pw in points.items():
        pc = R.T @ (pw - t)  # camera coordinates
        uvw = K @ pc
        u, v = uvw[0] / uvw[2], uvw[1] / uvw[2]
        col, row = int(np.floor(u)), int(np.floor(v))
        assert r.instance_id[row, col] == iid, f"sphere {iid} projects to pixel ({col}, {row})"
        rows, cols = np.nonzero(r.instance_id == iid)
        centroids[iid] = (cols.mean() + 0.5, rows.mean() + 0.5)
        # The silhouette of a small sphere is centred on the projected centre (sub-pixel).
        assert abs(centroids[iid][0] - u) < 0.3 and abs(centroids[iid][1] - v) < 0.3

    # Orientation, explicitly: +x (camera right) is at larger column indices, +y (camera down)
    # at larger row indices, with the principal point between them.
    assert centroids[11][0] > CX > centroids[12][0]
    assert centroids[13][1] > CY > centroids[14][1]
    assert abs(centroids[11][1] - CY) < 1 and abs(centroids[13][0] - CX) < 1
    # ... and the horizontal / vertical offsets follow fx and fy separately (asymmetric K).
    np.testing.assert_allclose(centroids[11][0] - CX, FX * 0.9 / 5.0, atol=0.3)
    np.testing.assert_allclose(centroids[13][1] - CY, FY * 0.5 / 5.0, atol=0.3)


def test_project_and_generate_ray_agree_with_numpy():
    """The library's own projection helpers implement the same convention as the labels."""
    cam = make_camera()
    R, t = pose(cam)
    rng = np.random.default_rng(7)
    for _ in range(20):
        pc = np.array([rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(1, 10)])
        pw = R @ pc + t
        u, v = cam.project(pw.tolist())
        np.testing.assert_allclose([u, v], [FX * pc[0] / pc[2] + CX, FY * pc[1] / pc[2] + CY], atol=2e-3)
        o, d = cam.generate_ray(u, v)
        np.testing.assert_allclose(o, t, atol=1e-5)
        np.testing.assert_allclose(d, (pw - t) / np.linalg.norm(pw - t), atol=1e-5)
    assert cam.project((R @ [0.0, 0.0, -1.0] + t).tolist()) is None, "points behind the camera do not project"


def test_default_instance_ids_and_dtypes():
    cam = make_camera()
    R, t = pose(cam)
    s = sg.Scene()
    m = s.add_mesh(**P.box((0.5, 0.5, 0.5)))
    cams = [(-1.2, 0.0, 6.0), (0.0, 0.0, 6.0), (1.2, 0.0, 6.0)]
    handles = [s.add_instance(m, P.translate(R @ np.array(p) + t)) for p in cams]
    s.remove_instance(handles[1])  # handles are never reused: the next instance gets a new one
    handles[1] = s.add_instance(m, P.translate(R @ np.array(cams[1]) + t), class_id=3)
    assert len(set(handles)) == 3
    s.set_camera(cam)
    r = s.render(spp=2, max_depth=2)
    for h, p in zip(handles, cams):
        col, row = int(np.floor(FX * p[0] / p[2] + CX)), int(np.floor(FY * p[1] / p[2] + CY))
        assert r.instance_id[row, col] == h + 1
    assert set(np.unique(r.instance_id)) == {0} | {h + 1 for h in handles}
    # class_id defaults to 0; only the re-added instance has class 3.
    assert set(np.unique(r.class_id[r.instance_id == handles[1] + 1])) == {3}
    assert np.all(r.class_id[(r.instance_id != handles[1] + 1)] == 0)

    for name, dtype, shape in [("rgb", np.float32, (H, W, 3)), ("alpha", np.float32, (H, W)),
                               ("depth", np.float32, (H, W)), ("distance", np.float32, (H, W)),
                               ("normal", np.float32, (H, W, 3)), ("albedo", np.float32, (H, W, 3)),
                               ("instance_id", np.uint32, (H, W)), ("class_id", np.uint32, (H, W))]:
        a = getattr(r, name)
        assert a.dtype == dtype, f"{name}: {a.dtype}"
        assert a.shape == shape, f"{name}: {a.shape}"
