"""The per-worker frame renderer: one scenario frame -> arrays, metadata and timings.

A :class:`FrameRenderer` owns one Scene for a worker's life: the ground and every mesh are
added once (BVHs built once), instance ids come from pools reused frame after frame, object
material slots are updated in place, lights are replaced. Each frame is a pure function of
(scenario, frame index): its parameters come from :func:`synthgen.scenario.sample_frame`,
its object randomness from per-object generators, its render seed from (seed, frame), and
what the worker rendered before never changes the result.
"""
from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import time
from typing import Any, Dict, List, Mapping, Optional, Set, Tuple

import numpy as np

from .._core import Scene, SynthgenError
from .. import post, randomize
from ..randomize import weather
from ..outputs.render import camera_meta
from ..scenario import Scenario, frame_rng, sample_frame
from ..scenario.sample import FrameSpec, ObjectSpec, PluginSpec
from ..scenario.schema import RENDER_KEYS
from ..schema.plugins import realize
from ..scene import primitives as P
from ..scene.vehicles import AXES, model_axes
from .exposure import apply_exposure, frame_exposure
from .layout import FrameView, search_layout, tilted
from .lod import amodal_and_levels
from .records import PlacedObject, frame_camera, level_frame, object_records, weather_labels
from .resources import FrameLibrary, Pool, Shape, Shapes

__all__ = ["FrameRenderer", "FrameSetup", "light_plugin"]


def light_plugin(light: PluginSpec) -> Tuple[str, Dict[str, Any]]:
    """(plugin name, parameters) of a sampled light; an envmap's asset id becomes its file."""
    params = dict(light.params)
    if "asset" in params:
        from ..scene import assets

        params["file"] = assets.resolve(params.pop("asset"))
    return light.type, params


def orientation(forward: str, up: str) -> Optional[np.ndarray]:
    """The rotation (a signed permutation) taking a model's ``forward`` axis to +x and its
    ``up`` axis to +y; None for the identity (+x, +y)."""
    if (forward, up) == ("+x", "+y"):
        return None
    try:
        return model_axes(forward, up)
    except ValueError:
        raise SynthgenError(f"a model's forward ({forward}) and up ({up}) must be different axes") from None


@dataclasses.dataclass
class FrameSetup:
    """A frame's scene as FrameRenderer.prepare left it (committed, not rendered)."""
    frame: int
    spec: FrameSpec
    fp: Any                     #: the photo frame (photo backgrounds) or None
    photo_info: Any
    camera: Any
    objects: List[PlacedObject]
    layout: Any
    keep: List[bool]
    amodal: Dict[int, Any]
    render_seed: int
    weather_ctx: Dict[str, Any]
    t0: float
    t_update: float
    t_layout: float
    geometry_lod: Optional[Dict[str, Any]] = None  #: meta ``geometry_lod`` (None: no levels shown)


