"""Post-processing: image-space steps applied to a rendered frame before it is
written (camera effects, compositing into photos, denoising). Pure functions: arrays +
parameters -> arrays; labels (depth, ids) are never filtered, only the image.

A step registers a :class:`PostStep`: its ``name`` (the ``type`` under a scenario's
``post:`` list), its parameter ``schema`` (leaves may be distributions in scenarios) and
``apply(arrays, params) -> arrays``. Steps run in the order the scenario lists them; what
ran, with its sampled parameters, goes into the frame's metadata. Adding a step is one
module here (found by :func:`discover`) plus its test.

:mod:`synthgen.post.photo` holds the steps of inserting renders into real photos
(compositing by differential rendering, camera matching), which the background pipeline
runs itself.
"""
from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Mapping, Tuple

import numpy as np

from .._core import SynthgenError
from ..schema.fields import Record

__all__ = ["PostStep", "register", "steps", "step", "discover", "step_modules", "apply_steps"]

Arrays = Dict[str, np.ndarray]


@dataclass(frozen=True)
class PostStep:
    name: str
    doc: str
    schema: Record
    apply: Callable[[Mapping[str, np.ndarray], Mapping[str, Any]], Arrays]
    module: str = ""


_STEPS: Dict[str, PostStep] = {}


def register(s: PostStep) -> PostStep:
    if s.name in _STEPS:
        raise SynthgenError(f"post-processing step '{s.name}' is registered twice")
    _STEPS[s.name] = s
    return s


def steps() -> List[PostStep]:
    """The registered steps, by name."""
    return [_STEPS[k] for k in sorted(_STEPS)]


def step(name: str) -> PostStep:
    return _STEPS[name]


def apply_steps(arrays: Mapping[str, np.ndarray], chain: List[Tuple[str, Mapping[str, Any]]]) -> Arrays:
    """Applies (name, params) steps in order; returns the new arrays (inputs untouched)."""
    out: Arrays = dict(arrays)
    for name, params in chain:
        out = dict(step(name).apply(out, params))
    return out


def step_modules() -> List[str]:
    """Modules that define a step (subpackages, like ``photo``, hold helpers of the pipeline)."""
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.ispkg)


def discover() -> None:
    """Imports every step module, which registers its step."""
    for name in step_modules():
        importlib.import_module(f"{__name__}.{name}")


discover()
