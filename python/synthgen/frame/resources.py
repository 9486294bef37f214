"""What a worker keeps in its scene across frames, and what lives for one frame only.

- :class:`Shapes`: every mesh is added once (one BVH build per worker): primitives, files,
  assets and the meshes of shape randomizers (signs, plates), with their bounds;
- :class:`FrameLibrary`: a facade of the scene that records the textures and materials made
  for one frame (generated signs, plates, decals, wear) so that they are removed when the
  next frame is set up, newest first; the library stays bounded over a long run;
- :class:`Pool`: instance ids reused frame after frame (id k for the frame's object k, so
  instance order -- and with it every light list -- is the same on every worker whatever
  it rendered before); ids beyond the frame's objects are hidden.
"""
from __future__ import annotations

from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple

import numpy as np

from .._core import Scene
from .. import randomize
from ..scene import primitives as P

__all__ = ["Shape", "Shapes", "FrameLibrary", "Pool", "mesh_bytes"]


def mesh_bytes(arrays: Mapping[str, Any]) -> int:
    """Bytes of a mesh's arrays as the scene stores them (float32 positions, normals, uvs;
    uint32 indices, int32 material ids; the BVH not counted)."""
    n = 0
    for key, size in (("positions", 12), ("normals", 12), ("uvs", 8)):
        if arrays.get(key) is not None:
            n += size * len(arrays[key])
    tri = len(np.asarray(arrays["indices"]).reshape(-1, 3))
    return n + 12 * tri + (4 * tri if arrays.get("material_ids") is not None else 0)


class Shape:
    """A mesh in the worker's scene with its object-space bounds."""

    def __init__(self, mesh_id: int, lo: np.ndarray, hi: np.ndarray, own_materials: bool, unit: float = 1.0,
                 material_ids: Tuple[int, ...] = (), forward: Optional[str] = None, up: Optional[str] = None):
        self.mesh_id, self.lo, self.hi, self.own_materials = mesh_id, lo, hi, own_materials
        self.unit = unit  #: metres per mesh unit (an asset's manifest `scale`)
        #: The distinct per-triangle material ids of a model with materials of its own
        #: (-1: triangles without one, shaded with the scene's default grey).
        self.material_ids = material_ids
        #: The model's own forward and up axes ("+z", ...) when its asset declares them.
        self.forward, self.up = forward, up
        #: A vehicle's plate mounting rectangles (name -> 4 x 3 corners in mesh coordinates: top
        #: left, top right, bottom right, bottom left as one faces the plate) and the placeholder
        #: material of each one's quad (None: no plates).
        self.plates: Dict[str, np.ndarray] = {}
        self.plate_material: Optional[Dict[str, int]] = None
        #: A vehicle's lamps (name -> {kind, side, centre, corners, normal} in mesh coordinates:
        #: synthgen.scene.vehicles.lamp_lenses) and each lens's placeholder material (an unlit lens).
        self.lamps: Dict[str, Dict[str, Any]] = {}
        self.lamp_material: Optional[Dict[str, int]] = None
        #: Material ids of the model by the role its entry gives them ("paint": [...]).
        self.roles: Dict[str, List[int]] = {}
        #: Levels of detail of a library model whose entry lists them (synthgen.scene.lod): the
        #: geometric error of each (mesh units, finest first, the finest's 0) and, once made,
        #: each level's (mesh, triangles, bytes of its arrays) (level 0: this shape's mesh).
        self.lod_errors: Tuple[float, ...] = (0.0,)
        self.lod_meshes: Dict[int, Tuple[int, int, int]] = {}
        self.lod_unusable: Dict[int, str] = {}  #: levels that cannot carry the model's parts, and why
        self._lod: Optional[Dict[str, Any]] = None  # what making a level needs (Shapes.level_mesh)


