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
