"""Scenario files: randomized scenes -> datasets. Validation and per-frame sampling.

A scenario is a YAML mapping (``scenarios/default.yaml`` is a complete example)::

    version: 1
    seed: 7                       # frame k's randomness derives only from (seed, k)
    count: 100                    # frames (``synthgen run -n`` overrides)
    resolution: [640, 480]
    camera:
      fov_y: {uniform: [40, 55]}  # degrees; or intrinsics fx, fy (cx, cy: image centre)
      pose: {type: orbit, target: [0, 0.4, 0], distance: {uniform: [5, 8]},
             elevation: {uniform: [10, 35]}, azimuth: {uniform: [0, 360]}, jitter: 0.2}
    lights:                       # a list, or {choice: [list, list, ...]} of light set-ups
      - {type: sky, elevation: {uniform: [15, 70]}, azimuth: {uniform: [0, 360]}, turbidity: 3}
    ground: {size: 40, material: {type: diffuse, albedo: [0.3, 0.3, 0.3]}}
    objects:
      - class: box                # class name: COCO category / YOLO index / KITTI type
        count: {int: [1, 3]}
        primitive: box            # box | sphere, or mesh: {file: ...} / asset: ID
        size: {uniform: [[0.3, 0.3, 0.3], [1, 1, 1]]}
        yaw: {uniform: [0, 360]}
        material: {type: coated, albedo: {hsv: {color: [0.6, 0.1, 0.1], h: 0.5, s: 0.3, v: 0.3}}}
    placement: {region: [-3, -3, 3, 3], non_overlapping: true, min_visible_fraction: 0.1,
                min_pixels: 50, max_retries: 20}
    render: {spp: 32, max_depth: 6}
    outputs: [rgb, depth, instance, semantic, coco, yolo, kitti]

Every scalar, vector, colour or choice may be a distribution (see
:mod:`synthgen.distributions`). Validation (:func:`load_scenario`) happens before anything
renders; errors read ``FILE:LINE:COLUMN: key.path: reason`` with close spellings and allowed
ranges. :func:`sample_frame` draws one frame's parameters from a generator seeded by
(scenario seed, frame index) only.
"""
from __future__ import annotations

import copy
import hashlib
import json
import os
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from . import distributions as D
from .scene_file import (EMPTY, REQUIRED, Bool, Choice, Field, FilePath, Integer, ListOf, Loc, Number, Record,
                         SceneFileError, String, ValidationContext, Validated, Vector, _show, _suggest, parse_yaml)

__all__ = ["SCENARIO_SCHEMA", "OUTPUT_KINDS", "DEFAULT_OUTPUTS", "Scenario", "load_scenario", "parse_scenario",
           "sample_frame", "frame_rng", "Random"]

#: Output kinds of ``outputs:``.
OUTPUT_KINDS = ("rgb", "rgb_exr", "depth", "depth16", "instance", "semantic", "coco", "yolo", "kitti")
DEFAULT_OUTPUTS = ("rgb", "depth", "instance", "semantic", "coco", "yolo", "kitti")


# ---------------------------------------------------------------------------------------
# Random fields


