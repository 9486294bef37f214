"""Vehicles of the asset library: a model's body standing on its wheels, at real scale.

Some models ship a body only and leave the wheels to the program that drives them (TORCS
draws tyres and rims from the car's axle, track and tyre parameters). A library entry with a
``wheels`` block gets them built here: each wheel a surface of revolution (tyre with rounded
shoulders, a dished metal rim), the body lifted by its ``ride_height``, all in one mesh with the
body's own materials plus a rubber and a rim material, so that the vehicle is one object (one
instance id, one box). The entry's keys (lengths in metres, along the model's own ``forward``,
``up`` and their cross product, the right):

``ride_height``
    the body's lowest point above the ground;
``wheels``
    ``axles`` (positions along forward), ``track`` (the distance between a pair's centres: one
    value, or one per axle), ``radius``, ``width``, ``rim_radius`` (optional, default 0.62
    radius);
``plates``
    ``front`` and / or ``rear``: ``{height}`` (the plate's centre above the ground) and
    optionally ``offset`` (along the right): the plate's mounting rectangle is found by casting
    rays along the vehicle's axis onto its body over the plate's rectangle (its centre, edges
    and corners, 520 x 112 mm); the plate stands 5 mm ahead of the furthest hit, flat and
    upright, as on its bracket. The plate quads are part of the mesh with one placeholder material (a blank
    plate), which the ``plates`` randomizer replaces per frame with a registration's texture.

``lamps``
    ``{<kind>: {height, offset, size}}``, the kinds ``head``, ``tail``, ``brake`` (omitted: the
    tail lamp brightens when braking, a combined lamp), ``indicator_front``, ``indicator_rear``
    (:data:`LAMP_KINDS`): a lamp's centre ``height`` above the ground, its centre's ``offset``
    from the centre line (a pair at -offset and +offset; 0: one lamp on the centre line, as a
    motorcycle's), its ``size`` (width, height; default per kind). Each lamp's lens is a small
    grid of quads cast onto the body at its front or rear (every vertex on the surface there,
    standing a few millimetres out), with a placeholder material (an unlit lens) that the
    ``lamps`` randomizer switches on per frame.

``materials``
    ``{<material name in the model>: role}``: ``paint`` (the body: the ``paint`` randomizer
    recolours it), ``glass`` (dark, a smooth coat reflecting the sky: it shows the interior as
    dark as it looks from outside by day), ``chrome``, ``rubber``, ``trim`` (black plastic).

Models whose faces carry no normals get smooth ones within a crease angle (AC3D's convention).
"""
from __future__ import annotations

import math
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .assets import AssetError
from .vehicle_parts import LAMP_KINDS, ROLES

__all__ = ["AXES", "PLATE_MM", "ROLES", "LAMP_KINDS", "lamp_names", "lamp_lenses", "role_material", "material_roles", "model_axes", "revolve", "wheel_mesh", "crease_normals", "ray_mesh", "plate_mounts",
           "body_lift", "build_vehicle"]

#: The mounting rectangle of a plate (EU and Russian plates: 520 x 112 / 110 mm).
PLATE_MM = (520.0, 112.0)

#: Lens grid: vertices across and up each lamp (cast onto the body one by one).
_LENS_GRID = (9, 5)

#: The axes a model may declare as its forward and up directions, as unit vectors.
AXES = {"+x": (1.0, 0.0, 0.0), "-x": (-1.0, 0.0, 0.0), "+y": (0.0, 1.0, 0.0), "-y": (0.0, -1.0, 0.0),
        "+z": (0.0, 0.0, 1.0), "-z": (0.0, 0.0, -1.0)}


def role_material(role: str) -> Tuple[str, Dict[str, Any]]:
    """(plugin, parameters) of the material of a role (not paint, which keeps the model's
    colour until the paint randomizer draws one)."""
    return {"glass": ("coated", {"albedo": 0.015, "roughness": 0.0, "ior": 1.52}),
            "chrome": ("conductor", {"metal": "chrome", "roughness": 0.06}),
            "rubber": ("coated", {"albedo": 0.025, "roughness": 0.75, "specular": 0.4}),
            "trim": ("coated", {"albedo": 0.03, "roughness": 0.45, "specular": 0.6})}[role]


