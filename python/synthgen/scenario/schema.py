"""The scenario format: the plugins' vocabulary with every leaf allowed to be a distribution,
plus what only scenarios have (camera poses, objects and their randomizers, placement,
outputs).

Materials, lights and the camera intrinsics come from the plugins' C++ declarations
(:func:`synthgen.schema.plugins.plugin_record`, scenario form: no texture or material
references); object randomizers (``sign``, ``plate``, ``wear``, ``decals``) from
:mod:`synthgen.randomize`; the output kinds from :mod:`synthgen.outputs`. ``synthgen schema
--scenario`` prints the whole format (:func:`format_scenario_schema`).
"""
from __future__ import annotations

from typing import Any

from .. import outputs, post, randomize
from ..outputs import split
from ..randomize import weather
from ..schema.errors import Loc, ValidationContext, show_value
from ..schema.fields import (EMPTY, REQUIRED, Bool, Choice, Field, FilePath, Integer, ListOf, Number, Record, String,
                             Vector)
from ..schema.plugins import plugin_record, scenario_texture_record, settings_record
from ..scene.assets import AXES
from ..schema.random import R, randomized
from ..schema.reference import format_schema

__all__ = ["SCENARIO_SCHEMA", "BACKGROUND", "MATERIAL", "LIGHT", "CAMERA", "EXPOSURE", "FORMAT_VERSION",
           "exposure_mode", "OBJECT", "PLACEMENT", "RENDER", "RENDER_KEYS", "SHAPE_KEYS", "POST_STEP",
           "format_scenario_schema"]

#: A material: any material plugin but those made of other materials (``mix``).
MATERIAL = randomized(plugin_record("material", scenario=True, doc="a material (synthgen plugin name and "
                                                                   "parameters)"))

LIGHT = randomized(plugin_record("light", scenario=True, doc="a light"))
# An environment map may name an asset of the manifest instead of a file.
LIGHT.variants["envmap"] = LIGHT.variants["envmap"].extend(
    {"asset": R(String(None, doc="asset id (kind hdr) instead of file"))}, one_of=[("file", "asset")])

ORBIT = {"target": R(Vector(3, (0.0, 0.0, 0.0), doc="point looked at")),
         "distance": R(Number(6.0, min=0.0, min_open=True, doc="metres from the target")),
         "elevation": R(Number(20.0, min=-89.0, max=89.0, doc="degrees above the ground")),
         "azimuth": R(Number(0.0, min=-360.0, max=720.0, doc="degrees about +y")),
         "jitter": R(Number(0.0, min=0.0, doc="uniform target jitter in metres (a cube of this half-size)"))}
LOOK_AT = {"eye": R(Vector(3, REQUIRED, doc="camera position in metres (world, y up)")),
           "target": R(Vector(3, (0.0, 0.0, 0.0), doc="point looked at"))}

#: The latest scenario format version (``version``): 2 exposes synthetic frames like a camera's
#: auto-exposure by default; 1 (and a file without ``version``) leaves the image as rendered.
FORMAT_VERSION = 2


def exposure_mode(exposure: Any, version: int) -> str:
    """The mode of a validated ``camera.exposure``: the given one; else fixed where a factor is
    given or in format version 1, auto from version 2."""
    if exposure.get("mode") is not None:
        return str(exposure["mode"])
    if exposure.get("factor") is not None or int(version) < 2:
        return "fixed"
    return "auto"