class Random(Field):
    """A value of field ``inner`` or a distribution over such values (bounds and options
    validated by ``inner``)."""

    _INNER = object()

    def __init__(self, inner: Field, doc: str = "", default: Any = _INNER):
        super().__init__(inner.default if default is Random._INNER else default, doc or inner.doc)
        self.inner = inner
        self._own_default = default is not Random._INNER

    @property
    def type_name(self) -> str:  # type: ignore[override]
        return self.inner.describe() + " (or a distribution)"

    def describe(self) -> str:
        return self.type_name

    def missing(self, loc: Loc, ctx: ValidationContext) -> Any:
        if self._own_default:
            return self.validate(copy.deepcopy(self.default), loc, ctx) if self.default is not None else None
        return self.inner.missing(loc, ctx)

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if isinstance(value, dict) and any(k in D.DIST_KEYS for k in value):
            return self._distribution(value, loc, ctx)
        if isinstance(value, dict) and not isinstance(self.inner, (Record, Random)):
            keys = [k for k in value if isinstance(k, str)]
            hint = _suggest(keys[0], D.DIST_KEYS) if keys else ""
            ctx.error(loc, f"expected a {self.inner.describe()} or a distribution, got a mapping with key(s) "
                           f"{', '.join(map(str, value))}{hint}; distributions: {', '.join(D.DIST_KEYS)}")
        return self.inner.validate(value, loc, ctx)

    def _pair(self, args: Any, loc: Loc, ctx: ValidationContext, kind: str) -> Tuple[Any, Any]:
        if not isinstance(args, (list, tuple)) or len(args) != 2:
            ctx.error(loc, f"{kind} needs a list of two values [low, high], got {_show(args)}")
        return (self.inner.validate(args[0], loc.index(0, args), ctx),
                self.inner.validate(args[1], loc.index(1, args), ctx))

    def _distribution(self, value: dict, loc: Loc, ctx: ValidationContext) -> D.Distribution:
        kinds = [k for k in value if k in D.DIST_KEYS]
        if len(kinds) > 1:
            ctx.error(loc.key(kinds[1], value), f"one distribution per value: '{kinds[0]}' and '{kinds[1]}' given")
        kind = kinds[0]
        allowed = (kind,) + D.DIST_EXTRA_KEYS.get(kind, ())
        for k in value:
            if k not in allowed:
                ctx.error(loc.key(k, value), f"unknown key '{k}' in a {kind} distribution{_suggest(k, allowed)}; "
                                             f"allowed keys: {', '.join(allowed)}")
        args = value[kind]
        aloc = loc.value(kind, value)
        inner = self.inner
        scalar = isinstance(inner, Number)
        if kind == "uniform":
            if isinstance(inner, Integer):
                ctx.error(aloc, "integer values take {int: [low, high]}, not uniform")
            if not (scalar or isinstance(inner, Vector)):
                ctx.error(aloc, f"uniform needs numbers or vectors; this key takes a {inner.describe()}")
            lo, hi = self._pair(args, aloc, ctx, kind)
            if np.any(np.asarray(lo) > np.asarray(hi)):
                ctx.error(aloc, f"uniform bounds must satisfy low <= high, got {list(np.atleast_1d(lo))} > "
                                f"{list(np.atleast_1d(hi))}")
            return D.Uniform(lo, hi)
        if kind == "loguniform":
            if not scalar or isinstance(inner, Integer):
                ctx.error(aloc, f"loguniform needs a real number; this key takes a {inner.describe()}")
            lo, hi = self._pair(args, aloc, ctx, kind)
            if not (0.0 < lo <= hi):
                ctx.error(aloc, f"loguniform bounds must satisfy 0 < low <= high, got [{lo}, {hi}]")
            return D.LogUniform(lo, hi)
        if kind == "int":
            if not isinstance(inner, Integer):
                ctx.error(aloc, f"int needs an integer value; this key takes a {inner.describe()}")
            lo, hi = self._pair(args, aloc, ctx, kind)
            if lo > hi:
                ctx.error(aloc, f"int bounds must satisfy low <= high, got [{lo}, {hi}]")
            return D.IntUniform(lo, hi)
        if kind == "normal":
            if not scalar or isinstance(inner, Integer):
                ctx.error(aloc, f"normal needs a real number; this key takes a {inner.describe()}")
            if not isinstance(args, (list, tuple)) or len(args) != 2:
                ctx.error(aloc, f"normal needs [mean, std], got {_show(args)}")
            mean = inner.validate(args[0], aloc.index(0, args), ctx)
            std = Number(min=0.0, min_open=True).check(args[1], aloc.index(1, args), ctx)
            lo = inner.validate(value["min"], loc.value("min", value), ctx) if "min" in value else inner.min
            hi = inner.validate(value["max"], loc.value("max", value), ctx) if "max" in value else inner.max
            d = D.Normal(mean, std, lo, hi)
            if lo is not None and hi is not None and lo > hi:
                ctx.error(loc, f"normal truncation must satisfy min <= max, got [{lo}, {hi}]")
            if d.acceptance() < 1e-3:
                ctx.error(loc, f"normal {d.spec()} puts only {d.acceptance():.1e} of its mass inside "
                               f"[{lo}, {hi}] (allowed: {inner.describe()})")
            return d
        if kind == "choice":
            if not isinstance(args, (list, tuple)) or not args:
                ctx.error(aloc, f"choice needs a non-empty list of options, got {_show(args)}")
            options = [self.validate(v, aloc.index(i, args), ctx) for i, v in enumerate(args)]
            weights = None
            if "weights" in value:
                w = value["weights"]
                wloc = loc.value("weights", value)
                if not isinstance(w, (list, tuple)) or len(w) != len(options):
                    ctx.error(wloc, f"weights must be a list of {len(options)} numbers (one per option)")
                weights = [Number(min=0.0).check(x, wloc.index(i, w), ctx) for i, x in enumerate(w)]
                if sum(weights) <= 0.0:
                    ctx.error(wloc, "weights must not all be 0")
            return D.Choice(options, weights, raw=list(args))
        if kind == "hsv":
            if not (isinstance(inner, Vector) and inner.size == 3):
                ctx.error(aloc, f"hsv jitter needs a colour; this key takes a {inner.describe()}")
            spec = Record({"color": Vector(3, REQUIRED, min=0.0, max=1.0, broadcast=True, doc="base colour"),
                           "h": Number(0.0, min=0.0, max=0.5, doc="hue jitter, fraction of the hue circle"),
                           "s": Number(0.0, min=0.0, max=1.0), "v": Number(0.0, min=0.0, max=1.0)})
            r = spec.validate(args, aloc, ctx)
            inner.validate(list(r["color"]), aloc, ctx)  # the base colour within the slot's range
            return D.HsvJitter(r["color"], r["h"], r["s"], r["v"])
        raise AssertionError(kind)


