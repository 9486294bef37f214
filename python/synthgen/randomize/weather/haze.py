"""Weather ``haze``: aerosols in a deep layer (the ``homogeneous`` medium): visibility 2-10 km,
far objects fade towards the horizon's colour."""
from __future__ import annotations

from . import register
from ._layer import Layer, layer_schema


class Haze(Layer):
    key = "haze"
    order = 10
    schema = layer_schema(4000.0, 800.0, 0.9, 0.7)
    doc = "haze: aerosols in a deep layer (far objects fade)"


register(Haze())