def material_roles(asset_id: str, entry: Mapping[str, Any], material_names: Sequence[str],
                   material_ids: Sequence[int]) -> Dict[str, List[int]]:
    """{role: the model's material ids} of a library entry's ``materials`` ({name in the model:
    role}), given the model's material names and ids as its import returns them (the frame's
    shapes and ``synthgen validate`` both read the roles here). AssetError naming a material
    the model does not have."""
    by_name = dict(zip(material_names, material_ids))
    roles: Dict[str, List[int]] = {}
    for name, role in (entry.get("materials") or {}).items():
        if name not in by_name:
            raise AssetError(f"asset '{asset_id}': materials: the model has no material '{name}' (it has "
                             f"{', '.join(repr(n) for n in by_name) or 'none'})")
        roles.setdefault(role, []).append(int(by_name[name]))
    return roles


def model_axes(forward: str = "+x", up: str = "+y") -> np.ndarray:
    """Rows: the model's forward, up and right (forward x up) unit vectors in its own coordinates."""
    f, u = np.array(AXES[forward], float), np.array(AXES[up], float)
    if abs(float(f @ u)) > 0.5:
        raise ValueError(f"forward {forward} and up {up} must be perpendicular")
    return np.stack([f, u, np.cross(f, u)])


def revolve(profile: Sequence[Tuple[float, float]], segments: int = 40) -> Dict[str, np.ndarray]:
    """A surface of revolution about the a axis of a profile of (r, a) points (in order along the
    surface; an r of 0 closes it at the axis). Vertices per profile point and angle; normals from
    the profile's tangent (so that the shoulders are smooth and the flanks flat)."""
    prof = np.asarray(profile, np.float64)
    n = len(prof)
    # Tangent per profile point (central differences), normal = tangent turned by -90 degrees in
    # the (r, a) plane: outward for a profile that runs with the surface on its left.
    t = np.gradient(prof, axis=0)
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
    nr, na = t[:, 1], -t[:, 0]
    ang = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    c, s = np.cos(ang), np.sin(ang)
    # Coordinates: (radial x, radial y, axial a) -> (x, y, a).
    pos = np.stack([prof[:, 0][:, None] * c[None, :], prof[:, 0][:, None] * s[None, :],
                    np.repeat(prof[:, 1][:, None], segments, 1)], -1).reshape(-1, 3)
    nrm = np.stack([nr[:, None] * c[None, :], nr[:, None] * s[None, :], np.repeat(na[:, None], segments, 1)],
                   -1).reshape(-1, 3)
    idx = []
    for i in range(n - 1):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            cc, d = a + segments, b + segments
            if prof[i, 0] > 0:
                idx.append((a, cc, b))
            if prof[i + 1, 0] > 0:
                idx.append((b, cc, d))
    return {"positions": pos.astype(np.float32), "normals": nrm.astype(np.float32),
            "indices": np.asarray(idx, np.uint32)}


def wheel_mesh(radius: float, width: float, rim_radius: float, segments: int = 40
               ) -> Tuple[Dict[str, np.ndarray], np.ndarray]:
    """A wheel about the z axis, centred at the origin: (mesh, part per triangle: 0 tyre, 1 rim).

    The tyre: tread, rounded shoulders (radius a fifth of the width), flat sidewalls down to the
    rim; the rim: a dished face on each side, its centre set in by a fifth of the width."""
    h = 0.5 * width
    sh = min(0.2 * width, 0.5 * (radius - rim_radius))
    k = [0.0, 0.38, 0.71, 0.92, 1.0]  # quarter circle, 5 points
    tyre = [(rim_radius, -0.92 * h)]
    tyre += [(radius - sh + sh * math.sin(q * math.pi / 2), -h + sh - sh * math.cos(q * math.pi / 2)) for q in k]
    tyre += [(radius - sh + sh * math.cos(q * math.pi / 2), h - sh + sh * math.sin(q * math.pi / 2)) for q in k]
    tyre += [(rim_radius, 0.92 * h)]
    # The rim on the +a side (outer), from the tyre's bead inwards, and its mirror.
    rim_o = [(rim_radius, 0.92 * h), (0.93 * rim_radius, 0.8 * h), (0.55 * rim_radius, 0.45 * h),
             (0.2 * rim_radius, 0.6 * h), (0.0, 0.6 * h)]
    rim_i = [(0.0, -0.6 * h), (0.2 * rim_radius, -0.6 * h), (0.55 * rim_radius, -0.45 * h),
             (0.93 * rim_radius, -0.8 * h), (rim_radius, -0.92 * h)]
    parts = [(revolve(tyre, segments), 0), (revolve(rim_o, segments), 1), (revolve(rim_i, segments), 1)]
    pos, nrm, idx, part = [], [], [], []
    base = 0
    for m, p in parts:
        pos.append(m["positions"])
        nrm.append(m["normals"])
        idx.append(m["indices"] + base)
        part.append(np.full(len(m["indices"]), p, np.int32))
        base += len(m["positions"])
    return ({"positions": np.concatenate(pos), "normals": np.concatenate(nrm), "indices": np.concatenate(idx)},
            np.concatenate(part))