def R(inner: Field, doc: str = "", **kw: Any) -> Random:
    return Random(inner, doc, **kw)


def _color(default: Any, doc: str = "", hi: float = 1.0) -> Random:
    return R(Vector(3, default, min=0.0, max=hi, broadcast=True, doc=doc))


# ---------------------------------------------------------------------------------------
# Schema

_ROUGH = lambda d=0.3: R(Number(d, min=0.0, max=1.0, doc="GGX roughness (alpha = roughness^2)"))  # noqa: E731

MATERIAL = Record(
    {"type": Choice(["diffuse", "coated", "conductor", "dielectric", "principled", "emissive"], REQUIRED,
                    doc="material plugin")},
    tag="type",
    variants={
        "diffuse": {"albedo": _color((0.5, 0.5, 0.5), "reflectance")},
        "coated": {"albedo": _color((0.5, 0.5, 0.5), "base reflectance"),
                   "ior": R(Number(1.5, min=1.0, max=3.0)), "roughness": _ROUGH(0.05)},
        "conductor": {"metal": R(Choice(["aluminium", "chrome", "copper", "gold", "iron", "silver"], "aluminium")),
                      "roughness": _ROUGH(0.2)},
        "dielectric": {"ior": R(Number(1.5, min=1.0, max=3.0)), "roughness": _ROUGH(0.0),
                       "thin": Bool(False, doc="thin sheet (windows)")},
        "principled": {"base_color": _color((0.8, 0.8, 0.8)), "metallic": R(Number(0.0, min=0.0, max=1.0)),
                       "roughness": _ROUGH(0.5), "specular": R(Number(0.5, min=0.0, max=1.0)),
                       "clearcoat": R(Number(0.0, min=0.0, max=1.0))},
        "emissive": {"radiance": _color((1.0, 1.0, 1.0), "W/(m^2 sr)", hi=1e6)},
    },
    doc="a material (synthgen plugin name and parameters)")

