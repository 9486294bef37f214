"""Weather and time of day (``weather:`` in scenarios, docs/weather.md): per frame, conditions
drawn like every other distribution -- fog, haze, wet roads, snow, dusk, night, rain -- each one
module of this package.

A condition belongs to a *group*; the groups are independent of each other and each draws from
a random stream of its own, so a scenario whose weather never happens renders the frames it
rendered before weather existed (tested), and adding rain never changes where the fog is:

- ``medium``: the participating medium that fills the scene (fog, haze, ...): at most one;
- ``surface``: the state of the surfaces (wet, snow): at most one;
- ``light``: the time of day (dusk, night): at most one;
- ``precipitation``: what falls (rain streaks, an image-space step): at most one.

Within a group the conditions are tried in their ``order``: each happens with its
``probability`` (default 1), and the first that happens is the frame's.

Protocol (:class:`Condition`):

- ``key`` (the scenario key), ``group``, ``order``, ``schema`` (its parameters, every leaf a
  distribution; ``probability`` is added here) and ``doc``;
- :meth:`Condition.check` -- what the scenario's inputs must satisfy (photo backgrounds and
  their depth maps, ...), reported at the condition's key before anything renders;
- :meth:`Condition.params` -- the drawn values as the frame's plain parameters (meta);
- :meth:`Condition.no_effect` -- why drawn parameters would change nothing (a fog layer whose
  top a distribution put below the ground): the frame then has no condition of the group, and
  its meta says why (``weather_notes``) instead of recording weather that is not there;
- :meth:`Condition.object_values` -- randomizer values the condition gives the frame's objects
  that their scenario entry leaves unset (night: every vehicle's lamps on), before the
  randomizers apply;
- :meth:`Condition.apply` -- changes the frame's scene before it renders (a medium, materials,
  lights, the sky, unlabelled geometry in the renderer's pool for the condition); may set the
  context's ``exposure`` (the factor the condition's image-space step multiplies the image by,
  which the render's own exposure includes: auto-exposure); returns what to add to the
  metadata;
- :meth:`Condition.post` -- an image-space step after the render (rain streaks; fog on photos
  from their depth): a pure function of the arrays, the parameters and a generator.

Adding a condition is one module here (found by :func:`discover`, registered with
:func:`register`) plus its test; the scenario schema and the docs follow from the registry.
"""
from __future__ import annotations

import importlib
import pkgutil
import zlib
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Tuple

import numpy as np

from ..._core import SynthgenError
from ...schema.fields import EMPTY, Number, Record

__all__ = ["Condition", "WeatherContext", "GROUPS", "register", "conditions", "condition", "schema",
           "sample", "condition_rng", "discover"]

#: The groups, in the order they apply, and the random stream of each (frame_rng's stream:
#: 7 was the first weather's, fog and haze, and stays theirs).
GROUPS: Dict[str, int] = {"medium": 7, "surface": 8, "light": 9, "precipitation": 10}


@dataclass
class WeatherContext:
    """What a condition may use while it changes one frame."""

    renderer: Any                 #: the frame renderer (its scene, library, ground, objects, lights)
    rng: np.random.Generator      #: the condition's generator: a pure function of (seed, frame, key)
    photo: Any = None             #: the frame's photo (augmented photos) or None
    #: Per pixel, the share of each surface's light that reaches the camera when the condition
    #: computes it itself (fog on photos); else the renderer asks the scene's medium.
    transmittance: Optional[np.ndarray] = None
    extra: Dict[str, Any] = field(default_factory=dict)
    camera: Any = None            #: the frame's camera
    seed: int = 0                 #: the frame's render seed (for a condition's own pre-passes)
    #: The factor this condition's image-space step multiplies the image by (auto-exposure);
    #: the render's exposure (clamping, adaptive sampling, the noise estimate) includes it.
    exposure: float = 1.0


