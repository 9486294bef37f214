"""Weather ``fog``: water droplets in a layer near the ground (the ``homogeneous`` medium):
visibility 30-1000 m, forward scattering."""
from __future__ import annotations

from . import register
from ._layer import Layer, layer_schema


class Fog(Layer):
    key = "fog"
    order = 0
    schema = layer_schema(150.0, 40.0, 0.95, 0.75)
    doc = "fog: water droplets in a layer near the ground"


register(Fog())
