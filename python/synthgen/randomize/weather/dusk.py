"""Weather ``dusk``: the sun just below the horizon (0 to -6 degrees: civil twilight, the blue
hour) -- the ``twilight`` sky with its glow over the sun, the vehicles' lamps and headlamp beams
on, the street lights on, the frame exposed like a camera's auto-exposure
(see :mod:`synthgen.randomize.weather._night`)."""
from __future__ import annotations

from . import register
from ._night import TimeOfDay, time_of_day_schema


class Dusk(TimeOfDay):
    key = "dusk"
    order = 0
    schema = time_of_day_schema({"uniform": [-6.0, 0.0]}, None, key=0.1, moon=False)
    doc = "dusk: the sun 0-6 degrees below the horizon, lamps and street lights on"


register(Dusk())