class Shapes:
    """The meshes of a worker, made on first use."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self._shapes: Dict[Tuple[str, Any], Shape] = {}
        self._grey_material: Optional[int] = None
        self._roles: Dict[str, int] = {}

    def _role(self, role: str, make: Callable[[str], Tuple[str, Dict[str, Any]]]) -> int:
        """The worker's material for a role (glass, chrome, rubber, trim), made once."""
        if role not in self._roles:
            self._roles[role] = self.scene.add_material(*make(role))
        return self._roles[role]

    def _grey(self) -> int:
        """A grey material for the triangles of a model without materials that gains parts."""
        if self._grey_material is None:
            self._grey_material = self.scene.add_material("diffuse", {"albedo": 0.5})
        return self._grey_material

    def get(self, kind: str, value: Any) -> Shape:
        """The shape of ``(kind, value)``: ("primitive", "box" | "sphere" | "cylinder" | "cone"), ("mesh", path),
        ("asset", id) or (randomizer key, sampled value) of a shape randomizer."""
        key = (kind, value) if kind in ("primitive", "mesh", "asset") else (kind, None)
        if key not in self._shapes:
            self._shapes[key] = self._make(*key)
        return self._shapes[key]

    def _make(self, kind: str, value: Any) -> Shape:
        scene = self.scene
        if kind in ("mesh", "asset"):
            unit, path, axes = 1.0, value, {}
            if kind == "asset":
                from ..scene import assets

                path = assets.resolve(value)
                entry = assets.entry(value)
                unit = float(entry.get("scale", 1.0))
                axes = {k: entry[k] for k in ("forward", "up") if k in entry}
            r = scene.load_mesh_file(path)
            mesh_id = r["mesh_id"]
            arrays = scene.mesh_arrays(mesh_id)
            plates, plate_material, roles, lamps, lamp_material = {}, None, {}, {}, None
            if kind == "asset" and entry.get("materials"):
                # Materials by role (the entry names them): glass, chrome, rubber, trim replaced by
                # materials that read as such; paint kept, and recorded for the paint randomizer.
                from ..scene.vehicles import material_roles, role_material

                roles = material_roles(value, entry, r.get("material_names", []), r["material_ids"])
                remap = {m: self._role(role, role_material) for role, ids in roles.items() if role != "paint"
                         for m in ids}
                mids = np.asarray(arrays["material_ids"], np.int32)
                arrays = dict(arrays, material_ids=np.array([remap.get(int(m), int(m)) for m in mids], np.int32))
                if not any(k in entry for k in ("wheels", "plates", "lamps")):
                    mesh_id = scene.add_mesh(arrays["positions"], arrays["indices"], normals=arrays.get("normals"),
                                             uvs=arrays.get("uvs"), material_ids=arrays["material_ids"], name=value)
            if kind == "asset" and any(k in entry for k in ("wheels", "plates", "lamps")):
                # A vehicle whose wheels or plate mounts the library entry describes: one mesh
                # with them (the plates with a placeholder material: a blank plate).
                from ..scene.vehicles import build_vehicle

                tyre = scene.add_material("coated", {"albedo": 0.025, "roughness": 0.75, "specular": 0.4})
                rim = scene.add_material("conductor", {"metal": "aluminium", "roughness": 0.3})
                if entry.get("plates"):  # one placeholder per mount: a blank plate
                    plate_material = {m: scene.add_material("diffuse", {"albedo": 0.75}) for m in entry["plates"]}
                if entry.get("lamps"):  # one placeholder per lamp: its unlit lens
                    from ..scene.vehicles import LAMP_KINDS, lamp_names

                    lamp_material = {name: scene.add_material("coated", {"albedo": list(LAMP_KINDS[k]["lens"]),
                                                                          "roughness": 0.05, "specular": 0.5})
                                     for name, k, _ in lamp_names(entry)}
                arrays = self._grey_filled(arrays)
                body = arrays
                built = build_vehicle(arrays, entry, unit, tyre, rim, plate_material, lamp_material)
                plates, lamps, arrays = built.pop("plates"), built.pop("lamps"), built
                mesh_id = scene.add_mesh(arrays["positions"], arrays["indices"], normals=arrays["normals"],
                                         uvs=arrays["uvs"], material_ids=arrays["material_ids"], name=value)
            pos = np.asarray(arrays["positions"], np.float64)
            ids = np.asarray(arrays["material_ids"], np.int64)
            distinct = tuple(int(i) for i in np.unique(ids)) if ids.size else (-1,)
            shape = Shape(mesh_id, pos.min(axis=0), pos.max(axis=0), True, unit, distinct, **axes)
            shape.plates, shape.plate_material, shape.roles = plates, plate_material, roles
            shape.lamps, shape.lamp_material = lamps, lamp_material
            if kind == "asset" and entry.get("lods"):
                from ..scene.vehicles import body_lift

                vehicle = any(k in entry for k in ("wheels", "plates", "lamps"))
                if not vehicle:
                    body = arrays
                shape.lod_errors = tuple(level["error"] for level in assets.lods(value))
                shape.lod_meshes = {0: (mesh_id, len(arrays["indices"]), mesh_bytes(arrays))}
                shape._lod = {"asset": value, "entry": entry, "unit": unit, "body": body,
                              "vehicle": (tyre, rim, plate_material, lamp_material,
                                          body_lift(body, entry, unit)) if vehicle else None}
            return shape
        if kind == "primitive":
            # Unit shapes (1 m across, centred), sized per object by scaling.
            m = {"box": lambda: P.box((1.0, 1.0, 1.0)), "sphere": lambda: P.uv_sphere(0.5, 48, 24),
                 "cylinder": lambda: P.cylinder(0.5, 1.0, 48), "cone": lambda: P.cone(0.5, 1.0, 48)}[value]()
            mid = scene.add_mesh(m["positions"], m["indices"], normals=m["normals"], uvs=m["uvs"], name=value)
            return Shape(mid, np.full(3, -0.5), np.full(3, 0.5), False)
        mid, lo, hi = randomize.randomizer(kind).make_shape(scene)
        return Shape(mid, lo, hi, False)


    def _grey_filled(self, arrays: Mapping[str, Any]) -> Dict[str, Any]:
        """A model's arrays with the worker's grey material on triangles that have none."""
        mids = np.asarray(arrays["material_ids"])
        if mids.size and not (mids < 0).any():
            return dict(arrays)
        return dict(arrays, material_ids=np.where(mids < 0, self._grey(), mids) if mids.size else
                    np.full(len(arrays["indices"]), self._grey(), np.int32))

    def level_mesh(self, shape: Shape, level: int) -> Optional[int]:
        """The mesh of level of detail ``level`` of a library model (0: the finest, ``shape``'s
        own), made on first use: the level's file, each of its triangles given the material of
        the finest level's closest triangle (so that the object's materials, their randomized
        paint and wear, apply to every level alike), then the same wheels, plates and lamps.
        None when the level cannot carry them (a lamp or plate mount the coarse body has lost:
        shape.lod_unusable says why; the caller takes a finer level)."""
        if level not in shape.lod_meshes and level not in shape.lod_unusable:
            try:
                shape.lod_meshes[level] = self._make_level(shape, level)
            except ValueError as e:  # vehicles.plate_mounts / lamp_lenses: the mount is off the body
                shape.lod_unusable[level] = str(e)
        return shape.lod_meshes[level][0] if level in shape.lod_meshes else None

    def _make_level(self, shape: Shape, level: int) -> Tuple[int, int, int]:
        from ..scene import assets
        from ..scene.vehicles import build_vehicle
        from .._core import surface_distances

        lod = shape._lod
        assert lod is not None, "level_mesh: the shape has no levels of detail"
        path = assets.lods(lod["asset"])[level]["path"]
        scene = self.scene
        r = scene.load_mesh_file(path)
        arrays = scene.mesh_arrays(r["mesh_id"])
        # The level's own mesh and materials go: its triangles take the finest level's materials.
        scene.remove_mesh(r["mesh_id"])
        for m in r["material_ids"]:
            scene.remove_material(int(m))
        for t in r.get("texture_ids", []):
            scene.remove_texture(int(t))
        body = lod["body"]
        pos, tri = np.asarray(arrays["positions"], np.float32), np.asarray(arrays["indices"], np.int64)
        centroids = pos[tri.reshape(-1, 3)].mean(axis=1)
        _, closest = surface_distances(np.asarray(body["positions"], np.float32),
                                       np.asarray(body["indices"], np.int64).reshape(-1, 3), centroids,
                                       return_triangles=True)
        arrays = dict(arrays, material_ids=np.asarray(body["material_ids"], np.int32)[closest])
        if lod["vehicle"] is not None:
            tyre, rim, plate_material, lamp_material, lift = lod["vehicle"]
            arrays = build_vehicle(arrays, lod["entry"], lod["unit"], tyre, rim, plate_material, lamp_material,
                                   lift=lift)
            arrays.pop("plates")
            arrays.pop("lamps")
        mesh_id = scene.add_mesh(arrays["positions"], arrays["indices"], normals=arrays.get("normals"),
                                 uvs=arrays.get("uvs"), material_ids=arrays["material_ids"],
                                 name=f"{lod['asset']} lod{level}")
        return mesh_id, len(np.asarray(arrays["indices"]).reshape(-1, 3)), mesh_bytes(arrays)


