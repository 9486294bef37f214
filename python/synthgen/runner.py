"""Scenario runner: frames of a scenario -> a labelled dataset on disk.

Layout of the output directory (frame k is ``{k:06d}``)::

    images/000000.png        sRGB 8-bit            images/000000.exr   linear float (rgb_exr)
    depth/000000.exr         camera z in metres, float32, +inf on background
    depth16/000000.png       uint16 millimetres, 0 = no surface or beyond 65.535 m (depth16)
    instance/000000.png      uint16 instance ids (1..N per frame, 0 = background/ground)
    semantic/000000.png      uint16 class ids (1 + index in the scenario's class list)
    labels/000000.txt        YOLO; dataset.yaml names the classes
    kitti/000000.txt         KITTI 2D labels (+ 3D fields in the camera frame)
    meta/000000.json         seed, every sampled parameter, objects (boxes, occlusion,
                             truncation, pose), the frame's COCO records; written last
    annotations/coco.json    assembled from meta/*.json at the end of a run (and on resume)

Every file is written to a temporary name and renamed; ``meta`` is written last and marks
a frame complete, so ``--resume`` renders exactly the frames without it and a killed run
leaves no partial file under a final name.

Each frame is a pure function of (scenario, frame index): its random numbers come from
:func:`synthgen.scenario.frame_rng`, its renders from a seed derived from the same pair, and
the worker's scene state (kept across frames: meshes and BVHs, materials, lights) never
changes the result. Frames are therefore bit-identical whichever worker renders them.
"""
from __future__ import annotations

import glob
import math
import os
import signal
import time
import traceback
from collections.abc import Mapping
from typing import Any, Callable, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple

import numpy as np

from . import annotations as A
from . import primitives as P
from . import scenario as S
from . import writers as W
from ._core import PinholeCamera, Scene, SynthgenError, TextureRef, load_image_plugin

__all__ = ["FrameRenderer", "write_frame", "assemble_coco", "write_yolo_dataset_yaml", "run", "frame_name",
           "completed_frames", "LocalExecutor", "DaskExecutor", "RunSummary"]

#: Objects may extend this far beyond the image on each side (fraction of the image size)
#: and still be measured for truncation.
TRUNCATION_PAD = 0.5


def frame_name(k: int) -> str:
    return f"{int(k):06d}"


def _rot_y(deg: float) -> np.ndarray:
    return P.rotate([0.0, 1.0, 0.0], float(deg))


def _look_at(eye, target) -> np.ndarray:
    return np.asarray(PinholeCamera.look_at(list(map(float, eye)), list(map(float, target)), [0.0, 1.0, 0.0]),
                      np.float64)


def _sun_direction(elevation: float, azimuth: float) -> List[float]:
    # The sky model's convention (light/sky.cpp): x = cos(el) sin(az), y = sin(el), z = -cos(el) cos(az).
    el, az = math.radians(elevation), math.radians(azimuth)
    return [math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)]


def light_params(light: Mapping[str, Any]) -> Tuple[str, Dict[str, Any]]:
    """synthgen light plugin (type, params) of a sampled scenario light."""
    t = light["type"]
    if t == "sky":
        return "sky", {"elevation": light["elevation"], "azimuth": light["azimuth"], "turbidity": light["turbidity"],
                       "strength": light["strength"]}
    if t == "envmap":
        if light.get("asset"):
            from . import assets

            path = assets.resolve(light["asset"])
        else:
            path = light["file"]
        return "envmap", {"filename": path, "rotation": light["rotation"], "strength": light["strength"],
                          "visible": light["visible"]}
    if t == "sun":
        return "sun", {"direction": _sun_direction(light["elevation"], light["azimuth"]),
                       "irradiance": list(light["irradiance"]), "angular_diameter": light["angular_diameter"]}
    if t == "environment":
        return "environment", {"radiance": list(light["radiance"])}
    raise SynthgenError(f"unknown light type {t!r}")


def material_params(m: Mapping[str, Any]) -> Tuple[str, Dict[str, Any]]:
    """synthgen material plugin (type, params) of a sampled scenario material."""
    p = {k: (list(v) if isinstance(v, tuple) else v) for k, v in m.items() if k != "type" and v is not None}
    return m["type"], p


class _Shape:
    """A mesh in the worker's scene with its object-space bounds."""

    def __init__(self, mesh_id: int, lo: np.ndarray, hi: np.ndarray, own_materials: bool):
        self.mesh_id, self.lo, self.hi, self.own_materials = mesh_id, lo, hi, own_materials
        self.unit = 1.0  # metres per mesh unit


