"""Weather ``night``: the sun 12 to 18 degrees below the horizon and deeper (nautical twilight's
end to night) -- the ``twilight`` sky's last glow, the natural night sky and a city's sky glow,
sometimes the moon; the vehicles' lamps and headlamp beams on, street lights along the road,
the frame exposed like a camera's auto-exposure (see :mod:`synthgen.randomize.weather._night`).

:func:`street_night` is the ``weather:`` section that renders a scenario's street at night in
every frame (bench/weather_overhead.py)."""
from __future__ import annotations

from typing import Any, Dict

from . import register
from ._night import TimeOfDay, time_of_day_schema


class Night(TimeOfDay):
    key = "night"
    order = 10
    schema = time_of_day_schema({"uniform": [-18.0, -12.0]}, {"loguniform": [0.0003, 0.01]}, key=0.05, moon=True)
    doc = "night: the sun 12-18 degrees below the horizon, the night sky, lamps, street lights, the moon"


register(Night())


def street_night(elevation: float = -15.0, spacing: float = 25.0, offset: float = 17.0, **street: Any
                 ) -> Dict[str, Any]:
    """The ``weather:`` section (a scenario override) that makes every frame a night street:
    the sun at ``elevation``, a fixed sky glow, no moon, head and tail lamps on (low beams),
    sodium street lights on both sides every ``spacing`` metres at ``offset`` from the centre
    line (17 m: outside scenarios/weather.yaml's 30 m plot), auto-exposure. ``street`` overrides
    street_lights' other keys. ``load_scenario(path, overrides=[("weather", street_night())])``."""
    lights = {"enabled": True, "spacing": float(spacing), "sides": "both", "offset": float(offset), **street}
    return {"night": {"probability": 1.0, "elevation": float(elevation), "sky_glow": 0.002,
                      "lamps": {"head": "low", "high_beam": 0.0}, "street_lights": lights,
                      "moon": {"probability": 0.0}}}
