"""Procedural meshes and transform helpers (numpy), for scenes built without asset files.

Every mesh function returns a dict with ``positions`` (N x 3 float32), ``indices``
(M x 3 uint32), ``normals`` (N x 3 float32) and ``uvs`` (N x 2 float32), ready for
``Scene.add_mesh(**mesh)``. Triangles are counter-clockwise seen from outside, so the
geometric normal points outwards.
"""
from __future__ import annotations

import numpy as np


def _mesh(positions, indices, normals, uvs) -> dict:
    return {
        "positions": np.ascontiguousarray(positions, dtype=np.float32),
        "indices": np.ascontiguousarray(indices, dtype=np.uint32),
        "normals": np.ascontiguousarray(normals, dtype=np.float32),
        "uvs": np.ascontiguousarray(uvs, dtype=np.float32),
    }


def plane(size_x: float = 1.0, size_z: float = 1.0) -> dict:
    """Square in the y = 0 plane, centred at the origin, normal +y."""
    hx, hz = 0.5 * size_x, 0.5 * size_z
    p = [[-hx, 0, -hz], [hx, 0, -hz], [hx, 0, hz], [-hx, 0, hz]]
    # counter-clockwise seen from +y
    idx = [[0, 2, 1], [0, 3, 2]]
    n = [[0, 1, 0]] * 4
    uv = [[0, 0], [1, 0], [1, 1], [0, 1]]
    return _mesh(p, idx, n, uv)


def ground(radius: float = 1.0e5, cell: float = 0.5, growth: float = 1.25) -> dict:
    """The y = 0 plane out to ``radius`` metres in every direction (by default far enough
    that its edge lies below the horizon by less than a pixel), normal +y, uv = (x, z) in
    metres (textures tile by their uv scale).

    A grid whose cells grow geometrically from ``cell`` metres at the origin by ``growth``
    per step: a hit point's floating-point error bound grows with its triangle's
    coordinates (interaction.h), so the ground near the origin, where the objects stand,
    stays as precise as a small plane while the far cells reach the horizon."""
    ticks = [0.0]
    step = float(cell)
    while ticks[-1] < radius:
        ticks.append(min(ticks[-1] + step, float(radius)))
        step *= growth
    t = np.array([-x for x in reversed(ticks[1:])] + ticks, np.float64)
    n = len(t)
    xs, zs = np.meshgrid(t, t, indexing="ij")  # vertex (i, j) at (t[i], 0, t[j])
    p = np.stack([xs.ravel(), np.zeros(n * n), zs.ravel()], -1)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a, b, c, d = i * n + j, (i + 1) * n + (j + 1), (i + 1) * n + j, i * n + (j + 1)
    # counter-clockwise seen from +y (as plane()): (a, b, c) and (a, d, b)
    idx = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, d, b], -1).reshape(-1, 3)])
    return _mesh(p, idx, np.tile([0.0, 1.0, 0.0], (n * n, 1)), p[:, [0, 2]])


def box(size=(1.0, 1.0, 1.0)) -> dict:
    """Axis-aligned box centred at the origin with flat-shaded faces (24 vertices)."""
    sx, sy, sz = (0.5 * float(s) for s in size)
    faces = [  # (normal, u axis, v axis)
        ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
        ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
        ((0, 1, 0), (1, 0, 0), (0, 0, -1)),
        ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
        ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
        ((0, 0, -1), (-1, 0, 0), (0, 1, 0)),
    ]
    half = np.array([sx, sy, sz])
    P, N, UV, I = [], [], [], []
    for n, u, v in faces:
        n, u, v = (np.array(a, dtype=np.float64) for a in (n, u, v))
        base = len(P)
        for cu, cv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            P.append((n + cu * u + cv * v) * half)
            N.append(n)
            UV.append([(cu + 1) / 2, (cv + 1) / 2])
        I += [[base, base + 1, base + 2], [base, base + 2, base + 3]]
    return _mesh(P, I, N, UV)


def uv_sphere(radius: float = 1.0, segments: int = 64, rings: int = 32) -> dict:
    """UV sphere centred at the origin with smooth normals."""
    if segments < 3 or rings < 2:
        raise ValueError("uv_sphere: need segments >= 3 and rings >= 2")
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    n = np.stack([np.sin(t) * np.cos(p), np.cos(t), -np.sin(t) * np.sin(p)], axis=-1).reshape(-1, 3)
    uv = np.stack([p / (2 * np.pi), 1.0 - t / np.pi], axis=-1).reshape(-1, 2)
    idx = []
    w = segments + 1
    for r in range(rings):
        for s in range(segments):
            a, b, c, d = r * w + s, r * w + s + 1, (r + 1) * w + s + 1, (r + 1) * w + s
            if r != 0:
                idx.append([a, d, b])
            if r != rings - 1:
                idx.append([b, d, c])
    return _mesh(n * radius, idx, n, uv)