def crease_normals(positions: np.ndarray, indices: np.ndarray, crease_deg: float = 50.0
                   ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Smooth vertex normals that keep edges sharper than ``crease_deg``: each triangle corner
    averages the (area-weighted) normals of the triangles at its vertex within the crease angle
    of its own; corners of one vertex with the same normal share a vertex. Returns (new vertex
    index per corner, T x 3; the original vertex of each new vertex; normals per new vertex)."""
    p = np.asarray(positions, np.float64)
    tri = np.asarray(indices, np.int64)
    fn = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])  # area-weighted
    unit = fn / np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-30)
    cos_c = math.cos(math.radians(crease_deg))
    corners = tri.ravel()
    order = np.argsort(corners, kind="stable")
    starts = np.searchsorted(corners[order], np.arange(len(p) + 1))
    corner_n = np.zeros((len(corners), 3))
    for v in range(len(p)):
        cs = order[starts[v]:starts[v + 1]]
        if len(cs) == 0:
            continue
        faces = cs // 3
        u = unit[faces]
        close = (u @ u.T) >= cos_c  # corner i takes face j when within the crease
        corner_n[cs] = close.astype(np.float64) @ fn[faces]
    corner_n /= np.maximum(np.linalg.norm(corner_n, axis=1, keepdims=True), 1e-30)
    # Weld corners of one vertex whose normals agree.
    key = np.concatenate([corners[:, None].astype(np.float64), np.round(corner_n, 4)], 1)
    uniq, inverse = np.unique(key, axis=0, return_inverse=True)
    return inverse.reshape(-1, 3), uniq[:, 0].astype(np.int64), uniq[:, 1:].astype(np.float32)


def ray_mesh(pos: np.ndarray, tri: np.ndarray, origins: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Distance along ``direction`` (unit) from each origin to the first triangle hit (inf: none).

    NOTE: Moller-Trumbore ray-triangle intersection (Moller & Trumbore 1997), vectorized over the
    triangles, one ray at a time (a handful of rays per model, at build time)."""
    v0, v1, v2 = pos[tri[:, 0]], pos[tri[:, 1]], pos[tri[:, 2]]
    e1, e2 = v1 - v0, v2 - v0
    d = np.asarray(direction, np.float64)
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    out = []
    for o in np.atleast_2d(origins):
        t0 = o - v0
        u = np.einsum("ij,ij->i", t0, p) * inv
        q = np.cross(t0, e1)
        v = (q @ d) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
        out.append(float(t[hit].min()) if hit.any() else math.inf)
    return np.asarray(out)


def plate_mounts(pos: np.ndarray, tri: np.ndarray, entry: Mapping[str, Any], unit: float) -> Dict[str, np.ndarray]:
    """The mounting rectangles of the entry's plates: {"front" | "rear": 4 x 3 corners (model
    units; top left, top right, bottom right, bottom left as one faces the plate)}. ``pos`` is
    the body standing on the ground (its up coordinate 0 at the ground)."""
    fwd, up, right = model_axes(entry.get("forward", "+x"), entry.get("up", "+y"))
    w, h = PLATE_MM[0] / 1000.0 / unit, PLATE_MM[1] / 1000.0 / unit
    reach = float(np.ptp(pos @ fwd)) + 1.0
    centre_f = 0.5 * float((pos @ fwd).min() + (pos @ fwd).max())
    out = {}
    for name, sgn in (("front", 1.0), ("rear", -1.0)):
        spec = (entry.get("plates") or {}).get(name)
        if spec is None:
            continue
        y = float(spec["height"]) / unit
        off = float(spec.get("offset", 0.0)) / unit
        outward = sgn * fwd
        base = (centre_f + sgn * reach) * fwd + y * up
        hits = []
        origins = [base + lat * right + dy * up for lat in (off - 0.5 * w, off, off + 0.5 * w)
                   for dy in (-0.5 * h, 0.0, 0.5 * h)]
        for t in ray_mesh(pos, tri, np.asarray(origins), -outward):
            if math.isfinite(t):
                hits.append(reach - t)  # how far the surface reaches out from the centre plane
        if not hits:
            raise ValueError(f"{name} plate at {spec['height']} m: no body surface there")
        c = (centre_f + sgn * (max(hits) + 0.005 / unit)) * fwd + y * up + off * right
        # Facing the plate from outside, one's right is the vehicle's left at the front (-right)
        # and its right at the rear.
        lr = -right if name == "front" else right
        out[name] = np.array([c - 0.5 * w * lr + 0.5 * h * up, c + 0.5 * w * lr + 0.5 * h * up,
                              c + 0.5 * w * lr - 0.5 * h * up, c - 0.5 * w * lr - 0.5 * h * up])
    return out


def lamp_names(entry: Mapping[str, Any]) -> List[Tuple[str, str, str]]:
    """(name, kind, side) of each lamp of the entry: side "left" / "right" (as the driver sees
    them) for a pair, "centre" for a lamp on the centre line; name "<kind>.<side>"."""
    out = []
    for kind, spec in (entry.get("lamps") or {}).items():
        sides = ("centre",) if float(spec.get("offset", 0.0)) == 0.0 else ("left", "right")
        out += [(f"{kind}.{side}", kind, side) for side in sides]
    return out


def lamp_lenses(pos: np.ndarray, tri: np.ndarray, entry: Mapping[str, Any], unit: float) -> Dict[str, Dict[str, Any]]:
    """The lenses of the entry's lamps, cast onto the body (``pos``, standing on the ground):
    {name: {"kind", "side", "grid": nu x nv x 3 vertices (model units; u across from the
    vehicle's left to its right, v from bottom to top), "valid" (nu x nv: on the body), "centre", "corners" (the grid's four),
    "normal" (outward)}}. Every
    vertex lies on the body surface hit by a ray along the vehicle's axis from outside, moved
    out by a stand-off (3 mm, 1.5 mm more per kind, so that overlapping lamps -- a brake lamp
    inside a tail lamp -- do not fight); a vertex whose ray finds no surface, or that is cut off
    from the lens's centre by a jump in depth (past the body's outline, through a gap), is off
    the lens (``valid`` false: no triangle uses it)."""
    fwd, up, right = model_axes(entry.get("forward", "+x"), entry.get("up", "+y"))
    along = pos @ fwd
    reach = float(np.ptp(along)) + 1.0
    centre_f = 0.5 * float(along.min() + along.max())
    nu, nv = _LENS_GRID
    out: Dict[str, Dict[str, Any]] = {}
    for k, (kind, spec) in enumerate((entry.get("lamps") or {}).items()):
        info = LAMP_KINDS[kind]
        sgn = float(info["end"])
        w, h = (float(v) / unit for v in spec.get("size", info["size"]))
        y, off = float(spec["height"]) / unit, float(spec.get("offset", 0.0)) / unit
        standoff = (0.003 + 0.0015 * k) / unit
        for name, kind_, side in lamp_names({"lamps": {kind: spec}}):
            lat = {"left": -off, "right": off, "centre": 0.0}[side]
            us, vs = np.linspace(-0.5 * w, 0.5 * w, nu), np.linspace(-0.5 * h, 0.5 * h, nv)
            origins = np.array([(centre_f + sgn * reach) * fwd + (lat + a) * right + (y + b) * up
                                for b in vs for a in us])
            t = ray_mesh(pos, tri, origins, -sgn * fwd)
            ok = np.isfinite(t)
            if not ok.any():
                raise ValueError(f"lamp {name} at {spec['height']} m, offset {spec.get('offset', 0.0)} m: no body "
                                 f"surface there")
            # A ray past the body's outline (a rounded corner) or through a gap (a grille, a
            # lamp's rim) finds no surface or one far behind its neighbours': the lens is the
            # vertices reached from its centre through neighbours whose hits are within a
            # slope of 2 (63 degrees off the axis) plus 5 mm of each other -- it follows a
            # sloped or wrapped body, stops at jumps. The others are off the lens (they keep
            # the lens's median depth; no triangle uses them).
            tg, okg = t.reshape(nv, nu).T, ok.reshape(nv, nu).T
            step = (w / (nu - 1), h / (nv - 1))
            cu, cv = nu // 2, nv // 2
            if not okg[cu, cv]:
                cand = np.argwhere(okg)
                cu, cv = cand[np.argmin(np.hypot(cand[:, 0] - cu, cand[:, 1] - cv))]
            valid = np.zeros((nu, nv), bool)
            valid[cu, cv] = True
            todo = [(cu, cv)]
            while todo:
                i0, j0 = todo.pop()
                for di, dj, sp in ((1, 0, step[0]), (-1, 0, step[0]), (0, 1, step[1]), (0, -1, step[1])):
                    i1, j1 = i0 + di, j0 + dj
                    if 0 <= i1 < nu and 0 <= j1 < nv and okg[i1, j1] and not valid[i1, j1] and \
                            abs(tg[i1, j1] - tg[i0, j0]) <= 2.0 * sp + 0.005 / unit:
                        valid[i1, j1] = True
                        todo.append((i1, j1))
            on = valid.T.reshape(-1)
            t = np.where(on, t, float(np.median(t[on])))
            grid = (origins - sgn * (t - standoff)[:, None] * fwd).reshape(nv, nu, 3).transpose(1, 0, 2)
            where = f"lamp {name} at {spec['height']} m, offset {spec.get('offset', 0.0)} m"
            if valid.sum() < 0.25 * valid.size:
                raise ValueError(f"{where}: less than a quarter of it lies on the body (past its outline?)")
            depth = sgn * float(np.median((grid[valid] @ fwd))) - sgn * centre_f
            extreme = sgn * (float(along.max()) if sgn > 0 else float(along.min())) - sgn * centre_f
            if extreme - depth > 0.6 / unit:
                raise ValueError(f"{where}: it lands {(extreme - depth) * unit:.2f} m behind the body's "
                                 f"{'front' if sgn > 0 else 'rear'} (past its outline, on a part further in?)")
            out[name] = {"kind": kind_, "side": side, "grid": grid, "valid": valid,
                         "centre": grid[nu // 2, nv // 2].copy(),
                         "corners": grid[[0, -1, -1, 0], [0, 0, -1, -1]].copy(), "normal": sgn * fwd}
    return out


def _lens_mesh(grid: np.ndarray, valid: np.ndarray, outward: np.ndarray
               ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(positions, triangles facing ``outward``, normals, uvs) of a lens grid (nu x nv x 3), its
    triangles those whose vertices are all ``valid`` (nu x nv) -- on the body."""
    nu, nv = grid.shape[:2]
    pos = grid.reshape(-1, 3)
    idx = np.arange(nu * nv).reshape(nu, nv)
    ok = valid.reshape(-1)
    tris = []
    for i in range(nu - 1):
        for j in range(nv - 1):
            a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
            tris += [t for t in ([a, b, c], [a, c, d]) if ok[t].all()]
    tris = np.asarray(tris, np.int64).reshape(-1, 3)
    n = np.cross(pos[tris[:, 1]] - pos[tris[:, 0]], pos[tris[:, 2]] - pos[tris[:, 0]])
    flip = (n @ outward) < 0
    tris[flip] = tris[flip][:, ::-1]
    uv = np.stack(np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv), indexing="ij"), -1).reshape(-1, 2)
    return pos, tris, np.repeat(outward[None].astype(np.float32), len(pos), 0), uv.astype(np.float32)


def body_lift(body: Mapping[str, Any], entry: Mapping[str, Any], unit: float) -> float:
    """How far a vehicle body is raised (model units along its up axis): its lowest point goes
    to the entry's ride height."""
    up = model_axes(entry.get("forward", "+x"), entry.get("up", "+y"))[1]
    return float(entry.get("ride_height", 0.0)) / unit - float((np.asarray(body["positions"], np.float64) @ up).min())


def build_vehicle(body: Mapping[str, Any], entry: Mapping[str, Any], unit: float,
                  tyre_material: int, rim_material: int, plate_materials: Optional[Mapping[str, int]] = None,
                  lamp_materials: Optional[Mapping[str, int]] = None, lift: Optional[float] = None) -> Dict[str, Any]:
    """The arrays of a vehicle mesh (positions, indices, normals, uvs or None, material_ids) in the
    model's units, and its plate mounts (``plates``: name -> 4 x 3 corners): ``body``
    (:meth:`Scene.mesh_arrays` of the imported model) lifted by the entry's ride height, its
    wheels (if the entry has ``wheels``) and plate quads (``plates``, each with its placeholder
    material from ``plate_materials``) and lamp lenses (``lamps``: :func:`lamp_lenses`, each with
    its placeholder material from ``lamp_materials``, by lamp name) added. ``unit``: metres per
    model unit."""
    axes = model_axes(entry.get("forward", "+x"), entry.get("up", "+y"))
    fwd, up, right = axes
    pos = np.asarray(body["positions"], np.float64)
    tri = np.asarray(body["indices"], np.int64)
    mids = np.asarray(body["material_ids"], np.int32)
    if mids.size == 0:
        mids = np.full(len(tri), -1, np.int32)
    uvs = body.get("uvs")
    if body.get("normals") is not None:
        nrm = np.asarray(body["normals"], np.float32)
    else:
        corner, src, nrm = crease_normals(pos, tri)
        pos, tri = pos[src], corner
        uvs = None if uvs is None else np.asarray(uvs)[src]
    if lift is None:
        lift = body_lift(body, entry, unit)
    pos = pos + lift * up
    P, N, T, M, U = [pos], [nrm], [tri], [mids], [uvs]
    base = len(pos)
    mounts = plate_mounts(pos, tri, entry, unit) if entry.get("plates") else {}
    for name, q in mounts.items():
        # Two triangles facing out, the plate texture upright and readable from outside.
        P.append(q)
        n = np.cross(q[3] - q[0], q[1] - q[0])  # towards the one facing it
        N.append(np.repeat((n / np.linalg.norm(n))[None].astype(np.float32), 4, 0))
        T.append(np.array([[0, 3, 2], [0, 2, 1]], np.int64) + base)
        M.append(np.full(2, (plate_materials or {}).get(name, -1), np.int32))
        U.append(np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32))
        base += 4
    lenses = lamp_lenses(pos, tri, entry, unit) if entry.get("lamps") else {}
    for name, lens in lenses.items():
        lp, lt, ln, lu = _lens_mesh(lens["grid"], lens["valid"], lens["normal"])
        P.append(lp)
        N.append(ln)
        T.append(lt + base)
        M.append(np.full(len(lt), (lamp_materials or {}).get(name, -1), np.int32))
        U.append(lu)
        base += len(lp)
    if uvs is None and (mounts or lenses):
        U[0] = np.zeros((len(pos), 2), np.float32)
    out = {"plates": mounts, "lamps": {k: {kk: vv for kk, vv in v.items() if kk not in ("grid", "valid")}
                                       for k, v in lenses.items()}}
    if "wheels" not in entry:
        out.update(_concat(P, N, T, M, U))
        return out
    w = entry["wheels"]
    radius, width = float(w["radius"]), float(w["width"])
    rim = float(w.get("rim_radius", 0.62 * radius))
    axles = [float(a) for a in w["axles"]]
    track = w["track"] if isinstance(w["track"], (list, tuple)) else [w["track"]] * len(axles)
    wheel, part = wheel_mesh(radius / unit, width / unit, rim / unit)
    # Wheel frame: its axis (z) along the model's right, its radial plane spanned by forward, up.
    frame = np.stack([fwd, up, right])  # rows: where the wheel's x, y, z go
    has_uv = U[0] is not None
    for a, tr in zip(axles, track):
        for side in (-1.0, 1.0):
            centre = (a * fwd + radius * up + side * 0.5 * float(tr) * right) / unit
            # Outer face outwards: mirror the wheel's axis on the left side.
            fr = frame.copy()
            fr[2] = side * right
            fr[0] = side * fwd  # keep the frame right-handed (a mirror would flip the triangles)
            P.append(wheel["positions"].astype(np.float64) @ fr + centre)
            N.append((wheel["normals"] @ fr).astype(np.float32))
            T.append(wheel["indices"].astype(np.int64) + base)
            M.append(np.where(part == 0, tyre_material, rim_material).astype(np.int32))
            U.append(np.zeros((len(wheel["positions"]), 2), np.float32) if has_uv else None)
            base += len(wheel["positions"])
    out.update(_concat(P, N, T, M, U))
    return out


def _concat(P, N, T, M, U) -> Dict[str, Any]:
    return {"positions": np.concatenate(P).astype(np.float32), "indices": np.concatenate(T).astype(np.uint32),
            "normals": np.concatenate(N).astype(np.float32),
            "uvs": None if U[0] is None else np.concatenate(U).astype(np.float32),
            "material_ids": np.concatenate(M).astype(np.int32)}