def _image_aspect(path: str) -> float:
    """Width / height of an image file (its header, through OpenImageIO)."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SynthgenError(f"{path}: cannot read the image: {oiio.geterror()}")
    spec = inp.spec()
    inp.close()
    return float(spec.width) / float(max(spec.height, 1))


class _Recorder:
    """A Scene facade that records the ids of the textures and materials added through it
    (the per-frame resources the frame renderer removes again)."""

    def __init__(self, scene: Scene, textures: List[int], materials: List[int]):
        self._scene, self._t, self._m = scene, textures, materials

    def add_texture(self, *a: Any, **k: Any) -> int:
        i = self._scene.add_texture(*a, **k)
        self._t.append(i)
        return i

    def add_material(self, *a: Any, **k: Any) -> int:
        i = self._scene.add_material(*a, **k)
        self._m.append(i)
        return i

    def remove_texture(self, texture_id: int) -> None:
        self._scene.remove_texture(texture_id)
        if texture_id in self._t:
            self._t.remove(texture_id)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._scene, name)


class FrameRenderer:
    """Renders frames of one scenario, keeping the scene (meshes and their BVHs, the
    ground, material slots) across frames; per frame only instances, materials, lights
    and the camera change."""

    def __init__(self, scenario: S.Scenario, threads: int = 0):
        self.sc = scenario
        self.threads = int(threads)
        self.scene = Scene()
        self._shapes: Dict[Any, _Shape] = {}
        self._pool: List[int] = []        # instance ids, reused frame after frame
        self._decor: List[int] = []       # unlabelled instances (sign poles, plate posts), reused too
        self._frame_textures: List[int] = []   # textures and materials made for one frame (signs,
        self._frame_materials: List[int] = []  # plates, wear), removed when the next frame is set up
        import shutil
        import tempfile
        import weakref

        # Generated images (signs, plates, decals) of the current frame; the directory goes
        # when the renderer does (or at exit), files of a frame when the next one is set up.
        self._tmp = tempfile.mkdtemp(prefix="synthgen-worker-")
        weakref.finalize(self, shutil.rmtree, self._tmp, True)
        self._frame_images: set = set()
        self._instances: List[int] = []   # this frame's objects (a prefix of the pool)
        self._lights: List[int] = []
        self._materials: List[int] = []
        self._ground_instance: Optional[int] = None
        self._ground_material: Optional[int] = None
        self._pole_material: Optional[int] = None
        g = scenario.spec["ground"]
        if g["enabled"]:
            pl = P.plane(float(g["size"]), float(g["size"]))
            gm = self.scene.add_mesh(pl["positions"], pl["indices"], normals=pl["normals"], uvs=pl["uvs"], name="ground")
            self._ground_instance = self.scene.add_instance(gm, np.eye(4), class_id=0, instance_id=0)

    # -- shapes -----------------------------------------------------------------------
    def _shape(self, obj: Mapping[str, Any]) -> _Shape:
        if obj.get("sign") is not None or obj.get("plate") is not None:
            key = ("panel", "sign" if obj.get("sign") is not None else "plate")
        elif obj.get("asset"):
            key = ("asset", obj["asset"])
        else:
            key = ("mesh", obj["mesh"]) if obj.get("mesh") else ("primitive", obj["primitive"])
        if key in self._shapes:
            return self._shapes[key]
        if key[0] == "panel":
            if key[1] == "sign":
                # A unit square in the x-y plane facing -z (towards a camera at azimuth 0, whose image
                # right is world -x): u runs along -x so the pictogram reads correctly from the front.
                q = np.array([[-0.5, 0, 0], [0.5, 0, 0], [0.5, 1, 0], [-0.5, 1, 0]], np.float32)
                mid = self.scene.add_mesh(q, np.array([[0, 2, 1], [0, 3, 2]], np.uint32),
                                          uvs=np.array([[1, 0], [0, 0], [0, 1], [1, 1]], np.float32), name="sign")
                lo, hi = np.array([-0.5, 0.0, 0.0]), np.array([0.5, 1.0, 0.0])
            else:
                b = P.box((1.0, 1.0, 1.0))
                mid = self.scene.add_mesh(b["positions"], b["indices"], normals=b["normals"], uvs=b["uvs"], name="plate")
                lo, hi = np.full(3, -0.5), np.full(3, 0.5)
            shape = _Shape(mid, lo, hi, False)
            self._shapes[key] = shape
            return shape
        if key[0] in ("mesh", "asset"):
            unit = 1.0
            path = key[1]
            if key[0] == "asset":
                from . import assets

                path = assets.resolve(key[1])
                unit = float(assets.entry(key[1]).get("scale", 1.0))
            r = self.scene.load_mesh_file(path)
            arr = self.scene.mesh_arrays(r["mesh_id"])
            pos = np.asarray(arr["positions"], np.float64)
            shape = _Shape(r["mesh_id"], pos.min(axis=0), pos.max(axis=0), True)
            shape.unit = unit
        else:
            m = P.box((1.0, 1.0, 1.0)) if key[1] == "box" else P.uv_sphere(0.5, 48, 24)
            mid = self.scene.add_mesh(m["positions"], m["indices"], normals=m["normals"], uvs=m["uvs"], name=key[1])
            shape = _Shape(mid, np.full(3, -0.5), np.full(3, 0.5), False)
        self._shapes[key] = shape
        return shape

    def _object_local(self, obj: Mapping[str, Any], shape: _Shape) -> Tuple[np.ndarray, float, np.ndarray]:
        """(object_from_shape scale/lift matrix, footprint radius, box size in metres)."""
        size = np.asarray(obj["size"], np.float64) * float(obj["scale"])
        if obj.get("sign") is not None:
            s = float(obj["sign"]["size"]) * float(obj["scale"])
            m = np.eye(4)
            m[:3, :3] = np.diag([s, s, 1.0])
            m[1, 3] = float(obj["sign"]["mount_height"])
            return m, 0.5 * s, np.array([s, s + float(obj["sign"]["mount_height"]), 0.02])
        if obj.get("plate") is not None:
            w, h = 0.52 * float(obj["scale"]), (0.112 if obj["plate"]["country"] == "ru" else 0.11) * float(obj["scale"])
            m = np.eye(4)
            m[:3, :3] = np.diag([w, h, 0.01])
            m[1, 3] = float(obj["plate"]["mount_height"]) + 0.5 * h
            return m, 0.5 * w, np.array([w, h + float(obj["plate"]["mount_height"]), 0.01])
        if shape.own_materials:  # meshes keep their proportions: size is a per-axis scale factor
            ext = (shape.hi - shape.lo) * shape.unit  # in metres (manifest `scale`)
            dims = ext * size
        else:
            dims = size.copy()
            if obj.get("primitive") == "sphere":
                dims = np.full(3, size[0])
        s = dims / np.maximum(shape.hi - shape.lo, 1e-12)
        centre = 0.5 * (shape.lo + shape.hi)
        # Scale about the bounds' centre, then lift so the lowest point touches y = 0.
        m = np.eye(4)
        m[:3, :3] = np.diag(s)
        m[:3, 3] = -centre * s + np.array([0.0, 0.5 * dims[1], 0.0])
        radius = 0.5 * math.hypot(dims[0], dims[2])
        return m, radius, dims

    # -- per frame ----------------------------------------------------------------------
    def _camera(self, cam: Mapping[str, Any], rng: np.random.Generator) -> PinholeCamera:
        w, h = self.sc.resolution
        pose = cam["pose"]
        if pose["type"] == "orbit":
            target = np.asarray(pose["target"], np.float64)
            j = float(pose["jitter"])
            if j > 0:
                target = target + rng.uniform(-j, j, 3)
            el, az = math.radians(pose["elevation"]), math.radians(pose["azimuth"])
            d = float(pose["distance"])
            eye = target + d * np.array([math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)])
        else:
            eye, target = np.asarray(pose["eye"], np.float64), np.asarray(pose["target"], np.float64)
        wfc = _look_at(eye, target)
        if cam.get("fx") is not None:
            fx = float(cam["fx"])
            fy = float(cam["fy"]) if cam.get("fy") is not None else fx
            cx = float(cam["cx"]) if cam.get("cx") is not None else 0.5 * w
            cy = float(cam["cy"]) if cam.get("cy") is not None else 0.5 * h
            return PinholeCamera(fx, fy, cx, cy, w, h, wfc)
        return PinholeCamera.from_fov(float(cam["fov_y"]), w, h, wfc)

    def _set_lights(self, lights: Sequence[Mapping[str, Any]]) -> None:
        for lid in self._lights:
            self.scene.remove_light(lid)
        self._lights = []
        for light in lights:
            t, p = light_params(light)
            self._lights.append(self.scene.add_light(t, p))

    def _material(self, slot: int, m: Mapping[str, Any]) -> int:
        t, p = material_params(m)
        while len(self._materials) <= slot:
            self._materials.append(self.scene.add_material("diffuse", {}))
        mid = self._materials[slot]
        self.scene.update_material(mid, t, p)
        return mid

    def _generated_image(self, name: str, img: np.ndarray) -> str:
        """Path of a generated image in the worker's directory; files are named by content, so
        the scene's image cache decodes each one once per worker."""
        import hashlib

        digest = hashlib.sha1(np.ascontiguousarray(img).tobytes()).hexdigest()[:16]
        path = os.path.join(self._tmp, f"{name}-{digest}.exr")
        if not os.path.exists(path):
            W.write_exr(path, np.asarray(img, np.float32))
        self._frame_images.add(path)
        return path

    def _image_texture(self, rec: "_Recorder", name: str, rgb: np.ndarray) -> int:
        """A generated image as a texture (see _generated_image)."""
        return rec.add_texture("image", {"filename": self._generated_image(name, rgb), "wrap": "clamp",
                                         "colorspace": "linear"})

    def _sign_material(self, rec: "_Recorder", o: Dict[str, Any]) -> int:
        from . import signs

        sg = o["sign"]
        s = signs.render_sign(sg["family"], sg.get("text"), 256)
        o["_sign"] = {"family": s["family"], "text": s["text"], "class_name": s["class_name"]}
        tex = self._image_texture(rec, "sign", s["rgba"])
        return rec.add_material("principled", {"base_color": TextureRef(tex), "alpha": TextureRef(tex),
                                               "alpha_mode": "mask", "roughness": 0.45})

    def _plate_material(self, rec: "_Recorder", o: Dict[str, Any], rng: np.random.Generator) -> int:
        from . import plates

        reg = plates.random_registration(o["plate"]["country"], rng)
        p = plates.render_plate(reg, px_per_mm=1.5)
        o["_plate"] = {"country": reg["country"], "text": reg["text"], "text_latin": p["text_latin"]}
        col = self._image_texture(rec, "plate", p["rgb"])
        nrm = self._image_texture(rec, "plate-normal", p["normal"])
        return rec.add_material("principled", {"base_color": TextureRef(col), "normal_map": TextureRef(nrm),
                                               "roughness": 0.35, "metallic": 0.0})

    def _apply_decals(self, rec: "_Recorder", mat: int, o: Dict[str, Any], shape: "_Shape",
                      rng: np.random.Generator) -> int:
        """Projects each decal onto the object's front (-z) from a projector in object space."""
        from . import plates, signs, wear

        if mat < 0:
            mat = rec.add_material("diffuse", {"albedo": 0.5})
        lo, hi = np.asarray(shape.lo, np.float64), np.asarray(shape.hi, np.float64)
        ext = np.maximum(hi - lo, 1e-6)
        centre = 0.5 * (lo + hi)
        done = []
        for d in o["decals"]:
            if float(rng.random()) >= float(d["probability"]):
                continue
            if d.get("plate") is not None:
                reg = plates.random_registration(d["plate"]["country"], rng)
                w_mm, h_mm = plates.SIZE_MM[reg["country"]]
                img, aspect = plates.render_plate(reg, px_per_mm=1.0)["rgb"], w_mm / h_mm
                info = {"kind": "plate", "country": reg["country"], "text": reg["text"]}
                path = None
            elif d.get("pictogram") is not None:
                sg_ = signs.render_sign(d["pictogram"]["family"], d["pictogram"].get("text"), 128)
                img, aspect = signs.on_background(sg_["rgba"]), 1.0
                info = {"kind": "pictogram", "class_name": sg_["class_name"]}
                path = None
            else:
                img, aspect, path = None, _image_aspect(d["image"]), d["image"]
                info = {"kind": "image", "file": os.path.basename(d["image"])}
            if path is None:
                path = self._generated_image("decal", img)
            width = float(d["size"]) * float(ext[0])
            cy = float(lo[1] + float(d["height"]) * ext[1])
            dist = 2.0 * float(ext.max()) + 1e-3
            target = [float(centre[0]), cy, float(centre[2])]
            position = [float(centre[0]), cy, float(lo[2]) - dist]
            fov = float(np.degrees(2.0 * np.arctan(0.5 * width / aspect / (dist + 0.5 * ext[2]))))
            mat = wear.decal(rec, mat, path, position=position, look_at=target, fov=max(fov, 0.1), aspect=aspect,
                             occlusion=False, space="object")
            # The decal's size on the object's front (object units): the image keeps its aspect.
            info["size"] = [round(width, 6), round(width / aspect, 6)]
            done.append(info)
        o["_decals"] = done
        return mat

    def _apply_wear(self, rec: "_Recorder", mat: int, o: Dict[str, Any], rng: np.random.Generator) -> int:
        from . import wear

        applied = {}
        if mat < 0:
            mat = rec.add_material("diffuse", {"albedo": 0.5})
        for effect in ("rust", "dirt", "scratches", "ice"):
            spec = o["wear"].get(effect)
            if spec is None:
                continue
            if float(rng.random()) >= float(spec["probability"]):
                continue
            kw = {k: v for k, v in spec.items() if k not in ("probability", "seed") and v is not None}
            if "colors" in kw:  # ramp stops {position, color} -> (position, (r, g, b))
                kw["colors"] = sorted((float(c["position"]), tuple(float(x) for x in c["color"])) for c in kw["colors"])
            seed = spec.get("seed")
            kw["seed"] = int(seed) if seed is not None else int(rng.integers(0, 1 << 31))
            mat = getattr(wear, effect)(rec, mat, **kw)
            applied[effect] = kw
        o["_wear"] = applied
        return mat

    def _place(self, objects: List[Dict[str, Any]], rng: np.random.Generator) -> List[Optional[Tuple[float, float]]]:
        """Positions (x, z) on the ground; None where an object found no free spot."""
        pl = self.sc.spec["placement"]
        x0, z0, x1, z1 = pl["region"]
        placed: List[Tuple[float, float, float]] = []
        out: List[Optional[Tuple[float, float]]] = []
        for o in objects:
            r = o["_radius"]
            spot = None
            for _ in range(100):
                x, z = float(rng.uniform(x0, x1)), float(rng.uniform(z0, z1))
                if not pl["non_overlapping"] or all(
                        math.hypot(x - px, z - pz) >= r + pr + pl["margin"] for px, pz, pr in placed):
                    spot = (x, z)
                    break
            if spot is not None:
                placed.append((spot[0], spot[1], r))
            out.append(spot)
        return out

    def _labels(self, camera: PinholeCamera) -> Any:
        self.scene.set_camera(camera)
        self.scene.commit()
        return self.scene.render(spp=1, labels_only=True, threads=self.threads)

    def _amodal(self, camera: PinholeCamera, k: int) -> Tuple[int, int]:
        """(amodal pixels inside the image, amodal pixels on a canvas padded by
        TRUNCATION_PAD on every side) of object k rendered alone."""
        w, h = self.sc.resolution
        pw, ph = int(round(TRUNCATION_PAD * w)), int(round(TRUNCATION_PAD * h))
        K = np.asarray(camera.K, np.float64)
        padded = PinholeCamera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]) + pw, float(K[1, 2]) + ph,
                               w + 2 * pw, h + 2 * ph, np.asarray(camera.world_from_camera, np.float64))
        for i, inst in enumerate(self._instances):
            self.scene.set_instance_visible(inst, i == k)
        for d in self._decor:
            self.scene.set_instance_visible(d, False)
        if self._ground_instance is not None:
            self.scene.set_instance_visible(self._ground_instance, False)
        r = self._labels(padded)
        mask = np.asarray(r.instance_id) == k + 1
        inside = int(mask[ph:ph + h, pw:pw + w].sum())
        return inside, int(mask.sum())

    def _show(self, objects: Sequence[Dict[str, Any]], visible: Sequence[bool]) -> None:
        """Shows the frame's objects (and their poles) where `visible`, hides the others."""
        for inst, v in zip(self._instances, visible):
            self.scene.set_instance_visible(inst, bool(v))
        for o, v in zip(objects, visible):
            if o.get("_decor") is not None:
                self.scene.set_instance_visible(self._decor[o["_decor"]], bool(v))
        if self._ground_instance is not None:
            self.scene.set_instance_visible(self._ground_instance, True)

    def render(self, frame: int) -> Tuple[Dict[str, np.ndarray], Dict[str, Any], Dict[str, float]]:
        """(arrays, meta, timings) of one frame."""
        t0 = time.perf_counter()
        sc = self.sc
        params = S.sample_frame(sc, frame)
        layout_rng = S.frame_rng(sc.seed, frame, 1)
        camera = self._camera(params["camera"], S.frame_rng(sc.seed, frame, 2))
        self._set_lights(params["lights"])
        if self._ground_instance is not None:
            if self._ground_material is None:
                self._ground_material = self.scene.add_material("diffuse", {})
            t, p = material_params(params["ground"]["material"])
            self.scene.update_material(self._ground_material, t, p)
            self.scene.set_instance_material(self._ground_instance, self._ground_material)
        # Instances of this frame: a pool of instance ids, id k always for the frame's object k
        # (so instance order, and with it every light list, is the same on every worker
        # whatever it rendered before); ids beyond this frame's objects are hidden. The pool
        # only grows to the largest object count, so long runs do not accumulate slots.
        objects = params["objects"]
        for inst in self._pool[len(objects):]:
            self.scene.set_instance_visible(inst, False)
            self.scene.set_instance_material(inst, -1)
        old_textures, old_materials = self._frame_textures, self._frame_materials
        self._frame_textures, self._frame_materials = [], []
        old_images, self._frame_images = self._frame_images, set()
        rec = _Recorder(self.scene, self._frame_textures, self._frame_materials)
        self._instances = []
        n_decor = 0
        for k, o in enumerate(objects):
            shape = self._shape(o)
            local, radius, dims = self._object_local(o, shape)
            o["_local"], o["_radius"], o["_dims"] = local, radius, dims
            obj_rng = S.frame_rng(sc.seed, frame, 100 + k)
            mat = -1
            if o.get("sign") is not None:
                mat = self._sign_material(rec, o)
            elif o.get("plate") is not None:
                mat = self._plate_material(rec, o, obj_rng)
            elif o.get("material") is not None:
                mat = self._material(k, o["material"])
            elif not shape.own_materials:
                mat = self._material(k, {"type": "diffuse", "albedo": (0.5, 0.5, 0.5)})
            if o.get("decals"):
                mat = self._apply_decals(rec, mat, o, shape, obj_rng)
            if o.get("wear") is not None:
                mat = self._apply_wear(rec, mat, o, obj_rng)
            o["_decor"] = None
            if o.get("sign") is not None or o.get("plate") is not None:
                o["_decor"] = n_decor
                n_decor += 1
            if k < len(self._pool):
                inst = self._pool[k]
                self.scene.set_instance_mesh(inst, shape.mesh_id)
                self.scene.set_instance_material(inst, mat)
                self.scene.set_instance_labels(inst, o["class_index"] + 1, k + 1)
            else:
                inst = self.scene.add_instance(shape.mesh_id, np.eye(4), class_id=o["class_index"] + 1,
                                               instance_id=k + 1, material_id=mat)
                self._pool.append(inst)
            self._instances.append(inst)
        # Decor (poles, posts): unlabelled instances from their own pool.
        pole_mesh = self._shape({"primitive": "box"}).mesh_id
        if self._pole_material is None:
            self._pole_material = self.scene.add_material("conductor", {"metal": "iron", "roughness": 0.5})
        while len(self._decor) < n_decor:
            self._decor.append(self.scene.add_instance(pole_mesh, np.eye(4), class_id=0, instance_id=0,
                                                       material_id=self._pole_material))
        for d in self._decor[n_decor:]:
            self.scene.set_instance_visible(d, False)
        # The previous frame's generated textures and materials are unused now: remove them
        # (newest first: mixes before what they mix), so the library stays bounded.
        for mid in reversed(old_materials):
            self.scene.remove_material(mid)
        for tid in reversed(old_textures):
            self.scene.remove_texture(tid)
        # Generated image files only the previous frame used (a batch of many frames with
        # unique plates would otherwise fill the disk).
        for path in old_images - self._frame_images:
            try:
                os.remove(path)
            except OSError:
                pass
        t_update = time.perf_counter()

        # Layouts: retry until every placed object meets the visibility criteria.
        pl = sc.spec["placement"]
        need_amodal = pl["min_visible_fraction"] > 0.0 or pl["max_visible_fraction"] < 1.0
        best = None
        attempts = 0
        for attempt in range(pl["max_retries"] + 1):
            attempts = attempt + 1
            spots = self._place(objects, layout_rng)
            for k, (o, spot) in enumerate(zip(objects, spots)):
                if spot is None:
                    continue
                base = P.translate([spot[0], 0.0, spot[1]]) @ _rot_y(o["yaw"])
                o["_world"] = base @ o["_local"]
                self.scene.set_instance_transform(self._instances[k], o["_world"].astype(np.float32))
                if o["_decor"] is not None:
                    h = float((o.get("sign") or o.get("plate"))["mount_height"])
                    pole = base @ P.translate([0.0, 0.5 * h, 0.03]) @ P.scale([0.05, max(h, 1e-3), 0.05])
                    o["_decor_world"] = pole
                    self.scene.set_instance_transform(self._decor[o["_decor"]], pole.astype(np.float32))
            self._show(objects, [s is not None for s in spots])
            ids = np.asarray(self._labels(camera).instance_id)
            counts = np.bincount(ids.ravel(), minlength=len(objects) + 1)
            fails = []
            for k, spot in enumerate(spots):
                if spot is None:
                    fails.append((k, "no free spot in the placement region"))
                elif counts[k + 1] < max(1, pl["min_pixels"]):
                    fails.append((k, f"{int(counts[k + 1])} visible pixels < min_pixels {pl['min_pixels']}"))
            if need_amodal and not fails:
                for k in range(len(objects)):
                    inside, _ = self._amodal(camera, k)
                    frac = counts[k + 1] / inside if inside else 0.0
                    if frac < pl["min_visible_fraction"]:
                        fails.append((k, f"visible fraction {frac:.3f} < {pl['min_visible_fraction']}"))
                    elif frac > pl["max_visible_fraction"]:
                        fails.append((k, f"visible fraction {frac:.3f} > {pl['max_visible_fraction']}"))
                self._show(objects, [s is not None for s in spots])
            if best is None or len(fails) < len(best[1]):
                best = (spots, fails, [o.get("_world") for o in objects])
            if not fails:
                break
        spots, fails, worlds = best
        dropped = {k: reason for k, reason in fails}
        for k, o in enumerate(objects):
            if worlds[k] is not None:
                o["_world"] = worlds[k]
                self.scene.set_instance_transform(self._instances[k], worlds[k].astype(np.float32))
        keep = [spots[k] is not None and k not in dropped for k in range(len(objects))]
        t_layout = time.perf_counter()

        # Amodal masks of the kept objects, then the final render.
        amodal = {}
        for k in range(len(objects)):
            if keep[k]:
                amodal[k] = self._amodal(camera, k)
        self._show(objects, keep)
        self.scene.set_camera(camera)
        self.scene.commit()
        rs = sc.spec["render"]
        render_seed = int(np.random.SeedSequence([sc.seed, int(frame), 3]).generate_state(1, np.uint64)[0])
        res = self.scene.render(spp=rs["spp"], max_depth=rs["max_depth"], rr_depth=rs["rr_depth"], seed=render_seed,
                                threads=self.threads)
        t_render = time.perf_counter()

        arrays = {"rgb": np.asarray(res.rgb), "depth": np.asarray(res.depth),
                  "instance_id": np.asarray(res.instance_id), "class_id": np.asarray(res.class_id)}
        records = self._object_records(objects, keep, dropped, amodal, arrays["instance_id"], camera)
        meta = {
            "format": "synthgen-dataset-frame", "format_version": 1, "frame": int(frame),
            "scenario_seed": sc.seed, "render_seed": render_seed, "scenario_sha256": sc.sha256,
            "image_size": list(sc.resolution), "camera": W.camera_meta(camera),
            "render": dict(rs), "layout_attempts": attempts,
            "lights": [dict(zip(("type", "params"), light_params(li))) for li in params["lights"]],
            "objects": records, "sampled": params["sampled"],
            "class_names": list(sc.class_names),
        }
        timings = {"update_s": t_update - t0, "layout_s": t_layout - t_update, "render_s": t_render - t_layout}
        return arrays, meta, timings

    def _object_records(self, objects, keep, dropped, amodal, ids, camera) -> List[Dict[str, Any]]:
        w, h = self.sc.resolution
        wfc = np.asarray(camera.world_from_camera, np.float64)
        cfw = np.linalg.inv(wfc)
        out = []
        for k, o in enumerate(objects):
            rec: Dict[str, Any] = {"index": k, "instance_id": k + 1, "class": self.sc.class_names[o["class_index"]],
                                   "class_id": o["class_index"] + 1, "kind": o["kind"]}
            for key in ("sign", "plate", "wear", "decals"):
                if o.get("_" + key) is not None:
                    rec[key] = o["_" + key]
            if not keep[k]:
                rec["dropped"] = dropped.get(k, "no free spot in the placement region")
                out.append(rec)
                continue
            mask = ids == k + 1
            vis = int(mask.sum())
            inside, total = amodal[k]
            rec.update({"visible_pixels": vis, "amodal_pixels": inside,
                        "occlusion": float(1.0 - vis / inside) if inside else 1.0,
                        "visible_fraction": float(vis / inside) if inside else 0.0,
                        "truncation": float(1.0 - inside / total) if total else 1.0,
                        "bbox": A.mask_bbox(mask)})
            world = o["_world"]
            # 3D box: bottom centre, dimensions (h, w, l) = (y, z, x extents), heading = object +x.
            base = np.array([world[0, 3], 0.0, world[2, 3], 1.0])  # the footprint centre on the ground
            loc_cam = (cfw @ base)[:3]
            heading = cfw[:3, :3] @ (world[:3, :3] @ np.array([1.0, 0.0, 0.0]))
            ry = math.atan2(-heading[2], heading[0])
            dims = o["_dims"]
            rec.update({"world_from_object": world.tolist(), "dimensions_hwl": [float(dims[1]), float(dims[2]),
                                                                                 float(dims[0])],
                        "location_camera": [float(v) for v in loc_cam], "rotation_y": float(A.wrap_angle(ry)),
                        "alpha": float(A.wrap_angle(ry - math.atan2(loc_cam[0], loc_cam[2])))})
            out.append(rec)
        return out