#: The camera's exposure (synthgen.frame.exposure): the factor the rendered linear image is
#: multiplied by -- metered like a camera's auto-exposure, or fixed. Not on photo backgrounds
#: (the render is matched to the photo's own exposure).
EXPOSURE = Record(
    {"mode": Choice(["auto", "fixed"], None,
                    doc="auto: metered like a camera's auto-exposure (a pre-pass at a quarter of the resolution, "
                        "its centre-weighted log-average luminance mapped to key, highlights protected); fixed: the "
                        "image x factor; default: auto in format version 2, fixed (factor 1: the image as rendered) "
                        "in version 1 or when factor is given"),
     "key": Number(0.18, min=0.001, max=1.0, doc="auto: the log-average luminance the frame is exposed to (0.18 "
                                                 "mid-grey)"),
     "ev": R(Number(0.0, min=-20.0, max=20.0, doc="exposure compensation in stops: the image x 2^ev on top of the "
                                                  "metered (auto) or fixed factor")),
     "factor": R(Number(None, min=0.0, min_open=True, doc="fixed: the image x this (default 1)"))},
    default=EMPTY,
    doc="the camera's exposure of synthetic frames (docs/scenarios.md#exposure); photo backgrounds take the "
        "photo's")

#: The pinhole camera's lens distortion coefficients (OpenCV's order).
DISTORTION_KEYS = ("k1", "k2", "p1", "p2", "k3")

#: The camera plugin's intrinsics and lens distortion (the image size is ``resolution``), a pose and an
#: exposure.
CAMERA = randomized(settings_record("camera", "pinhole", scenario=True,
                                    keys=("fov_y", "fx", "fy", "cx", "cy", *DISTORTION_KEYS),
                                    default=EMPTY, doc="camera")).extend(
    {"pose": Record({"type": Choice(["orbit", "look_at"], "orbit",
                                    doc="orbit: around a target at a distance, elevation and azimuth; look_at: from "
                                        "an eye point")}, tag="type",
                    variants={"orbit": ORBIT, "look_at": LOOK_AT}, default=EMPTY,
                    doc="where the camera is and what it looks at (image y points down, world y up)"),
     "exposure": EXPOSURE})

#: Keys of ``objects[]`` that say what the object is (exactly one is given).
SHAPE_KEYS = ("primitive", "mesh", "asset") + tuple(r.key for r in randomize.randomizers() if r.shape)

OBJECT = Record(
    {"class": String(None, doc="class name (COCO category, YOLO class, KITTI type); required unless label is false"),
     "label": Bool(True, doc="false: an unlabelled object (occluder, clutter): it is rendered and occludes, but has "
                             "no class, id 0 in the masks, no annotation, and no visibility limits unless the entry "
                             "sets them"),
     "name": String(None, doc="label for messages and metadata"),
     "count": R(Integer(1, min=0, max=1000, doc="instances per frame")),
     "primitive": R(Choice(["box", "sphere", "cylinder", "cone"], None,
                           doc="built-in shape, 1 m across before size: box, sphere, cylinder or cone (about y, "
                               "the cone's apex up)")),
     "mesh": FilePath(None, doc="mesh file (OBJ, PLY, glTF, GLB)"),
     "asset": R(String(None, doc="asset id of assets_manifest (kind mesh; `synthgen assets list`)")),
     "size": R(Vector(3, (1.0, 1.0, 1.0), min=0.0, min_open=True, broadcast=True,
                      doc="primitives: extent along x, y, z in metres (a sphere: its diameter, the first value; "
                          "a cylinder or cone: diameter, height, diameter); meshes and assets: per-axis scale of "
                          "the model's own size")),
     "scale": R(Number(1.0, min=0.0, min_open=True, doc="uniform scale of the shape")),
     "yaw": R(Number(0.0, min=-360.0, max=720.0, doc="rotation about +y, degrees")),
     "forward": Choice(list(AXES), None, doc="the model's forward axis (default: the asset's, else +x): KITTI "
                                             "length and heading follow it"),
     "up": Choice(list(AXES), None, doc="the model's up axis (default: the asset's, else +y): turned to the "
                                        "world's up"),
     "material": R(MATERIAL, doc="material; omitted: the mesh's own materials or grey", default=None),
     "roll": R(Number(0.0, min=-180.0, max=180.0, doc="tilt about the object's forward axis, degrees (after which "
                                                      "it rests on its lowest point)")),
     "pitch": R(Number(0.0, min=-180.0, max=180.0, doc="tilt about its lateral axis, degrees (positive: front up)")),
     "region": Vector(4, None, doc="[x_min, z_min, x_max, z_max] where this entry's objects stand (default: "
                                   "placement.region)"),
     "rests_on": String(None, doc="the name (or class) of another entry whose objects this entry's objects rest on: "
                                  "on the top of one of them, chosen at random (stacks, things on tables or roofs)"),
     "pixel_height": R(Number(None, min=1.0, doc="height of the object's box in the image, pixels (a distribution "
                                                 "covers detector scales): it stands at the distance that gives it, "
                                                 "instead of in a region")),
     "min_pixels": Integer(None, min=0, doc="visible pixels of each instance (default: placement.min_pixels)"),
     "min_visible_fraction": Number(None, min=0.0, max=1.0,
                                    doc="visible / amodal pixels of each instance (default: placement's)"),
     "max_visible_fraction": Number(None, min=0.0, max=1.0,
                                    doc="at most this visible (default: placement's; < 1 asks for occluded or "
                                        "truncated instances)"),
     **{r.key: r.schema for r in randomize.randomizers()}},
    one_of=[SHAPE_KEYS], doc="an object kind placed on the ground")

