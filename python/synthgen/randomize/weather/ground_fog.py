"""Weather ``ground_fog``: banks of fog lying on the ground, thinning with height, patchy along
the road (the heterogeneous ``ground_fog`` medium, cpp/medium/ground_fog.cpp: a height profile
times a coverage mask of 3D fBm noise, tracked through a majorant grid). Each frame draws its
own banks (the noise seed from the condition's generator; recorded in meta)."""
from __future__ import annotations

from ...schema.fields import Number, Record
from ...schema.random import R
from . import register
from ._layer import NoiseMedium


class GroundFog(NoiseMedium):
    key = "ground_fog"
    plugin = "ground_fog"
    what = "ground fog"
    order = 5
    doc = "ground fog: banks of fog on the ground, thinning with height, patchy (a heterogeneous medium)"
    schema = Record({
        "visibility": R(Number(40.0, min=0.0, min_open=True,
                               doc="meteorological visibility in metres inside a bank at the ground (extinction "
                                   "3.912 / visibility there)")),
        "scale_height": R(Number(3.0, min=0.05, max=500.0, doc="height in metres over which the density falls by e")),
        "coverage": R(Number(0.6, min=0.0, max=1.0, min_open=True, doc="share of the ground under fog banks")),
        "contrast": R(Number(1.5, min=0.1, max=20.0, doc="sharpness of the banks' edges")),
        "feature_size": R(Number(40.0, min=0.5, max=10000.0, doc="width of the banks in metres")),
        "feature_height": R(Number(8.0, min=0.1, max=1000.0, doc="height of the banks' noise features in metres")),
        "albedo": R(Number(0.95, min=0.0, max=1.0, doc="single-scattering albedo")),
        "g": R(Number(0.75, min=-0.99, max=0.99, doc="Henyey-Greenstein asymmetry (> 0: forward scattering)")),
    })

    #: The medium plugin's parameters this condition draws (the rest keep the plugin's defaults).
    keys = tuple(schema.fields)


register(GroundFog())