class FrameLibrary:
    """A Scene facade that records the ids of the textures and materials added through it
    (the per-frame resources, removed when the next frame is set up)."""

    def __init__(self, scene: Scene):
        self._scene = scene
        self._textures: List[int] = []
        self._materials: List[int] = []

    def add_texture(self, *a: Any, **k: Any) -> int:
        i = self._scene.add_texture(*a, **k)
        self._textures.append(i)
        return i

    def add_image_texture(self, *a: Any, **k: Any) -> int:
        i = self._scene.add_image_texture(*a, **k)
        self._textures.append(i)
        return i

    def add_material(self, *a: Any, **k: Any) -> int:
        i = self._scene.add_material(*a, **k)
        self._materials.append(i)
        return i

    def remove_texture(self, texture_id: int) -> None:
        self._scene.remove_texture(texture_id)
        if texture_id in self._textures:
            self._textures.remove(texture_id)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._scene, name)

    def release(self) -> None:
        """Removes everything recorded (newest first: mixes before what they mix)."""
        for mid in reversed(self._materials):
            self._scene.remove_material(mid)
        for tid in reversed(self._textures):
            self._scene.remove_texture(tid)
        self._materials, self._textures = [], []


class Pool:
    """Instance ids reused across frames; :meth:`take` returns the instance for slot ``k``
    (adding one with ``make`` when the pool is too small)."""

    def __init__(self) -> None:
        self.ids: List[int] = []

    def take(self, k: int, make: Callable[[], int]) -> Tuple[int, bool]:
        """(instance id of slot k, whether it already existed)."""
        if k < len(self.ids):
            return self.ids[k], True
        self.ids.append(make())
        return self.ids[-1], False

    def beyond(self, n: int) -> List[int]:
        """The ids of slots n and above (unused this frame)."""
        return self.ids[n:]