LIGHT = Record(
    {"type": Choice(["sky", "envmap", "sun", "environment"], REQUIRED, doc="light type")},
    tag="type",
    variants={
        "sky": {"elevation": R(Number(45.0, min=-10.0, max=90.0, doc="sun elevation, degrees")),
                "azimuth": R(Number(0.0, min=-360.0, max=720.0, doc="sun azimuth, degrees")),
                "turbidity": R(Number(3.0, min=1.7, max=10.0)),
                "strength": R(Number(0.02, min=0.0, max=1e6, doc="radiance scale; the Preetham model is in "
                                                                 "physical units, 0.02 maps a clear day to display range"))},
        "envmap": {"file": FilePath(None, doc="equirectangular HDR/EXR image"),
                   "asset": R(String(None, doc="asset id (kind hdr) instead of file")),
                   "rotation": R(Number(0.0, min=-360.0, max=720.0, doc="degrees about +y")),
                   "strength": R(Number(1.0, min=0.0, max=1e6)), "visible": Bool(True)},
        "sun": {"elevation": R(Number(45.0, min=-10.0, max=90.0)), "azimuth": R(Number(0.0, min=-360.0, max=720.0)),
                "irradiance": _color((3.0, 3.0, 3.0), "W/m^2", hi=1e6),
                "angular_diameter": R(Number(0.53, min=0.0, max=20.0))},
        "environment": {"radiance": _color((0.5, 0.5, 0.5), "W/(m^2 sr)", hi=1e6)},
    },
    doc="a light")

ORBIT = {"target": R(Vector(3, (0.0, 0.0, 0.0), doc="point looked at")),
         "distance": R(Number(6.0, min=0.0, min_open=True, doc="metres from the target")),
         "elevation": R(Number(20.0, min=-89.0, max=89.0, doc="degrees above the ground")),
         "azimuth": R(Number(0.0, min=-360.0, max=720.0, doc="degrees about +y")),
         "jitter": R(Number(0.0, min=0.0, doc="uniform target jitter in metres (a cube of this half-size)"))}
LOOK_AT = {"eye": R(Vector(3, REQUIRED)), "target": R(Vector(3, (0.0, 0.0, 0.0)))}

CAMERA = Record(
    {"fov_y": R(Number(45.0, min=1.0, max=170.0, doc="vertical field of view, degrees")),
     "fx": R(Number(None, min=1.0, doc="focal length in pixels (instead of fov_y)")),
     "fy": R(Number(None, min=1.0)), "cx": R(Number(None)), "cy": R(Number(None)),
     "pose": Record({"type": Choice(["orbit", "look_at"], "orbit")}, tag="type",
                    variants={"orbit": ORBIT, "look_at": LOOK_AT}, default=EMPTY)},
    exclusive=[("fov_y",), ("fx", "fy")], requires={"fy": ("fx",)}, default=EMPTY, doc="camera")

def _wear_effect(params: Dict[str, Field]) -> Record:
    return Record(dict({"probability": Number(1.0, min=0.0, max=1.0, doc="chance that an instance gets the effect"),
                        "amount": R(Number(0.35, min=0.0, max=1.0, doc="covered fraction")),
                        "seed": R(Integer(None, min=0, max=(1 << 31) - 1, doc="pattern seed (default: drawn)"))},
                       **params), default=None)


_RAMP_STOP = Record({"position": Number(REQUIRED, min=0.0, max=1.0, doc="position in the ramp"),
                     "color": _color(REQUIRED, "linear RGB at that position")})