# ---------------------------------------------------------------------------------------
# Writing (pure: arrays + meta -> files)

OUTPUT_DIRS = {"rgb": ("images", ".png"), "rgb_exr": ("images", ".exr"), "depth": ("depth", ".exr"),
               "depth16": ("depth16", ".png"), "instance": ("instance", ".png"), "semantic": ("semantic", ".png"),
               "yolo": ("labels", ".txt"), "kitti": ("kitti", ".txt"), "meta": ("meta", ".json")}


def _write_text(path: str, text: str) -> str:
    tmp = W._temp_path(path)
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        W._commit(tmp, path)
    except BaseException:
        W._discard(tmp)
        raise
    return path


def frame_annotations(meta: Mapping[str, Any], instance_id: np.ndarray) -> List[Dict[str, Any]]:
    """COCO annotations (image_id = frame, ids assigned later) of a frame's visible objects."""
    anns = []
    for o in meta["objects"]:
        if o.get("dropped") or not o.get("visible_pixels"):
            continue
        a = A.coco_annotation(1, int(meta["frame"]), int(o["class_id"]), instance_id == o["instance_id"],
                              extra={"instance_id": o["instance_id"], "occlusion": o["occlusion"],
                                     "truncation": o["truncation"]})
        if a is not None:
            anns.append(a)
    return anns