PLACEMENT = Record(
    {"region": Vector(4, (-3.0, -3.0, 3.0, 3.0), doc="[x_min, z_min, x_max, z_max] on the ground, metres"),
     "non_overlapping": Bool(True, doc="footprint circles may not overlap"),
     "margin": Number(0.05, min=0.0, doc="extra clearance between footprints, metres"),
     "min_visible_fraction": Number(0.0, min=0.0, max=1.0, doc="visible / amodal pixels of every object"),
     "max_visible_fraction": Number(1.0, min=0.0, max=1.0,
                                    doc="at most this visible (e.g. < 1 to ask for occluded or truncated objects)"),
     "min_pixels": Integer(1, min=0, doc="visible pixels of every object"),
     "max_retries": Integer(20, min=0, max=10000, doc="layouts tried before objects are dropped"),
     "allow_drops": Bool(False, doc="objects that find no place after the retries are left out of their frame as "
                                    "expected (a crowded photo), still listed in the metadata and the run summary, "
                                    "without exit status 3")},
    default=EMPTY, doc="placement on the ground plane (y = 0)")

class _PhotoEntry(Field):
    """A photo entry: a path / glob / folder, or {file | asset, calibration}."""

    type_name = "path, glob or folder, or {file | asset, calibration}"
    RECORD = Record({"file": String(None, doc="photo file, glob or folder"),
                     "asset": String(None, doc="asset id (kind photo) of assets_manifest"),
                     "calibration": FilePath(None, doc="this photo's calibration file")},
                    one_of=[("file", "asset")])

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if isinstance(value, str):
            return String().validate(value, loc, ctx)
        if isinstance(value, dict):
            return self.RECORD.validate(value, loc, ctx)
        ctx.error(loc, f"expected a {self.type_name}, got {show_value(value)}")

    def describe(self) -> str:
        return self.type_name


