"""Shared by the medium conditions whose medium is the ``homogeneous`` plugin (a layer of
constant density, cpp/medium/homogeneous.cpp): fog and haze."""
from __future__ import annotations

from typing import Any, Dict, Mapping, Optional

from ...schema.fields import Number, Record
from ...schema.random import R
from . import Condition, WeatherContext


def refuse_photos(spec: Mapping[str, Any], fail: Any, what: str) -> None:
    """A medium rendered around the inserted objects only would not match the photo."""
    if spec.get("background") is not None:
        fail(f"not available with photo backgrounds yet: the photo has no {what} of its own "
             "(fog on photos, from their depth, is to come: docs/weather.md)")


def layer_schema(visibility: float, top: float, albedo: float, g: float) -> Record:
    """The layer's parameters, each value also a distribution."""
    return Record({
        "visibility": R(Number(visibility, min=0.0, min_open=True,
                               doc="meteorological visibility in metres (contrast 2% at this distance: extinction "
                                   "3.912 / visibility)")),
        "top": R(Number(top, doc="height of the layer's top in metres (clear air above)")),
        "albedo": R(Number(albedo, min=0.0, max=1.0, doc="single-scattering albedo")),
        "g": R(Number(g, min=-0.99, max=0.99, doc="Henyey-Greenstein asymmetry (> 0: forward scattering)")),
    })


class Layer(Condition):
    """A homogeneous layer from the ground up to ``top``."""

    group = "medium"

    def check(self, value: Mapping[str, Any], spec: Mapping[str, Any], fail: Any) -> None:
        refuse_photos(spec, fail, "fog")

    def params(self, value: Mapping[str, Any]) -> Dict[str, Any]:
        return {k: float(value[k]) for k in ("visibility", "top", "albedo", "g")}

    def apply(self, ctx: WeatherContext, params: Mapping[str, Any]) -> Optional[Dict[str, Any]]:
        ctx.renderer.scene.set_medium("homogeneous", dict(params))
        return None