def write_frame(out_dir: str, frame: int, arrays: Mapping[str, np.ndarray], meta: Mapping[str, Any],
                outputs: Sequence[str]) -> Dict[str, str]:
    """Writes one frame's files (``outputs`` kinds; meta always, last). Returns {kind: path}."""
    name = frame_name(frame)
    path = lambda kind: os.path.join(out_dir, OUTPUT_DIRS[kind][0], name + OUTPUT_DIRS[kind][1])  # noqa: E731
    for kind in (set(outputs) | {"meta"}) & set(OUTPUT_DIRS):
        os.makedirs(os.path.dirname(path(kind)), exist_ok=True)
    w, h = meta["image_size"]
    ids = np.asarray(arrays["instance_id"])
    files: Dict[str, str] = {}
    if "rgb" in outputs:
        files["rgb"] = W.write_srgb_png(path("rgb"), arrays["rgb"])
    if "rgb_exr" in outputs:
        files["rgb_exr"] = W.write_exr(path("rgb_exr"), arrays["rgb"])
    depth = np.asarray(arrays["depth"], np.float32)
    if "depth" in outputs:
        files["depth"] = W.write_exr(path("depth"), depth)
    if "depth16" in outputs:
        mm = np.where(np.isfinite(depth), np.round(depth * 1000.0), 0.0)
        files["depth16"] = W.write_id_png(path("depth16"), np.where(mm > 65535, 0, mm).astype(np.uint16))
    if "instance" in outputs:
        files["instance"] = W.write_id_png(path("instance"), ids)
    if "semantic" in outputs:
        files["semantic"] = W.write_id_png(path("semantic"), arrays["class_id"])
    visible = [o for o in meta["objects"] if not o.get("dropped") and o.get("visible_pixels")]
    if "yolo" in outputs:
        lines = [A.yolo_line(o["class_id"] - 1, o["bbox"], w, h) for o in visible]
        files["yolo"] = _write_text(path("yolo"), "".join(line + "\n" for line in lines))
    if "kitti" in outputs:
        lines = [A.kitti_line(o["class"], o["bbox"], truncated=o["truncation"],
                              occluded=A.kitti_occlusion_level(o["visible_fraction"]), alpha=o["alpha"],
                              dimensions=o["dimensions_hwl"], location=o["location_camera"],
                              rotation_y=o["rotation_y"]) for o in visible]
        files["kitti"] = _write_text(path("kitti"), "".join(line + "\n" for line in lines))
    meta = dict(meta)
    meta["coco"] = {"image": {"id": int(frame), "file_name": f"images/{name}.png", "width": int(w), "height": int(h)},
                    "annotations": frame_annotations(meta, ids) if "coco" in outputs else []}
    meta["files"] = {k: os.path.relpath(v, out_dir) for k, v in files.items()}
    files["meta"] = W.write_json(path("meta"), meta)
    return files