#: Real photos as backgrounds (synthgen.background; docs/augmented_photos.md).
BACKGROUND = Record(
    {"photos": ListOf(_PhotoEntry(), REQUIRED, min_items=1,
                      doc="photo files, globs (`photos/*.jpg`) or folders, relative to the scenario, or {file | asset, "
                          "calibration} entries; each photo has a calibration: the entry's, PHOTO.yaml beside it, a "
                          "calibration.yaml for its folder, or `calibration`"),
     "calibration": FilePath(None, doc="a calibration file for every photo (sidecars override its keys)"),
     "unlabelled_ok": Bool(False, doc="accept photos that declare no real labels (labels or objects in their "
                                      "calibration): a car in the photo left unlabelled teaches a detector that cars "
                                      "are background"),
     "composite": Choice(["ratio", "additive"], "ratio",
                         doc="ratio: photo x (render with objects / without) where the ground catches shadows "
                             "(Cycles' shadow catcher; the ground's albedo cancels); additive: photo + (with - "
                             "without) (Debevec 1998)"),
     "zoom": R(Number(1.0, min=1.0, max=8.0, doc="the photo scaled to cover the image, then by this much more; "
                                                 "the frame is a random crop of it")),
     "max_uses": Integer(None, min=1, doc="frames per photo at most (photos are used in turn, each once per round)"),
     "min_distance": Number(3.0, min=0.0, doc="objects stand at least this far from the camera, metres"),
     "max_distance": Number(40.0, min=0.0, min_open=True, doc="and at most this far"),
     "max_real_overlap": Number(0.5, min=0.0, max=1.0,
                                doc="an inserted object and a real object (or an ignore region) may overlap by at most "
                                    "this fraction of the farther one's box (the one hidden); none may stand behind "
                                    "a real object known only by its box (its rectangle would cut it)"),
     "dome": Bool(True, doc="the photo projected onto a distant dome is what the objects reflect (envmap "
                             "reflection_only: seen by glossy and specular bounces only, in the render's units by a "
                             "low-resolution pre-pass's exposure)"),
     "match": Record({"denoise": Bool(True, doc="filter the objects' Monte Carlo noise first (joint bilateral "
                                                 "guided by their albedo and normals)"),
                      "noise": Bool(True, doc="the photo's noise (sigma^2 = a y + b, fitted in sRGB) on what the "
                                               "objects changed"),
                      "blur": Bool(True, doc="blur the objects to the photo's sharpness"),
                      "jpeg": Bool(True, doc="re-encode the frame at the photo's estimated JPEG quality (JPEG "
                                             "photos)"),
                      "vignetting": Number(0.0, min=0.0, max=1.0, doc="cos^4 falloff on the objects (0: none, 1: a "
                                                                      "thin lens's)"),
                      "chromatic_aberration": Number(0.0, min=-5.0, max=5.0,
                                                     doc="lateral colour fringes on the objects: red/blue displaced "
                                                         "by this many pixels at the image corner"),
                      "render_noise": Number(0.5, min=0.0, max=1.0,
                                             doc="render the objects again (a crop around each, adaptive sampling) "
                                                 "until their noise is below this fraction of the photo's at their "
                                                 "level, before the photo's noise is added (0: off)"),
                      "max_spp": Integer(0, min=0, doc="the objects' sample cap for render_noise (0: 4 x "
                                                       "render.spp); objects stopped by it short of the target "
                                                       "are reported")},
                     default=EMPTY, doc="camera matching: what the photo's camera did, applied to the objects"),
     "ground_albedo": Vector(3, None, min=0.0, max=1.0, broadcast=True,
                             doc="albedo of the ground that catches shadows (default: 0.15 with the photo's ground "
                                 "colour; ratio compositing cancels it to first order)")},
    default=None, doc="insert the objects into real photos: the photo's camera, ground, sun and real labels")

#: The render settings a scenario sets (the seed of each frame derives from the scenario's).
RENDER_KEYS = ("spp", "max_depth", "rr_depth", "threads", "clamp_indirect", "noise_threshold", "target_psnr",
               "min_spp", "max_spp", "denoise", "max_medium_depth", "texture_lod", "texture_lod_margin",
               "texture_budget_mib")
RENDER = settings_record("render", "path_tracer", keys=RENDER_KEYS, default=EMPTY,
                         doc="path tracing settings (threads: per worker; 0 = all cores / workers)")
# Host policy, not the path tracer's: which level of detail each library model uses.
RENDER.fields["geometry_lod"] = Number(
    0.5, min=0.0, max=8.0,
    doc="library models whose entry lists levels of detail (lods) use, per frame, the coarsest whose geometric "
        "error projects under this many pixels (0: always the finest; docs/geometry_lod.md)")
