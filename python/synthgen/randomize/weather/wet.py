"""Weather ``wet`` (group surface): a wet road after rain. The ground gets a water film in
patches -- darker and glossier: light that enters the film is partly reflected back down at the
water-air interface and absorbed at the next bounce (Lekner & Dorf 1988, "Why some things are
darker when wet", Applied Optics 27(7); Jensen et al. 1999, "Rendering of wet materials") --
and puddles, flat water with a mirror surface that reflects the sky, the objects and the
lights; every object's materials get the film too (synthgen.scene.wear.wet_twin: a clear-coat
gloss, rough and porous parts darker), each one wrapped so that models keep theirs. Labels do
not see materials and do not change. The ground of a photo (a shadow catcher) stays dry."""
from __future__ import annotations

from typing import Any, Dict, Mapping, Optional

from ...scene import wear
from ...schema.fields import Number, Record
from ...schema.random import R
from . import Condition, WeatherContext, register
from ._surface import wrap_surfaces


class Wet(Condition):
    key = "wet"
    group = "surface"
    order = 0
    doc = "wet surfaces: a water film (darker, glossier), puddles on the ground"
    schema = Record({
        "wetness": R(Number(0.9, min=0.0, max=1.0, doc="share of the ground under a water film (in patches, as a "
                                                       "road dries), and the weight of the objects' film")),
        "roughness": R(Number(0.1, min=0.0, max=1.0, doc="roughness of the film (0: a mirror; the stones of "
                                                         "asphalt poking through make it rougher)")),
        "puddles": R(Number(0.1, min=0.0, max=1.0, doc="share of the ground under puddles (flat mirror water)")),
        "puddle_scale": R(Number(3.0, min=0.01, max=1000.0, doc="size of the puddles in metres (the feature size "
                                                                "of their noise)")),
    })

    def params(self, value: Mapping[str, Any]) -> Dict[str, Any]:
        return {k: float(value[k]) for k in ("wetness", "roughness", "puddles", "puddle_scale")}

    def apply(self, ctx: WeatherContext, params: Mapping[str, Any]) -> Optional[Dict[str, Any]]:
        seed = int(ctx.rng.integers(0, 1 << 31))
        lib = ctx.renderer.library  # this frame's textures and materials (removed with it)

        def ground(m: int) -> int:
            return wear.wet_ground(lib, m, seed=seed, **params)

        def objects(m: int) -> int:
            return wear.wet(lib, m, wetness=params["wetness"], roughness=params["roughness"])

        wrap_surfaces(ctx, ground, objects)
        return {"seed": seed}


register(Wet())