def completed_frames(out_dir: str) -> List[int]:
    """Frames whose meta file exists (the last file written for a frame)."""
    out = []
    for p in glob.glob(os.path.join(out_dir, "meta", "[0-9]" * 6 + ".json")):
        out.append(int(os.path.basename(p)[:6]))
    return sorted(out)


def remove_temporaries(out_dir: str) -> int:
    """Deletes temporary files left by an interrupted run; returns how many."""
    n = 0
    for p in glob.glob(os.path.join(out_dir, "*", ".*.tmp*")) + glob.glob(os.path.join(out_dir, ".*.tmp*")):
        try:
            os.unlink(p)
            n += 1
        except OSError:
            pass
    return n


def assemble_coco(out_dir: str, class_names: Sequence[str], frames: Optional[Iterable[int]] = None) -> str:
    """annotations/coco.json from the per-frame records in meta/*.json."""
    import json

    images, anns = [], []
    for k in sorted(frames if frames is not None else completed_frames(out_dir)):
        with open(os.path.join(out_dir, "meta", frame_name(k) + ".json"), encoding="utf-8") as f:
            meta = json.load(f)
        images.append(meta["coco"]["image"])
        anns.extend(meta["coco"]["annotations"])
    ds = A.coco_dataset(images, anns, class_names, info={"description": "synthgen dataset", "version": "1"})
    path = os.path.join(out_dir, "annotations", "coco.json")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    return W.write_json(path, ds)