class Condition:
    """Base class of the weather conditions (see the module docstring)."""

    key: str = ""
    group: str = ""
    order: int = 0
    schema: Record
    doc: str = ""
    #: True: the condition chooses the frame's exposure itself (its context's ``exposure``: a
    #: time of day's metering); the camera's auto-exposure then adds only its compensation.
    exposes: bool = False

    def check(self, value: Mapping[str, Any], spec: Mapping[str, Any], fail: Any, photos: Any = None) -> None:
        """Checks the scenario's inputs against this condition; ``fail(message)`` reports an
        error at the condition's key. ``photos``: the scenario's photo backgrounds (a
        :class:`synthgen.background.photoset.PhotoSet`, every photo and calibration readable)
        or None."""

    def params(self, value: Mapping[str, Any]) -> Dict[str, Any]:
        """The frame's parameters from the drawn values (plain numbers; recorded in meta)."""
        return {k: _plain(v) for k, v in value.items() if k != "probability"}

    def no_effect(self, params: Mapping[str, Any]) -> Optional[str]:
        """Why the frame's parameters would change nothing (then the frame has none of this
        group's conditions), or None. Default: None."""
        return None

    def object_values(self, params: Mapping[str, Any], spec: Any, obj: Any, shape: Any,
                      rng: np.random.Generator) -> Optional[Dict[str, Any]]:
        """{randomizer key: value} for one of the frame's objects (``obj``, an ObjectSpec, of
        ``shape``), used where its scenario entry gives that randomizer no value; ``spec`` is the
        frame's FrameSpec, ``rng`` a generator of this condition and object. Default: none."""
        return None

    def apply(self, ctx: WeatherContext, params: Mapping[str, Any]) -> Optional[Dict[str, Any]]:
        """Changes the frame's scene before it renders; returns extra metadata or None."""
        return None

    def post(self, ctx: WeatherContext, arrays: Dict[str, np.ndarray],
             params: Mapping[str, Any]) -> Dict[str, np.ndarray]:
        """The image-space step after the render (default: none)."""
        return arrays


def _plain(v: Any) -> Any:
    if isinstance(v, (np.floating, float)):
        return float(v)
    if isinstance(v, (np.integer, int)) and not isinstance(v, bool):
        return int(v)
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_plain(x) for x in v]
    if isinstance(v, Mapping):
        return {k: _plain(x) for k, x in v.items()}
    return v


_REGISTRY: Dict[str, Condition] = {}


def register(c: Condition) -> Condition:
    """Adds a condition (called by its module at import)."""
    if not c.key or c.key in _REGISTRY or c.group not in GROUPS:
        raise SynthgenError(f"weather condition {c.key!r}: no key, registered twice or unknown group {c.group!r}")
    _REGISTRY[c.key] = c
    return c


def conditions() -> List[Condition]:
    """Every condition, by group (in GROUPS' order) and order within it."""
    groups = list(GROUPS)
    return sorted(_REGISTRY.values(), key=lambda c: (groups.index(c.group), c.order, c.key))


def condition(key: str) -> Condition:
    return _REGISTRY[key]


def schema() -> Record:
    """The scenario's ``weather:`` record: one optional entry per condition."""
    fields = {}
    for c in conditions():
        body = dict(c.schema.fields)
        body = {"probability": Number(1.0, min=0.0, max=1.0, doc="chance that a frame has it (the conditions "
                                                                 f"of the {c.group} group are tried in turn)"),
                **body}
        fields[c.key] = Record(body, default=None, doc=f"{c.group}: {c.doc}")
    groups = ", ".join(f"{g} ({', '.join(c.key for c in conditions() if c.group == g)})" for g in GROUPS)
    return Record(fields, default=EMPTY, doc=f"weather and time of day (docs/weather.md): per group at most one "
                                              f"condition per frame -- {groups}")


def sample(w: Mapping[str, Any], seed: int, frame: int, rec: Dict[str, Any],
           notes: Optional[List[str]] = None) -> List[Tuple[str, Dict[str, Any]]]:
    """The frame's conditions [(key, parameters)], at most one per group, in GROUPS' order. A
    condition whose drawn parameters would have no effect (:meth:`Condition.no_effect`) is not
    the frame's: its group has none, and ``notes`` gets ``"KEY: reason"``."""
    from ...schema import distributions as D
    from ...schema.distributions import frame_rng

    out: List[Tuple[str, Dict[str, Any]]] = []
    for group, stream in GROUPS.items():
        members = [c for c in conditions() if c.group == group and w.get(c.key) is not None]
        if not members:
            continue
        rng = frame_rng(seed, frame, stream)
        for c in members:
            spec = w[c.key]
            if not float(rng.random()) < float(spec["probability"]):
                continue
            body = {k: v for k, v in spec.items() if k != "probability"}
            params = c.params(D.sample_tree(body, rng, f"weather.{c.key}", rec))
            why = c.no_effect(params)
            if why is None:
                out.append((c.key, params))
            elif notes is not None:
                notes.append(f"{c.key}: {why}")
            break
    return out


def condition_rng(seed: int, frame: int, key: str) -> np.random.Generator:
    """The generator a condition applies with: a pure function of (scenario seed, frame, key)."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(
        [int(seed), int(frame), 7, zlib.crc32(key.encode())])))


def discover() -> None:
    """Imports every condition module, which registers its condition."""
    for m in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if not m.name.startswith("_"):  # _name: shared code, not a condition
            importlib.import_module(f"{__name__}.{m.name}")


discover()