class FrameRenderer:
    """Renders frames of one scenario, keeping the scene across frames (see the module
    docstring)."""

    def __init__(self, scenario: Scenario, threads: int = 0):
        self.sc = scenario
        self.threads = int(threads)
        self.scene = Scene()
        for path in scenario.spec["extensions"]:
            # Consented to when the scenario was loaded (allow_extensions in the file and by the
            # caller); a worker process loads the libraries again (compiled once, cached).
            from ..scene.extensions import load_extension

            load_extension(path, scene=self.scene)
        self.shapes = Shapes(self.scene)
        self.pool = Pool()                # object instances, id k for the frame's object k
        self.decor = Pool()               # unlabelled posts and poles below signs and plates
        #: Unlabelled geometry of the weather conditions (street lights' poles), a pool per
        #: condition: every instance is hidden before the frame's conditions apply.
        self.weather_pools: Dict[str, Pool] = {}
        self.slots: List[int] = []        # material slot k of object k, updated in place
        self._slots_set: Set[int] = set()  # the slots set this frame (_set_objects)
        self.library = FrameLibrary(self.scene)   # this frame's generated textures and materials
        self.lights: List[int] = []
        self.ground: Optional[int] = None
        self.ground_material: Optional[int] = None
        self.pole_material: Optional[int] = None
        self.default_material: Optional[int] = None
        self.mapped: Set[int] = set()     # instances that have a per-instance material map
        self.objects: List[PlacedObject] = []
        if scenario.spec["render"]["texture_lod"]:
            # Tiled mip-mapped copies of image files, shared by workers and runs: each frame
            # reads only the levels its camera needs (docs/texture_lod.md).
            from ..scene.assets import cache_dir

            self.scene.set_mip_cache_dir(os.path.join(cache_dir(), "mips"))
        bg = scenario.spec["background"]
        self.photos = None
        if bg is not None:
            # A photo's ground: a shadow catcher out to the horizon (labels 0, never labelled).
            from ..background.photoset import PhotoSet

            self.photos = PhotoSet(bg, scenario.base_dir, scenario.seed)
            pl = P.ground()
            gm = self.scene.add_mesh(pl["positions"], pl["indices"], normals=pl["normals"], uvs=pl["uvs"], name="ground")
            self.ground = self.scene.add_instance(gm, np.eye(4), class_id=0, instance_id=0)
            self.scene.set_instance_catcher(self.ground, True)
            self.last_photo = None
            return
        g = scenario.spec["ground"]
        if g["enabled"]:
            pl = P.ground() if g["size"] is None else P.plane(float(g["size"]), float(g["size"]))
            gm = self.scene.add_mesh(pl["positions"], pl["indices"], normals=pl["normals"], uvs=pl["uvs"], name="ground")
            self.ground = self.scene.add_instance(gm, np.eye(4), class_id=0, instance_id=0)
            if g["backplate"]:
                self.scene.set_instance_catcher(self.ground, True)

    def _add_dome(self, fp: Any, camera: Any, keep: List[bool], objects: List[PlacedObject], seed: int
                  ) -> Dict[str, Any]:
        """Adds the photo's dome (frame.photo.photo_dome) as a reflection-only environment, in the
        render's units: a pre-pass at a quarter of the resolution (4 spp, the objects hidden)
        gives the exposure that maps the rendered ground to the photo's; the dome is the photo
        divided by it. One map file per photo, kept for the worker's life."""
        import os
        import tempfile

        from .._core import PinholeCamera
        from ..outputs.files import write_exr
        from .photo import exposure_factor, photo_dome

        if not hasattr(self, "_dome_dir"):
            import atexit
            import shutil

            self._dome_dir = tempfile.mkdtemp(prefix="synthgen-dome-")
            atexit.register(shutil.rmtree, self._dome_dir, True)
        path = os.path.join(self._dome_dir, f"dome-{fp.photo.sha256[:16]}.exr")
        if not os.path.exists(path):
            write_exr(path, photo_dome(fp.photo.pixels, fp.setup.calibration))
        w, h = camera.width, camera.height
        q = 4
        small = PinholeCamera(camera.fx / q, camera.fy / q, (camera.cx + 0.5) / q - 0.5, (camera.cy + 0.5) / q - 0.5,
                              max(1, w // q), max(1, h // q), np.asarray(camera.world_from_camera, np.float64),
                              distortion=tuple(camera.distortion))
        self.scene.set_camera(small)
        with self._hidden(self.pool.ids + self.decor.ids):
            pre = self.scene.render(spp=4, max_depth=4, seed=seed, threads=self.threads)
        photo_small = fp.pixels[: (h // q) * q, : (w // q) * q].reshape(h // q, q, w // q, q, 3).mean(axis=(1, 3))
        ids = np.asarray(pre.instance_id)
        k, where = exposure_factor(photo_small, np.asarray(pre.rgb), np.zeros(ids.shape), (ids == 0) &
                                   np.isfinite(np.asarray(pre.depth)), [], np.zeros(ids.shape, bool))
        strength = float(1.0 / max(float(np.mean(k)), 1e-6))
        self.lights.append(self.scene.add_light("envmap", {"file": path, "strength": strength,
                                                           "reflection_only": True, "visible": False}))
        self.light_specs.append(("envmap", {"file": "photo dome", "strength": strength, "reflection_only": True}))
        return {"strength": strength, "pre_pass_exposure": [float(v) for v in k], "from": where}

    def _backplate(self, res: Any, rs: Mapping[str, Any], seed: int) -> Tuple[np.ndarray, Dict[str, Any]]:
        """The frame over the environment's own image: the camera's view of the lights alone
        (every instance hidden: each ray sees the map), the ground a catcher (ratio composite)."""
        from ..post.photo.composite import composite

        with self._hidden(self.pool.ids + self.decor.ids + [self.ground]):
            plate = np.array(self.scene.render(spp=rs["spp"], max_depth=1, seed=seed, threads=self.threads).rgb)
        return composite(plate, res, "ratio"), {"backplate": "the environment's own image", "composite": "ratio"}

    @contextlib.contextmanager
    def _hidden(self, ids: List[int]):
        """Hides the shown ones of these instances for a render, then shows them again."""
        shown = [i for i in ids if self.scene.instance_visible(i)]
        for i in shown:
            self.scene.set_instance_visible(i, False)
        try:
            yield
        finally:
            for i in shown:
                self.scene.set_instance_visible(i, True)

    def prepare(self, frame: int) -> "FrameSetup":
        """Sets the scene up for one frame -- lights, ground, objects, their layout, the camera,
        the weather -- and commits it, without rendering (render() goes on from here; tools
        such as ``synthgen texres`` look at the frame's scene)."""
        t0 = time.perf_counter()
        sc = self.sc
        spec = sample_frame(sc, frame)
        fp = photo_info = None
        if self.photos is not None:
            from ..schema import distributions as D
            from .photo import photo_lights, road_yaw

            bg = sc.spec["background"]
            prng = frame_rng(sc.seed, frame, 5)
            zoom = float(D.sample_tree(bg["zoom"], prng, "background.zoom", spec.sampled))
            fp = self.photos.frame(frame, sc.resolution, prng, zoom)
            self.last_photo = fp
            camera = fp.camera()
            lights, photo_info = photo_lights(fp, [light_plugin(li) for li in spec.lights])
            self._set_light_plugins(lights)
            # Objects' yaw is relative to the photo's road (0: along it, away from the camera).
            for o in spec.objects:
                o.yaw = float(o.yaw) + road_yaw(fp.setup.road_direction)
        else:
            camera = frame_camera(spec.camera, sc.resolution, frame_rng(sc.seed, frame, 2))
            self._set_lights(spec.lights)
        # This frame's generated textures and materials go into a new library; the previous
        # frame's are removed once this frame's exist (an image both use stays decoded).
        previous, self.library = self.library, FrameLibrary(self.scene)
        self._set_ground(spec)
        objects = self._set_objects(spec)
        previous.release()
        self._clear_weather()  # the previous frame's weather geometry must not take part in this layout
        self.objects, self.camera = objects, camera  # the frame's placed objects and camera (tools, tests)
        t_update = time.perf_counter()

        view = FrameView(self.scene, objects, self.decor.ids, self.ground, sc.resolution, self.threads)
        if fp is not None:
            from .photo import PhotoPlacement

            bg = sc.spec["background"]
            view.photo = PhotoPlacement(fp, camera, bg["min_distance"], bg["max_distance"], bg["max_real_overlap"])
        layout = search_layout(view, camera, sc.spec["placement"], frame_rng(sc.seed, frame, 1))
        keep = layout.kept()

        # Unlabelled objects (label: false) keep their ids for the layout's checks, then become
        # background in the labels: class 0, instance 0.
        for o in objects:
            if not o.spec.labelled:
                self.scene.set_instance_labels(o.instance, 0, 0)
        amodal, geometry_lod = amodal_and_levels(self.shapes, view, objects, keep, camera, sc.spec["render"])
        t_layout = time.perf_counter()  # the layout stage: its checks, amodal masks and levels of detail
        view.show(keep)
        render_seed = int(np.random.SeedSequence([sc.seed, int(frame), 3]).generate_state(1, np.uint64)[0])
        if fp is not None and sc.spec["background"]["dome"]:
            photo_info = dict(photo_info or {})
            photo_info["dome"] = self._add_dome(fp, camera, keep, objects, render_seed)
        self.scene.set_camera(camera)
        weather_ctx = self._apply_weather(spec, fp, camera, render_seed)
        self.scene.commit()
        return FrameSetup(frame=frame, spec=spec, fp=fp, photo_info=photo_info, camera=camera, objects=objects,
                          layout=layout, keep=keep, amodal=amodal, render_seed=render_seed, weather_ctx=weather_ctx,
                          t0=t0, t_update=t_update, t_layout=t_layout, geometry_lod=geometry_lod)

    def render(self, frame: int) -> Tuple[Dict[str, np.ndarray], Dict[str, Any], Dict[str, float]]:
        """(arrays, meta, timings) of one frame."""
        f, sc = self.prepare(frame), self.sc
        rs = sc.spec["render"]
        spec, fp, photo_info, camera, objects = f.spec, f.fp, f.photo_info, f.camera, f.objects
        layout, keep, amodal, render_seed, weather_ctx = f.layout, f.keep, f.amodal, f.render_seed, f.weather_ctx
        t_update, t_layout = f.t_update, f.t_layout
        from ..post.quality import exposure_scale

        if rs["denoise"] and fp is not None:  # check_inputs reports it at the YAML key first
            raise SynthgenError("render.denoise is not available with photo backgrounds yet")
        # The scene's exposure: the post steps', the weather's own (night) and the camera's.
        exposure = exposure_scale(spec.post)
        for c in weather_ctx.values():
            exposure *= c.exposure
        cam_exposure, exposure_meta = frame_exposure(self, spec.camera.exposure, fp is not None, weather_ctx, camera,
                                                     render_seed)
        exposure *= cam_exposure
        c_render = time.process_time()
        res = self.scene.render(seed=render_seed, threads=self.threads, exposure=exposure,
                                **{k: rs[k] for k in RENDER_KEYS if k != "threads"})
        sampling = None
        if fp is not None:  # the inserted objects rendered until less noisy than the photo
            from .photo_samples import refine_objects

            res, sampling = refine_objects(self.scene, res, fp, camera, rs, sc.spec["background"]["match"],
                                           exposure=exposure, seed=render_seed, threads=self.threads)
        t_render = time.perf_counter()
        c_render = time.process_time() - c_render  # the path tracer's CPU time (all its threads)

        arrays = {"rgb": np.asarray(res.rgb), "depth": np.asarray(res.depth),
                  "instance_id": np.asarray(res.instance_id), "class_id": np.asarray(res.class_id),
                  "normal": np.asarray(res.normal), "albedo": np.asarray(res.albedo)}
        photo_meta = None
        if fp is None and self.ground is not None and sc.spec["ground"]["backplate"]:
            arrays["rgb"], photo_meta = self._backplate(res, rs, render_seed)
        if fp is not None:
            from ..outputs.coco import mask_bbox
            from .photo import finish_photo_frame, real_object_records

            ids = arrays["instance_id"]
            boxes = [[b[0], b[1], b[0] + b[2], b[1] + b[3]] for k in range(len(objects)) if keep[k]
                     for b in [mask_bbox(ids == k + 1)] if b is not None]
            arrays, photo_meta = finish_photo_frame(fp, res, arrays, sc.spec["background"]["composite"], boxes,
                                                    fp.depth, fp.occluders, camera, sc.spec["background"]["match"],
                                                    frame_rng(sc.seed, frame, 6), sampling=sampling)
            hidden = set(np.unique(ids[(ids > 0) & (arrays["instance_id"] == 0)]).tolist())
            for k in range(len(objects)):
                if keep[k] and objects[k].spec.labelled and (k + 1) in hidden and not (arrays["instance_id"] == k + 1).any():
                    keep[k] = False
                    layout.dropped[k] = "hidden by a real occluder of the photo"
            photo_meta.update(photo_info or {})
        for key, params in spec.weather:  # image-space weather (rain, fog on photos) before the post steps
            arrays = weather.condition(key).post(weather_ctx[key], arrays, params)
        arrays = apply_exposure(arrays, cam_exposure)
        if spec.post:
            arrays = post.apply_steps(arrays, [(p.type, p.params) for p in spec.post])
        meta = {
            "format": "synthgen-dataset-frame", "format_version": 1, "frame": int(frame),
            "scenario_seed": sc.seed, "render_seed": render_seed, "scenario_sha256": sc.sha256,
            "image_size": list(sc.resolution), "camera": camera_meta(camera), "kitti_frame": level_frame(camera),
            "render": dict(rs), "layout_attempts": layout.attempts,
            "lights": [{"type": t, "params": p} for t, p in self.light_specs],
            "objects": object_records(objects, keep, layout.dropped, amodal, arrays["instance_id"], camera,
                                      sc.class_names),
            "sampled": spec.sampled, "class_names": list(sc.class_names), "negative": spec.negative,
            # The render's estimated error against its converged image (from its half-sample
            # images; after the scene's exposure): synthgen.post.quality.
            "noise": self._noise(res, exposure),
            # The camera's exposure (frame.exposure); total: with the weather's and the post steps'.
            "exposure": {**exposure_meta, "total": exposure},
            # The frame's weather (docs/weather.md): {condition: its parameters}, or none.
            "weather": ({key: {**params, **(weather_ctx[key].extra)} for key, params in spec.weather}
                        if spec.weather else None),
            # Conditions drawn with no effect, left out of "weather" (a fog layer below the ground).
            **({"weather_notes": list(spec.weather_notes)} if spec.weather_notes else {}),
            # Which image rgb is: the render's mean ("raw") or the denoiser's output ("denoised").
            "rgb": "denoised" if rs["denoise"] else "raw",
            # Texel memory of the image textures: every level, and as rendered (texture_lod keeps
            # the levels the camera needs: docs/texture_lod.md).
            "texture_memory": {"full_bytes": int(res.stats["texture_bytes_full"]),
                               "resident_bytes": int(res.stats["texture_bytes_resident"])},
            # What this frame shares with others, for the train/val split (outputs.split): its
            # layout is its own (every frame draws a new one).
            "split_keys": [f"layout:{sc.sha256[:16]}:{int(frame)}"],
        }
        if f.geometry_lod is not None:  # levels of detail used, what they saved (docs/geometry_lod.md)
            meta["geometry_lod"] = f.geometry_lod
        # Vehicles' plates: where each plate and each of its characters is in the image.
        for k, rec in enumerate(meta["objects"]):
            if keep[k] and "plates" in rec and objects[k].shape.plates:
                from ..randomize.plates import project_plates

                rec["plates"] = dict(rec["plates"], image=project_plates(
                    rec["plates"], objects[k].shape.plates, objects[k].world, camera, arrays.get("depth")))
                cls = rec["plates"].get("class")
                if cls and rec.get("visible_pixels"):
                    from ..randomize.plates import plate_parts

                    # Plate-only labels: the plates as objects of their own class.
                    meta.setdefault("parts", []).extend(plate_parts(
                        rec["plates"], objects[k].shape.plates, objects[k].world, camera,
                        arrays["depth"], arrays["instance_id"], rec, cls, sc.class_names.index(cls) + 1,
                        np.asarray(meta["kitti_frame"]["level_from_world"])))
            if keep[k] and "lamps" in rec and objects[k].shape.lamps:
                from ..randomize.lamps import project_lamps

                rec["lamps"] = dict(rec["lamps"], image=project_lamps(
                    rec["lamps"], objects[k].shape.lamps, objects[k].world, camera, arrays.get("depth")))
        transmittance = next((c.transmittance for c in weather_ctx.values() if c.transmittance is not None), None)
        if transmittance is None and self.scene.medium_type() is not None:
            transmittance = self.scene.camera_transmittance(np.asarray(res.distance))
        if transmittance is not None:
            weather_labels(meta["objects"], transmittance, arrays["rgb"], arrays["instance_id"])
        if fp is None and photo_meta is not None:
            meta["background"] = photo_meta
        if fp is not None:
            # Frames of one photo share its content: one split for all of them.
            meta["split_keys"].append(f"photo:{fp.photo.sha256}")
            meta["background"] = {**fp.meta(), **photo_meta}
            meta["real_objects"] = real_object_records(fp, arrays["instance_id"], sc.class_names)
        if spec.post:
            meta["post"] = [{"type": p.type, "params": dict(p.params)} for p in spec.post]
        timings = {"update_s": t_update - f.t0, "layout_s": t_layout - t_update, "render_s": t_render - t_layout,
                   "render_cpu_s": c_render}
        if rs["texture_lod"]:
            timings["texture_lod_s"] = float(res.stats["texture_lod_time_s"])
        if fp is not None:  # compositing, camera matching and labels of a photo frame
            timings["photo_s"] = time.perf_counter() - t_render
        return arrays, meta, timings

    def _apply_weather(self, spec: FrameSpec, fp: Any, camera: Any = None, seed: int = 0
                       ) -> Dict[str, "weather.WeatherContext"]:
        """The frame's weather conditions applied to the scene (the previous frame's medium
        removed first, and the conditions' geometry hidden); {condition key: its context} for
        their image-space steps and meta."""
        self._clear_weather()
        out = {}
        for key, params in spec.weather:
            ctx = weather.WeatherContext(self, weather.condition_rng(self.sc.seed, spec.frame, key), fp,
                                         camera=camera, seed=int(seed))
            ctx.extra.update(weather.condition(key).apply(ctx, params) or {})
            out[key] = ctx
        return out

    def _clear_weather(self) -> None:
        """Removes the previous frame's medium and hides its weather geometry (street lights ...),
        so that nothing of it reaches this frame's layout checks: a frame must not depend on what
        its worker rendered before."""
        if self.scene.medium_type() is not None:
            self.scene.clear_medium()
        for pool in self.weather_pools.values():
            for inst in pool.ids:
                if self.scene.instance_visible(inst):
                    self.scene.set_instance_visible(inst, False)

    @staticmethod
    def _noise(res: Any, exposure: float) -> Optional[Dict[str, float]]:
        from ..post.quality import estimate_noise

        count = np.asarray(res.sample_count)
        est = estimate_noise(np.asarray(res.rgb_even), np.asarray(res.rgb_odd), count, float(exposure))
        if est is None:
            return None
        # spp: the mean over the pixels (adaptive sampling gives each pixel its own count).
        return {"psnr_db": round(est["psnr_db"], 3), "relmse": float(f"{est['relmse']:.5g}"),
                "spp": round(float(count.mean()), 3)}

    # -- scene set-up of one frame --------------------------------------------------------
    def _set_lights(self, lights: List[PluginSpec]) -> None:
        self._set_light_plugins([light_plugin(li) for li in lights])

    def replace_lights(self, lights: List[Tuple[str, Dict[str, Any]]]) -> None:
        """Replaces the frame's lights by these (plugin, parameters) (a weather condition's
        time of day); the metadata lists them."""
        self._set_light_plugins(lights)

    def weather_pool(self, key: str) -> Pool:
        """The pool of a weather condition's unlabelled instances (hidden at every frame's start)."""
        return self.weather_pools.setdefault(key, Pool())

    def _set_light_plugins(self, lights: List[Tuple[str, Dict[str, Any]]]) -> None:
        for lid in self.lights:
            self.scene.remove_light(lid)
        self.lights = [self.scene.add_light(t, p) for t, p in lights]
        self.light_specs = list(lights)

    def _set_ground(self, spec: FrameSpec) -> None:
        if self.ground is None:
            return
        if self.ground_material is None:
            self.ground_material = self.scene.add_material("diffuse", {})
        if self.photos is not None:
            from .photo import ground_albedo

            albedo = ground_albedo(self.last_photo, self.sc.spec["background"]["ground_albedo"])
            self.scene.update_material(self.ground_material, "diffuse", {"albedo": albedo})
            self.scene.set_instance_material(self.ground, self.ground_material)
            return
        m = spec.ground.material
        self.scene.update_material(self.ground_material, m.type, realize(self.library, m.params))
        self.scene.set_instance_material(self.ground, self.ground_material)

    def _slot_material(self, k: int, m: PluginSpec) -> int:
        while len(self.slots) <= k:
            self.slots.append(self.scene.add_material("diffuse", {}))
        self.scene.update_material(self.slots[k], m.type, realize(self.library, m.params))
        self._slots_set.add(k)
        return self.slots[k]

    def _set_objects(self, spec: FrameSpec) -> List[PlacedObject]:
        """Shapes, materials (with what the randomizers make of them) and instances of the
        frame's objects; posts for signs and plates; the previous frame's generated textures
        and materials removed."""
        for inst in self.pool.beyond(len(spec.objects)):
            self.scene.set_instance_visible(inst, False)
            self.scene.set_instance_material(inst, -1)
            self._set_material_map(inst, {})
        objects = []
        n_decor = 0
        self._slots_set = set()
        for o in spec.objects:
            placed = self._set_object(spec, o)
            if placed.post_height is not None:
                placed.decor, n_decor = n_decor, n_decor + 1
            objects.append(placed)
        # Material slots not set this frame let go of last frame's textures (before the caller
        # releases them): those of indices no object has, and those of objects that keep their
        # own materials (a library vehicle at an index a textured box had last frame, when an
        # entry's count changes).
        for k, slot in enumerate(self.slots):
            if k not in self._slots_set:
                self.scene.update_material(slot, "diffuse", {})
        pole_mesh = self.shapes.get("primitive", "box").mesh_id
        if self.pole_material is None:
            self.pole_material = self.scene.add_material("conductor", {"metal": "iron", "roughness": 0.5})
        for d in range(n_decor):
            self.decor.take(d, lambda: self.scene.add_instance(pole_mesh, np.eye(4), class_id=0, instance_id=0,
                                                               material_id=self.pole_material))
        for d in self.decor.beyond(n_decor):
            self.scene.set_instance_visible(d, False)
        return objects

    def _set_object(self, spec: FrameSpec, o: ObjectSpec) -> PlacedObject:
        k = o.index
        kind, value = o.shape
        shape = self.shapes.get(kind, value)
        local, radius, dims, post = self._local(o, shape)
        rng = frame_rng(spec.seed, spec.frame, 100 + k)
        # The object's materials: one (a scenario material, grey, or what a sign or plate
        # makes), or -- a model with materials of its own -- one per material of its mesh,
        # which randomizers wrap one by one (keys: the mesh's material ids).
        keys: Optional[Tuple[int, ...]] = None
        mats: List[int] = []
        if kind not in ("primitive", "mesh", "asset"):
            pass  # a shape randomizer makes the material
        elif o.material is not None:
            mats = [self._slot_material(k, o.material)]
        elif not shape.own_materials:
            mats = [self._slot_material(k, PluginSpec("diffuse", {"albedo": [0.5, 0.5, 0.5]}))]
        else:
            keys = shape.material_ids
            mats = [m if m >= 0 else self._default_material() for m in keys]
        model = kind in ("primitive", "mesh", "asset")
        ctx = randomize.ObjectContext(self.library, rng, o, shape.lo, shape.hi,
                                      forward=AXES[(o.forward or shape.forward or "+x") if model else "+x"],
                                      up=AXES[(o.up or shape.up or "+y") if model else "+y"],
                                      plates=shape.plates if model else None,
                                      plate_material=shape.plate_material if model else None,
                                      roles=shape.roles if model else None,
                                      lamps=shape.lamps if model else None,
                                      lamp_material=shape.lamp_material if model else None)
        # Values the frame's weather gives where the scenario gives none (night: lamps on).
        values = dict(o.randomizers)
        for key, params in spec.weather:
            extra = weather.condition(key).object_values(
                params, spec, o, shape, weather.condition_rng(spec.seed, spec.frame, f"{key}:object:{k}"))
            for rk, v in (extra or {}).items():
                if values.get(rk) is None:
                    values[rk] = v
        done = {}
        for r in randomize.randomizers(by="apply_order"):
            value = values.get(r.key)
            if value is not None:
                mats, info = r.apply(ctx, value, mats)
                if info is not None:
                    done[r.key] = info
        mat = mats[0] if keys is None else -1
        material_map = {} if keys is None else {key: m for key, m in zip(keys, mats) if m != key}
        inst, existed = self.pool.take(k, lambda: self.scene.add_instance(
            shape.mesh_id, np.eye(4), class_id=o.class_index + 1, instance_id=k + 1, material_id=mat))
        if existed:
            self.scene.set_instance_mesh(inst, shape.mesh_id)
            self.scene.set_instance_material(inst, mat)
            self.scene.set_instance_labels(inst, o.class_index + 1, k + 1)
        self._set_material_map(inst, material_map)
        info = {r.key: done[r.key] for r in randomize.randomizers() if r.key in done}
        forward = AXES[o.forward or shape.forward or "+x"] if kind in ("primitive", "mesh", "asset") else AXES["+x"]
        return PlacedObject(o, shape, inst, local, radius, dims, post, forward=forward, info=info, material=mat,
                            materials={} if keys is None else dict(zip(keys, mats)))

    def _set_material_map(self, inst: int, material_map: Dict[int, int]) -> None:
        """Per-instance materials of a model that keeps its own (only instances that have or
        had a map are touched)."""
        if material_map or inst in self.mapped:
            self.scene.set_instance_material_map(inst, material_map)
        if material_map:
            self.mapped.add(inst)
        else:
            self.mapped.discard(inst)

    def _default_material(self) -> int:
        """The scene's default grey as a material of its own, for triangles of a model that
        have none (so wear can wrap them too)."""
        if self.default_material is None:
            self.default_material = self.scene.add_material("diffuse", {"albedo": 0.5})
        return self.default_material

    def _local(self, o: ObjectSpec, shape: Shape) -> Tuple[np.ndarray, float, np.ndarray, Optional[float]]:
        """(object_from_shape scale and lift, footprint radius, box size in metres, post
        height of a post or None)."""
        kind, value = o.shape
        if kind not in ("primitive", "mesh", "asset"):
            return randomize.randomizer(kind).placement(value, o.scale)
        # The model turned so that its forward axis is +x and its up axis +y (the frame in which
        # sizes, the footprint and KITTI's dimensions and heading are measured).
        turn = orientation(o.forward or shape.forward or "+x", o.up or shape.up or "+y")
        lo, hi = shape.lo, shape.hi
        if turn is not None:
            a, b = turn @ lo, turn @ hi
            lo, hi = np.minimum(a, b), np.maximum(a, b)
        size = np.asarray(o.size, np.float64) * o.scale
        if shape.own_materials:  # meshes keep their proportions: size is a per-axis scale factor
            dims = (hi - lo) * shape.unit * size  # in metres (manifest `scale`)
        else:
            dims = size.copy()
            if value == "sphere":
                dims = np.full(3, size[0])
        s = dims / np.maximum(hi - lo, 1e-12)
        centre = 0.5 * (lo + hi)
        # Scale about the bounds' centre, then lift so the lowest point touches y = 0.
        m = np.eye(4)
        m[:3, :3] = np.diag(s)
        m[:3, 3] = -centre * s + np.array([0.0, 0.5 * dims[1], 0.0])
        if turn is not None:
            t4 = np.eye(4)
            t4[:3, :3] = turn
            m = m @ t4
        if o.roll or o.pitch:
            return tilted(m, dims, o.roll, o.pitch) + (dims, None)
        return m, 0.5 * math.hypot(dims[0], dims[2]), dims, None