def write_yolo_dataset_yaml(out_dir: str, class_names: Sequence[str]) -> str:
    import yaml

    text = yaml.safe_dump({"path": os.path.abspath(out_dir), "train": "images", "val": "images",
                           "names": {i: n for i, n in enumerate(class_names)}}, sort_keys=False)
    return _write_text(os.path.join(out_dir, "dataset.yaml"), text)


# ---------------------------------------------------------------------------------------
# Execution: one task function for every executor

_WORKER: Dict[str, Any] = {}


def render_task(scenario_path: str, out_dir: str, frame: int, threads: int = 0) -> Dict[str, Any]:
    """Renders and writes one frame in the calling process, reusing this process's
    FrameRenderer for the same scenario. Returns {frame, ok, error, timings}."""
    try:
        key = (os.path.abspath(scenario_path), threads)
        fr = _WORKER.get("renderer")
        if fr is None or _WORKER.get("key") != key:
            load_image_plugin()
            fr = FrameRenderer(S.load_scenario(scenario_path), threads)
            _WORKER.update(renderer=fr, key=key, frames=0)
        t0 = time.perf_counter()
        arrays, meta, timings = fr.render(frame)
        t1 = time.perf_counter()
        write_frame(out_dir, frame, arrays, meta, fr.sc.spec["outputs"])
        timings["write_s"] = time.perf_counter() - t1
        timings["total_s"] = time.perf_counter() - t0
        _WORKER["frames"] += 1
        dropped = [o["dropped"] for o in meta["objects"] if o.get("dropped")]
        return {"frame": frame, "ok": True, "timings": timings, "dropped": dropped, "pid": os.getpid()}
    except Exception as e:  # reported per frame; the run goes on
        return {"frame": frame, "ok": False, "error": f"{type(e).__name__}: {e}",
                "traceback": traceback.format_exc(), "pid": os.getpid()}