def _revolution(profile, segments: int, cap_bottom: bool, cap_top: bool) -> dict:
    """A closed solid of revolution about the y axis from a side ``profile``: rows of
    (radius, y, normal_radial, normal_y) -- two rows per flat band so normals do not blend
    across an edge; flat caps (radius > 0 at the bottom / top row) with their own vertices."""
    if segments < 3:
        raise ValueError("need segments >= 3")
    phi = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    c, s_ = np.cos(phi), -np.sin(phi)  # as uv_sphere: u grows counter-clockwise seen from +y
    P, N, UV, I = [], [], [], []
    w = segments + 1
    prof = np.asarray(profile, np.float64)
    ys = prof[:, 1]
    v_of = (ys - ys.min()) / max(ys.max() - ys.min(), 1e-12)
    for r, y, nr, ny in prof:
        for k in range(w):
            P.append([r * c[k], y, r * s_[k]])
            N.append([nr * c[k], ny, nr * s_[k]])
            UV.append([phi[k] / (2 * np.pi), 0.0])
    for i, v in enumerate(v_of):
        for k in range(w):
            UV[i * w + k][1] = v
    for i in range(len(prof) - 1):
        if prof[i, 1] == prof[i + 1, 1] and prof[i, 0] == prof[i + 1, 0]:
            continue  # the two rows of one crease: no band between them
        for k in range(segments):
            a, b, cc, d = i * w + k, i * w + k + 1, (i + 1) * w + k + 1, (i + 1) * w + k
            # Rows run upwards: (a, b, d) is counter-clockwise seen from outside; a row of
            # radius 0 (an apex) gets no degenerate triangle.
            if prof[i, 0] > 0:
                I.append([a, b, d])
            if prof[i + 1, 0] > 0:
                I.append([b, cc, d])
    for cap, row, ny in ((cap_bottom, 0, -1.0), (cap_top, len(prof) - 1, 1.0)):
        r, y = prof[row, 0], prof[row, 1]
        if not cap or r <= 0:
            continue
        centre = len(P)
        P.append([0.0, y, 0.0])
        N.append([0.0, ny, 0.0])
        UV.append([0.5, 0.5])
        for k in range(segments):
            P.append([r * c[k], y, r * s_[k]])
            N.append([0.0, ny, 0.0])
            UV.append([0.5 + 0.5 * c[k], 0.5 + 0.5 * s_[k]])
        for k in range(segments):
            a, b = centre + 1 + k, centre + 1 + (k + 1) % segments
            I.append([centre, b, a] if ny < 0 else [centre, a, b])
    return _mesh(P, I, N, UV)


def cylinder(radius: float = 0.5, height: float = 1.0, segments: int = 64) -> dict:
    """Closed cylinder about the y axis, centred at the origin (y in [-h/2, h/2]): smooth
    side normals, flat caps."""
    r, h = float(radius), 0.5 * float(height)
    if r <= 0 or h <= 0:
        raise ValueError("cylinder: radius and height must be positive")
    return _revolution([(r, -h, 1.0, 0.0), (r, h, 1.0, 0.0)], segments, True, True)


def cone(radius: float = 0.5, height: float = 1.0, segments: int = 64) -> dict:
    """Closed cone about the y axis, centred at the origin (base disc at y = -h/2, apex at
    y = h/2): side normals of the slanted surface (the apex gets one vertex per segment, so
    its normals stay slanted), a flat base."""
    r, hh = float(radius), float(height)
    if r <= 0 or hh <= 0:
        raise ValueError("cone: radius and height must be positive")
    length = np.hypot(r, hh)
    nr, ny = hh / length, r / length  # outward normal of the slanted side
    return _revolution([(r, -0.5 * hh, nr, ny), (0.0, 0.5 * hh, nr, ny)], segments, True, False)


def translate(t) -> np.ndarray:
    m = np.eye(4, dtype=np.float32)
    m[:3, 3] = t
    return m


def scale(s) -> np.ndarray:
    s = np.broadcast_to(np.asarray(s, dtype=np.float32), (3,))
    return np.diag([s[0], s[1], s[2], 1.0]).astype(np.float32)


def rotate(axis, degrees: float) -> np.ndarray:
    """Rotation by `degrees` about `axis` (right-handed, Rodrigues' formula)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    th = np.radians(degrees)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    R = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K
    m = np.eye(4, dtype=np.float32)
    m[:3, :3] = R
    return m
