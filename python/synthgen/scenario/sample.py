"""Sampling one frame of a scenario: a pure function of (scenario, frame index) into typed
records.

:func:`frame_rng` (:mod:`synthgen.schema.distributions`) is the only source of randomness: a
generator seeded by (scenario seed, frame, stream) through numpy's SeedSequence.
:func:`sample_frame` walks the validated tree in a fixed order
(:func:`synthgen.schema.distributions.sample_tree`), records every draw under its key path and
returns a :class:`FrameSpec`: the camera, lights (plugin name and given parameters), ground and
one :class:`ObjectSpec` per object instance.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Tuple

from .. import randomize
from ..randomize.weather import sample as sample_weather
from ..schema import distributions as D
from ..schema.distributions import frame_rng
from ..schema.plugins import given_params
from .load import Scenario, support_of
from .schema import DISTORTION_KEYS, SHAPE_KEYS, exposure_mode

#: The stream of the camera's exposure draws (camera.exposure): its own, so that a randomized
#: exposure changes no other draw (streams 1-6: layout, camera jitter, render seed, negatives,
#: photo, photo finish; 7-10: the weather groups; 100 + k: object k).
EXPOSURE_STREAM = 11

__all__ = ["frame_rng", "sample_frame", "FrameSpec", "ObjectSpec", "PluginSpec", "CameraSpec", "GroundSpec"]


@dataclass
class PluginSpec:
    """A sampled plugin (a material or a light): its name and the parameters the scenario
    gives (the native core owns the defaults)."""

    type: str
    params: Dict[str, Any]

    @classmethod
    def of(cls, rec: Mapping[str, Any]) -> "PluginSpec":
        return cls(str(rec["type"]), given_params(rec))


@dataclass
class CameraSpec:
    """The sampled camera: vertical field of view or intrinsics (fx, fy, cx, cy as given),
    the pose record (``type`` orbit or look_at and its values) and the exposure: ``mode``
    (auto or fixed, resolved by the format version), ``key``, ``ev``, ``factor`` (None: 1)."""

    fov_y: float
    intrinsics: Dict[str, float]
    pose: Mapping[str, Any]
    exposure: Mapping[str, Any] = field(default_factory=lambda: {"mode": "fixed", "key": 0.18, "ev": 0.0,
                                                                 "factor": None})
    #: OpenCV lens distortion (k1, k2, p1, p2, k3); zeros: none.
    distortion: Tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0)


@dataclass
class GroundSpec:
    enabled: bool
    size: Optional[float]   #: None: the ground reaches the horizon
    material: PluginSpec


@dataclass
class ObjectSpec:
    """One sampled object instance of a frame."""

    index: int                  #: position in the frame (its instance id is index + 1)
    kind: int                   #: index of its entry in the scenario's ``objects``
    class_index: int            #: index in the scenario's class list (class id = class_index + 1); -1: unlabelled
    class_name: str
    name: Optional[str]
    shape: Tuple[str, Any]      #: ("primitive", "box") | ("mesh", path) | ("asset", id) | (randomizer key, value)
    size: Tuple[float, float, float]
    scale: float
    yaw: float
    material: Optional[PluginSpec]
    #: Visibility limits of this entry (min_pixels, min/max_visible_fraction) that override
    #: the placement's.
    limits: Dict[str, Any] = field(default_factory=dict)
    forward: Optional[str] = None  #: the model's forward axis, when the scenario names it
    up: Optional[str] = None       #: the model's up axis, when the scenario names it
    #: The sampled value of every randomizer key (None: not given), in sample order.
    randomizers: Dict[str, Any] = field(default_factory=dict)
    roll: float = 0.0               #: tilt about the forward axis, degrees
    pitch: float = 0.0              #: tilt about the lateral axis, degrees
    region: Optional[Tuple[float, float, float, float]] = None  #: its entry's region, if it has one
    support: Optional[int] = None   #: the entry whose objects it rests on (rests_on), if any
    pixel_height: Optional[float] = None  #: its box height in the image, pixels, if asked

    @property
    def labelled(self) -> bool:
        """False for objects of entries with ``label: false`` (no class, id 0 in the masks)."""
        return self.class_index >= 0


@dataclass
class FrameSpec:
    """Every random parameter of one frame, and ``sampled``: {key path: drawn value}."""

    frame: int
    seed: int
    camera: CameraSpec
    lights: List[PluginSpec]
    ground: GroundSpec
    objects: List[ObjectSpec]
    sampled: Dict[str, Any]
    #: Post-processing steps: name and every parameter (defaults included), in order.
    post: List[PluginSpec] = field(default_factory=list)
    #: A negative frame: its labelled objects were left out (scenario negative_frames).
    negative: bool = False
    #: The frame's weather: [(condition key, its parameters)], at most one per group
    #: (synthgen.randomize.weather), in the order they apply.
    weather: List[Tuple[str, Dict[str, Any]]] = field(default_factory=list)
    #: Why a condition the frame drew is not its weather ("fog: no fog: top -3 m ..."): meta
    #: ``weather_notes``.
    weather_notes: List[str] = field(default_factory=list)


#: The visibility limits an object entry may set for its instances.
LIMIT_KEYS = ("min_pixels", "min_visible_fraction", "max_visible_fraction")


def _object(index: int, kind: int, class_index: int, o: Mapping[str, Any], support: Optional[int]) -> ObjectSpec:
    shape_key = next(k for k in SHAPE_KEYS if o.get(k) is not None)
    mat = o.get("material")
    return ObjectSpec(index=index, kind=kind, class_index=class_index, class_name=str(o["class"] or ""),
                      name=o.get("name"),
                      shape=(shape_key, o[shape_key]), size=tuple(float(x) for x in o["size"]),
                      scale=float(o["scale"]), yaw=float(o["yaw"]), material=PluginSpec.of(mat) if mat else None,
                      forward=o.get("forward"), up=o.get("up"),
                      limits={k: o[k] for k in LIMIT_KEYS if o.get(k) is not None},
                      randomizers={r.key: o.get(r.key) for r in randomize.randomizers()},
                      roll=float(o["roll"]), pitch=float(o["pitch"]),
                      region=tuple(float(v) for v in o["region"]) if o.get("region") is not None else None,
                      support=support,
                      pixel_height=float(o["pixel_height"]) if o.get("pixel_height") is not None else None)


def sample_frame(sc: Scenario, frame: int) -> FrameSpec:
    """Every random parameter of frame ``frame`` (see the module docstring)."""
    rng = frame_rng(sc.seed, frame)
    spec = sc.spec
    rec: Dict[str, Any] = {}
    camera = D.sample_tree({k: v for k, v in spec["camera"].items() if k != "exposure"}, rng, "camera", rec)
    lights = D.sample_tree(spec["lights"], rng, "lights", rec)
    ground = D.sample_tree(spec["ground"], rng, "ground", rec)
    objects: List[ObjectSpec] = []
    supports = support_of(spec)
    for k, kind in enumerate(spec["objects"]):
        n = D.sample_tree(kind["count"], rng, f"objects[{k}].count", rec)
        body = {key: v for key, v in kind.items() if key != "count"}
        for i in range(int(n)):
            o = D.sample_tree(body, rng, f"objects[{k}]#{i}", rec)
            cls = sc.class_names.index(kind["class"]) if kind["label"] else -1
            objects.append(_object(len(objects), k, cls, o, supports[k]))
    # Negative frames: the labelled objects left out (a stream of its own, so that every
    # other draw is the same as in the frame with them).
    negative = bool(spec["negative_frames"] > 0.0 and frame_rng(sc.seed, frame, 4).random() < spec["negative_frames"])
    if negative:
        objects = [o for o in objects if not o.labelled]
        for i, o in enumerate(objects):
            o.index = i
    steps = D.sample_tree(spec["post"], rng, "post", rec)
    weather_notes: List[str] = []
    weather = sample_weather(spec["weather"], sc.seed, frame, rec, weather_notes)
    intrinsics = {k: float(camera[k]) for k in ("fx", "fy", "cx", "cy") if camera.get(k) is not None}
    exposure = dict(D.sample_tree(spec["camera"]["exposure"], frame_rng(sc.seed, frame, EXPOSURE_STREAM),
                                  "camera.exposure", rec))
    exposure["mode"] = exposure_mode(spec["camera"]["exposure"], spec["version"])
    return FrameSpec(
        frame=int(frame), seed=sc.seed,
        camera=CameraSpec(fov_y=float(camera["fov_y"]), intrinsics=intrinsics, pose=camera["pose"],
                          exposure=exposure,
                          distortion=tuple(float(camera.get(k) or 0.0) for k in DISTORTION_KEYS)),
        lights=[PluginSpec.of(li) for li in lights],
        ground=GroundSpec(enabled=bool(ground["enabled"]), size=None if ground["size"] is None else float(ground["size"]),
                          material=PluginSpec.of(ground["material"])),
        objects=objects, sampled={k: D.plain(v) for k, v in rec.items()},
        post=[PluginSpec(str(p["type"]), {k: v for k, v in p.items() if k != "type"}) for p in steps],
        negative=negative, weather=weather, weather_notes=weather_notes)