def _init_worker() -> None:
    # Ctrl-C is handled by the parent, which then terminates the pool.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


class LocalExecutor:
    """Frames on a pool of worker processes on this machine (``workers`` = 1: in this
    process). Workers keep their scene across frames and are replaced after ``recycle``
    frames, so memory cannot grow without bound."""

    def __init__(self, workers: int = 1, recycle: int = 200):
        self.workers = max(1, int(workers))
        self.recycle = max(1, int(recycle))
        self._pool = None

    def map(self, fn: Callable, args: List[tuple]) -> Iterator[Dict[str, Any]]:
        if self.workers == 1:
            for a in args:
                yield fn(*a)
            return
        import multiprocessing as mp

        ctx = mp.get_context("spawn")  # no fork of a process with TBB/Embree threads
        self._pool = ctx.Pool(self.workers, initializer=_init_worker, maxtasksperchild=self.recycle)
        try:
            for r in self._pool.imap_unordered(_star, [(fn, a) for a in args]):
                yield r
            self._pool.close()
        except BaseException:
            self._pool.terminate()
            raise
        finally:
            self._pool.join()

    def shutdown(self) -> None:
        if self._pool is not None:
            self._pool.terminate()


def _star(fa):
    fn, a = fa
    return fn(*a)


class DaskExecutor:
    """Frames on a Dask distributed cluster (``address`` of a scheduler, or a
    ``distributed.Client``). Workers keep their scene across frames like local ones."""

    def __init__(self, address: Any):
        from distributed import Client

        self.client = address if isinstance(address, Client) else Client(address)
        self._own = not isinstance(address, Client)

    def map(self, fn: Callable, args: List[tuple]) -> Iterator[Dict[str, Any]]:
        from distributed import as_completed

        futures = [self.client.submit(fn, *a, pure=False, key=f"synthgen-frame-{a[2]}-{time.time_ns()}") for a in args]
        for fut in as_completed(futures):
            yield fut.result()

    def shutdown(self) -> None:
        if self._own:
            self.client.close()


class RunSummary(dict):
    """frames, failures (frame, reason), mean seconds per frame and per stage."""

    def text(self) -> str:
        lines = [f"frames rendered: {self['rendered']} (skipped as already complete: {self['skipped']}), "
                 f"failures: {len(self['failures'])}"]
        for f in self["failures"][:20]:
            lines.append(f"  frame {f['frame']}: {f['error']}")
        if self["rendered"]:
            st = ", ".join(f"{k[:-2]} {v:.3f}" for k, v in self["stage_s"].items())
            lines.append(f"mean seconds/frame: {self['mean_s_per_frame']:.3f} (per stage: {st}); "
                         f"wall {self['wall_s']:.1f} s, {self['frames_per_s']:.3f} frames/s")
        if self.get("interrupted"):
            lines.append("interrupted: completed frames are kept; run again with --resume")
        return "\n".join(lines)