WEAR = Record({
    "rust": _wear_effect({"scale": R(Number(3.0, min=0.001, max=1000.0)), "bottom_bias": R(Number(0.6, min=0.0, max=2.0)),
                          "roughness": R(Number(0.85, min=0.0, max=1.0)), "bump": R(Number(0.002, min=0.0, max=0.05)),
                          "colors": ListOf(_RAMP_STOP, None, min_items=1,
                                           doc="colour ramp of the rust (default: dark brown to orange)")}),
    "dirt": _wear_effect({"scale": R(Number(5.0, min=0.001, max=1000.0)), "bottom_bias": R(Number(1.0, min=0.0, max=4.0)),
                          "ao_radius": R(Number(0.3, min=0.0001, max=100.0, doc="crease search distance, metres")),
                          "ao_weight": R(Number(1.0, min=0.0, max=4.0, doc="dirt in creases (ambient occlusion)")),
                          "color": _color((0.12, 0.09, 0.06), "dirt colour (linear RGB)"),
                          "roughness": R(Number(0.95, min=0.0, max=1.0))}),
    "scratches": _wear_effect({"density": R(Number(8.0, min=0.001, max=10000.0)),
                               "width": R(Number(0.04, min=0.0001, max=1.0)),
                               "direction": R(Choice(["x", "y", "z"], None, doc="object axis the scratches run along "
                                                                                 "(default: random directions)")),
                               "elongation": R(Number(8.0, min=1.0, max=100.0, doc="cell stretch along direction")),
                               "metal": R(Choice(["aluminium", "chrome", "copper", "gold", "iron", "silver"],
                                                 "aluminium")),
                               "roughness": R(Number(0.35, min=0.0, max=1.0)),
                               "depth": R(Number(0.0, min=0.0, max=0.01, doc="groove depth in metres (tilts the "
                                                                             "metal's normal; 0: flat)"))}),
    "ice": _wear_effect({"scale": R(Number(4.0, min=0.001, max=1000.0)), "top_bias": R(Number(0.5, min=0.0, max=2.0)),
                         "bump": R(Number(0.003, min=0.0, max=0.05))}),
}, default=None, doc="wear effects (synthgen.wear presets), applied in the order rust, dirt, scratches, ice")

SIGN = Record({
    "family": R(Choice(["prohibitory", "warning", "stop", "give_way", "information"], REQUIRED)),
    "text": R(String(None, doc="number of a prohibitory sign, symbol of a warning / information sign")),
    "size": R(Number(0.7, min=0.05, max=5.0, doc="sign width in metres")),
    "mount_height": R(Number(1.5, min=0.0, max=10.0, doc="height of the sign's lower edge; a pole below it")),
}, default=None, doc="a road sign: a generated pictogram (alpha cut-out) on a pole")

PLATE = Record({
    "country": R(Choice(["ru", "de"], REQUIRED)),
    "mount_height": R(Number(0.6, min=0.0, max=10.0, doc="height of the plate's lower edge; a post below it")),
}, default=None, doc="a licence plate with a random valid registration (its text goes into the metadata)")

DECAL = Record({
    "image": FilePath(None, doc="an image file (PNG with alpha, JPEG, EXR)"),
    "pictogram": Record({"family": R(Choice(["prohibitory", "warning", "stop", "give_way", "information"], REQUIRED)),
                         "text": R(String(None))}, default=None, doc="a generated sign pictogram"),
    "plate": Record({"country": R(Choice(["ru", "de"], REQUIRED))}, default=None, doc="a generated licence plate"),
    "probability": Number(1.0, min=0.0, max=1.0, doc="chance that an instance gets the decal"),
    "size": R(Number(0.4, min=0.01, max=1.0, doc="decal width as a fraction of the object's width")),
    "height": R(Number(0.5, min=0.0, max=1.0, doc="decal centre height, fraction of the object's height")),
}, one_of=[("image", "pictogram", "plate")], doc="an image projected onto the object's front (-z side)")

OBJECT = Record(
    {"class": String(REQUIRED, doc="class name (COCO category, YOLO class, KITTI type)"),
     "name": String(None, doc="label for messages and metadata"),
     "count": R(Integer(1, min=0, max=1000, doc="instances per frame")),
     "primitive": R(Choice(["box", "sphere"], None, doc="built-in shape")),
     "mesh": FilePath(None, doc="mesh file (OBJ, PLY, glTF, GLB)"),
     "asset": R(String(None, doc="asset id of assets_manifest (kind mesh; `synthgen assets list`)")),
     "size": R(Vector(3, (1.0, 1.0, 1.0), min=0.0, min_open=True, broadcast=True,
                      doc="box size or sphere diameter, metres")),
     "scale": R(Number(1.0, min=0.0, min_open=True, doc="uniform scale of the shape")),
     "yaw": R(Number(0.0, min=-360.0, max=720.0, doc="rotation about +y, degrees")),
     "material": R(MATERIAL, doc="material; omitted: the mesh's own materials or grey", default=None),
     "sign": SIGN,
     "plate": PLATE,
     "wear": WEAR,
     "decals": ListOf(DECAL, [], doc="decals projected onto the front, before wear")},
    one_of=[("primitive", "mesh", "asset", "sign", "plate")], doc="an object kind placed on the ground")