RENDER.fields["geometry_lod_iou"] = Number(
    0.98, min=0.0, max=1.0,
    doc="and, for a labelled object, whose amodal mask (the object rendered alone) keeps at least this IoU with "
        "the finest level's")


#: A post-processing step: ``{type: NAME, ...its parameters}`` (:mod:`synthgen.post`).
POST_STEP = Record({"type": Choice([s.name for s in post.steps()], doc="post-processing step")}, tag="type",
                   variants={s.name: randomized(s.schema) for s in post.steps()}, doc="a post-processing step")


#: Weather (docs/weather.md): the conditions of synthgen.randomize.weather, one key each.
WEATHER = weather.schema()


class _Resolution(Field):
    type_name = "[width, height] in pixels (each 1..16384)"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            ctx.error(loc, f"expected {self.type_name}, got {show_value(value)}")
        el = Integer(min=1, max=16384)
        return tuple(el.validate(v, loc.index(i, value), ctx) for i, v in enumerate(value))


SCENARIO_SCHEMA = Record(
    {"version": Integer(1, min=1, max=FORMAT_VERSION,
                        doc="format version: 2 exposes synthetic frames like a camera's auto-exposure by default "
                            "(camera.exposure); 1 (or none) renders them as before, the image as rendered"),
     "description": String("", doc="free text"),
     "seed": Integer(0, min=0, max=(1 << 63) - 1, doc="scenario seed"),
     "count": Integer(10, min=1, max=10 ** 9, doc="number of frames"),
     "allow_extensions": Bool(False, doc="this scenario may compile and run the C files under 'extensions' (with "
                                         "--allow-extensions on the command line too: extensions run with your "
                                         "rights)"),
     "extensions": ListOf(FilePath(doc="a C file"), [], doc="user extensions (C files, synthgen_ext.h) whose "
                                                            "textures the materials use; docs/extensions.md"),
     "resolution": _Resolution((640, 480), doc="image size"),
     "camera": CAMERA,
     "lights": R(ListOf(LIGHT, REQUIRED, min_items=1), doc="lights, or a choice of light set-ups",
                 default=[{"type": "sky", "strength": 0.02}]),
     "ground": Record({"size": Number(None, min=0.0, min_open=True,
                                      doc="edge length in metres of a square ground (default: the ground reaches "
                                          "the horizon)"),
                       "enabled": Bool(True, doc="false: no ground (objects float in the sky)"),
                       "backplate": Bool(False, doc="the ground catches the objects' shadows over the environment "
                                                    "map's own image (an envmap light needed): the HDR's ground and "
                                                    "horizon are the background, no plane with an edge; the "
                                                    "material's albedo only guides the shadows (ratio compositing)"),
                       "material": R(MATERIAL, default={"type": "diffuse", "albedo": [0.3, 0.3, 0.3]})},
                      default=EMPTY, doc="ground plane y = 0 (class 0, unlabelled)"),
     "objects": ListOf(OBJECT, REQUIRED, min_items=1, doc="object kinds"),
     "placement": PLACEMENT,
     "weather": WEATHER,
     "render": RENDER,
     "outputs": ListOf(Choice(outputs.kind_names()), outputs.default_outputs(), doc="what to write"),
     "split": split.SCHEMA,
     "negative_frames": Number(0.0, min=0.0, max=1.0,
                               doc="fraction of frames without labelled objects (negatives for detectors; unlabelled "
                                   "entries stay)"),
     "post": ListOf(POST_STEP, [], doc="image-space steps applied to each frame's image, in order"),
     "background": BACKGROUND},
    doc="a scenario")


def format_scenario_schema() -> str:
    """The scenario reference: every key of a scenario, then the inline texture form that
    texture parameters take (``{texture: {type: NAME, ...}}``)."""
    return (format_schema(SCENARIO_SCHEMA) + "\n\n# An inline texture, {texture: <this>}, wherever a parameter "
            "takes a texture:\n" + format_schema(scenario_texture_record()))