def run(scenario_path: str, out_dir: str, count: Optional[int] = None, workers: int = 1,
        scheduler: Any = None, resume: bool = False, only: Optional[Sequence[int]] = None,
        recycle: int = 200, progress: bool = True, threads: Optional[int] = None) -> RunSummary:
    """Renders a scenario into ``out_dir`` (see the module docstring for the layout)."""
    sc = S.load_scenario(scenario_path)  # validate before anything renders
    n = int(count) if count is not None else sc.count
    frames = list(only) if only is not None else list(range(n))
    os.makedirs(out_dir, exist_ok=True)
    done = set(completed_frames(out_dir))
    if done and not resume and only is None:
        raise SynthgenError(f"{out_dir} already holds {len(done)} frame(s); use --resume to complete it "
                            f"or choose another output directory")
    removed = remove_temporaries(out_dir)
    todo = [k for k in frames if not (resume and k in done)] if only is None else frames
    if threads is None:
        threads = max(1, (os.cpu_count() or 1) // max(1, workers)) if (workers > 1 or scheduler) else 0
    if sc.spec["render"]["threads"]:
        threads = sc.spec["render"]["threads"]
    executor = DaskExecutor(scheduler) if scheduler is not None else LocalExecutor(workers, recycle)
    args = [(os.path.abspath(scenario_path), os.path.abspath(out_dir), k, threads) for k in todo]
    results, failures = [], []
    interrupted = False
    t0 = time.perf_counter()
    bar = None
    if progress:
        try:
            from tqdm import tqdm

            bar = tqdm(total=len(todo), unit="frame", desc="synthgen", dynamic_ncols=True)
        except ImportError:
            bar = None
    try:
        for r in executor.map(render_task, args):
            (results if r["ok"] else failures).append(r)
            if bar is not None:
                bar.update(1)
                if not r["ok"]:
                    bar.write(f"frame {r['frame']} failed: {r['error']}")
    except KeyboardInterrupt:
        interrupted = True
        executor.shutdown()
    finally:
        if bar is not None:
            bar.close()
        if scheduler is not None and not interrupted:
            executor.shutdown()
    wall = time.perf_counter() - t0
    complete = completed_frames(out_dir)
    if "coco" in sc.spec["outputs"]:
        assemble_coco(out_dir, sc.class_names, [k for k in complete if k < n or only is not None])
    if "yolo" in sc.spec["outputs"]:
        write_yolo_dataset_yaml(out_dir, sc.class_names)
    stages: Dict[str, float] = {}
    for r in results:
        for k, v in r["timings"].items():
            stages[k] = stages.get(k, 0.0) + v
    m = max(1, len(results))
    summary = RunSummary(
        rendered=len(results), skipped=len(frames) - len(todo), failures=[{"frame": f["frame"], "error": f["error"]}
                                                                         for f in failures],
        wall_s=wall, frames_per_s=len(results) / wall if wall > 0 else 0.0,
        mean_s_per_frame=stages.get("total_s", 0.0) / m,
        stage_s={k: v / m for k, v in stages.items() if k != "total_s"},
        interrupted=interrupted, temporaries_removed=removed, complete=len(complete))
    W.write_json(os.path.join(out_dir, "run_summary.json"), dict(summary))
    return summary


# ---------------------------------------------------------------------------------------
# Verification


def _read_u16(path: str) -> np.ndarray:
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise SynthgenError(f"{path}: {buf.geterror()}")
    return np.asarray(buf.get_pixels(oiio.UINT16))[..., 0].astype(np.int64)


def verify_dataset(out_dir: str) -> Dict[str, Any]:
    """Checks that the labels of a dataset agree with its masks: for every complete frame,
    each COCO annotation decodes to exactly the pixels of its instance in instance/*.png,
    bbox and area are the mask's, the semantic mask holds its category there, every visible
    instance is labelled once, and the YOLO and KITTI files hold the same boxes and classes.
    Returns counts; raises SynthgenError naming the first disagreement."""
    import json

    def fail(msg: str) -> None:
        raise SynthgenError(f"{out_dir}: {msg}")

    with open(os.path.join(out_dir, "annotations", "coco.json"), encoding="utf-8") as f:
        coco = json.load(f)
    names = [c["name"] for c in coco["categories"]]
    by_image: Dict[int, List[Dict[str, Any]]] = {}
    for a in coco["annotations"]:
        by_image.setdefault(a["image_id"], []).append(a)
    frames = completed_frames(out_dir)
    if sorted(im["id"] for im in coco["images"]) != frames:
        fail("annotations/coco.json does not list exactly the complete frames")
    n_ann = 0
    for k in frames:
        name = frame_name(k)
        ids = _read_u16(os.path.join(out_dir, "instance", name + ".png"))
        h, w = ids.shape
        sem_path = os.path.join(out_dir, "semantic", name + ".png")
        sem = _read_u16(sem_path) if os.path.isfile(sem_path) else None
        anns = sorted(by_image.get(k, []), key=lambda a: a["instance_id"])
        present = sorted(int(i) for i in np.unique(ids) if i != 0)
        if [a["instance_id"] for a in anns] != present:
            fail(f"frame {k}: COCO labels instances {[a['instance_id'] for a in anns]}, mask shows {present}")
        yolo_path = os.path.join(out_dir, "labels", name + ".txt")
        kitti_path = os.path.join(out_dir, "kitti", name + ".txt")
        yolo = A.parse_yolo(open(yolo_path).read(), w, h) if os.path.isfile(yolo_path) else None
        kitti = A.parse_kitti(open(kitti_path).read()) if os.path.isfile(kitti_path) else None
        for lst, what in ((yolo, "YOLO"), (kitti, "KITTI")):
            if lst is not None and len(lst) != len(anns):
                fail(f"frame {k}: {what} has {len(lst)} objects, COCO {len(anns)}")
        for j, a in enumerate(anns):
            m = ids == a["instance_id"]
            if not np.array_equal(A.rle_decode(a["segmentation"]), m):
                fail(f"frame {k}: the RLE of instance {a['instance_id']} is not its mask")
            if a["area"] != int(m.sum()) or a["bbox"] != A.mask_bbox(m):
                fail(f"frame {k}: area/bbox of instance {a['instance_id']} differ from its mask")
            if sem is not None and set(np.unique(sem[m]).tolist()) != {a["category_id"]}:
                fail(f"frame {k}: semantic mask disagrees with category of instance {a['instance_id']}")
            if yolo is not None:
                c, box = yolo[j]
                if c != a["category_id"] - 1 or np.max(np.abs(np.subtract(box, a["bbox"]))) > 1e-3 * max(w, h):
                    fail(f"frame {k}: YOLO line {j + 1} differs from COCO annotation {a['id']}")
            if kitti is not None:
                kt = kitti[j]
                if kt["type"] != names[a["category_id"] - 1].replace(" ", "_") or \
                        np.max(np.abs(np.subtract(kt["bbox"], a["bbox"]))) > 0.01:
                    fail(f"frame {k}: KITTI line {j + 1} differs from COCO annotation {a['id']}")
            n_ann += 1
    return {"frames": len(frames), "annotations": n_ann, "categories": names}