PLACEMENT = Record(
    {"region": Vector(4, (-3.0, -3.0, 3.0, 3.0), doc="[x_min, z_min, x_max, z_max] on the ground, metres"),
     "non_overlapping": Bool(True, doc="footprint circles may not overlap"),
     "margin": Number(0.05, min=0.0, doc="extra clearance between footprints, metres"),
     "min_visible_fraction": Number(0.0, min=0.0, max=1.0, doc="visible / amodal pixels of every object"),
     "max_visible_fraction": Number(1.0, min=0.0, max=1.0,
                                    doc="at most this visible (e.g. < 1 to ask for occluded or truncated objects)"),
     "min_pixels": Integer(1, min=0, doc="visible pixels of every object"),
     "max_retries": Integer(20, min=0, max=10000, doc="layouts tried before objects are dropped")},
    default=EMPTY, doc="placement on the ground plane (y = 0)")

RENDER = Record(
    {"spp": Integer(32, min=1, max=1 << 20), "max_depth": Integer(6, min=1, max=1024),
     "rr_depth": Integer(5, min=0, max=1024), "threads": Integer(0, min=0, max=4096,
                                                                 doc="per worker; 0 = all cores / workers")},
    default=EMPTY, doc="path tracing settings")


class _Resolution(Field):
    type_name = "[width, height] in pixels (each 1..16384)"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            ctx.error(loc, f"expected {self.type_name}, got {_show(value)}")
        el = Integer(min=1, max=16384)
        return tuple(el.validate(v, loc.index(i, value), ctx) for i, v in enumerate(value))


SCENARIO_SCHEMA = Record(
    {"version": Integer(1, min=1, max=1, doc="format version"),
     "description": String("", doc="free text"),
     "seed": Integer(0, min=0, max=(1 << 63) - 1, doc="scenario seed"),
     "count": Integer(10, min=1, max=10 ** 9, doc="number of frames"),
     "resolution": _Resolution((640, 480), doc="image size"),
     "camera": CAMERA,
     "lights": R(ListOf(LIGHT, REQUIRED, min_items=1), doc="lights, or a choice of light set-ups",
                 default=[{"type": "sky"}]),
     "ground": Record({"size": Number(40.0, min=0.0, min_open=True), "enabled": Bool(True),
                       "material": R(MATERIAL, default={"type": "diffuse", "albedo": [0.3, 0.3, 0.3]})},
                      default=EMPTY, doc="ground plane y = 0 (class 0, unlabelled)"),
     "objects": ListOf(OBJECT, REQUIRED, min_items=1, doc="object kinds"),
     "placement": PLACEMENT,
     "render": RENDER,
     "outputs": ListOf(Choice(list(OUTPUT_KINDS)), list(DEFAULT_OUTPUTS), doc="what to write")},
    doc="a scenario")


# ---------------------------------------------------------------------------------------
# Loading


class Scenario:
    """A validated scenario: ``spec`` (validated tree with distributions), ``source``,
    ``base_dir``, ``class_names`` (category order: COCO id = index + 1), ``text_sha256``."""

    def __init__(self, spec: Validated, source: str, base_dir: str, text: str):
        self.spec = spec
        self.source = source
        self.base_dir = base_dir
        self.text = text
        self.sha256 = hashlib.sha256(text.encode()).hexdigest()
        names: List[str] = []
        for o in spec["objects"]:
            if o["class"] not in names:
                names.append(o["class"])
        self.class_names = names

    @property
    def seed(self) -> int:
        return int(self.spec["seed"])

    @property
    def count(self) -> int:
        return int(self.spec["count"])

    @property
    def resolution(self) -> Tuple[int, int]:
        return tuple(self.spec["resolution"])  # type: ignore[return-value]


