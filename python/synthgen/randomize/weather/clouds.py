"""Weather ``clouds``: a deck of low clouds (the heterogeneous ``clouds`` medium,
cpp/medium/clouds.cpp: fBm billows with flat bases and rounded tops, clear gaps by coverage)
between the sun and the scene: broken light, cloud shadows drifting over the road, an overcast
sky where the deck closes. Each frame draws its own clouds (the noise seed from the condition's
generator; recorded in meta)."""
from __future__ import annotations

from typing import Any, Dict, Mapping, Optional

from ...schema.fields import Number, Record
from ...schema.random import R
from . import WeatherContext, register
from ._layer import NoiseMedium


class Clouds(NoiseMedium):
    key = "clouds"
    plugin = "clouds"
    what = "clouds"
    order = 7
    doc = "low clouds: a deck of clouds over the scene, broken by clear gaps (a heterogeneous medium)"
    schema = Record({
        "visibility": R(Number(60.0, min=0.0, min_open=True,
                               doc="meteorological visibility in metres inside a cloud (extinction 3.912 / "
                                   "visibility; cumulus about 30-100 m)")),
        "bottom": R(Number(400.0, min=1.0, doc="height of the cloud base in metres")),
        "top": R(Number(900.0, min=2.0, doc="height of the cloud tops in metres")),
        "coverage": R(Number(0.5, min=0.0, max=1.0, min_open=True, doc="share of the sky the deck covers")),
        "feature_size": R(Number(500.0, min=1.0, max=100000.0, doc="width of the billows in metres")),
        "albedo": R(Number(0.99, min=0.0, max=1.0, doc="single-scattering albedo")),
        "g": R(Number(0.8, min=-0.99, max=0.99, doc="Henyey-Greenstein asymmetry (> 0: forward scattering)")),
    })

    keys = tuple(schema.fields)

    def apply(self, ctx: WeatherContext, params: Mapping[str, Any]) -> Optional[Dict[str, Any]]:
        if not params["bottom"] < params["top"]:
            from ..._core import SynthgenError

            raise SynthgenError(f"weather.clouds: bottom ({params['bottom']}) must be below top ({params['top']})")
        return super().apply(ctx, params)


register(Clouds())