def _check_assets(tree: Any, loc: Loc, ctx: ValidationContext, kind: str) -> None:
    """Every asset id (constant or among choice options) exists in the manifest with `kind`."""
    from . import assets

    values = tree.options if isinstance(tree, D.Choice) else [tree]
    manifest = assets.load_manifest()
    for v in values:
        if v is None:
            continue
        if isinstance(v, D.Distribution):
            ctx.error(loc, "asset ids take a constant or a choice")
        try:
            e = assets.entry(v, manifest)
        except assets.AssetError as err:
            ctx.error(loc, str(err))
        if e["kind"] != kind:
            ctx.error(loc, f"asset '{v}' is a {e['kind']}, not a {kind}")


def _check(spec: Validated, ctx: ValidationContext) -> None:
    for i, o in enumerate(spec["objects"]):
        if "asset" in o.given:
            _check_assets(o["asset"], o.locs["asset"], ctx, "mesh")
    lights = spec["lights"]
    setups = lights.options if isinstance(lights, D.Choice) else [lights]
    for setup in setups:
        for li in setup:
            if isinstance(li, dict) and li.get("type") == "envmap":
                given = [k for k in ("file", "asset") if li.get(k) is not None]
                if len(given) != 1:
                    ctx.error(li.loc, "an envmap light needs exactly one of 'file' or 'asset'")
                if li.get("asset") is not None:
                    _check_assets(li["asset"], li.locs["asset"], ctx, "hdr")
    pl = spec["placement"]
    if pl["max_visible_fraction"] < pl["min_visible_fraction"]:
        ctx.error(pl.locs.get("max_visible_fraction", pl.loc), "max_visible_fraction must be >= min_visible_fraction")
    x0, z0, x1, z1 = spec["placement"]["region"]
    if not (x0 < x1 and z0 < z1):
        ctx.error(spec["placement"].locs.get("region", spec.loc), "region must satisfy x_min < x_max and z_min < z_max")


def parse_scenario(data: Any, source: str = "<scenario>", base_dir: Optional[str] = None, text: str = "") -> Scenario:
    """Validates a scenario tree (from :func:`synthgen.scene_file.read_yaml`)."""
    ctx = ValidationContext(source, base_dir)
    spec = SCENARIO_SCHEMA.validate(data, Loc.root(data), ctx)
    _check(spec, ctx)
    return Scenario(spec, source, ctx.base_dir, text or json.dumps(D.plain(spec), sort_keys=True))


def load_scenario(path: str | os.PathLike) -> Scenario:
    """Reads and validates a scenario file; raises :class:`SceneFileError` (file:line:col)."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise SceneFileError(path, None, None, "", f"cannot read the scenario: {e.strerror or e}") from e
    data = parse_yaml(text, path)
    return parse_scenario(data, path, os.path.dirname(os.path.abspath(path)), text)


# ---------------------------------------------------------------------------------------
# Sampling


def frame_rng(seed: int, frame: int, stream: int = 0) -> np.random.Generator:
    """The generator of frame ``frame``: a pure function of (scenario seed, frame index,
    stream) through numpy's SeedSequence (PCG64)."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([int(seed), int(frame), int(stream)])))


def sample_frame(sc: Scenario, frame: int) -> Dict[str, Any]:
    """Every random parameter of frame ``frame``: camera, lights, ground, objects (one entry
    per instance, with its kind index and class), and ``sampled`` ({key path: value})."""
    rng = frame_rng(sc.seed, frame)
    spec = sc.spec
    rec: Dict[str, Any] = {}
    camera = D.sample_tree(spec["camera"], rng, "camera", rec)
    lights = D.sample_tree(spec["lights"], rng, "lights", rec)
    ground = D.sample_tree(spec["ground"], rng, "ground", rec)
    objects = []
    for k, kind in enumerate(spec["objects"]):
        n = D.sample_tree(kind["count"], rng, f"objects[{k}].count", rec)
        body = {key: v for key, v in kind.items() if key != "count"}
        for i in range(int(n)):
            o = D.sample_tree(body, rng, f"objects[{k}]#{i}", rec)
            o["kind"] = k
            o["class_index"] = sc.class_names.index(kind["class"])
            objects.append(o)
    return {"frame": int(frame), "seed": sc.seed, "camera": camera, "lights": lights, "ground": ground,
            "objects": objects, "sampled": {k: D.plain(v) for k, v in rec.items()}}
