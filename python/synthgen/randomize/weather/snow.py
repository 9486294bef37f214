"""Weather ``snow`` (group surface): snow lying on every surface that faces up -- the ground
and the tops of objects -- in patches, sliding off steep faces (synthgen.scene.wear.snow: the
``facing`` texture times an fBm in world coordinates, so patches run on from the ground onto
objects); a white, rough, diffuse layer (albedo 0.8-0.9, no specular glare) over each of the
frame's materials, each one wrapped so that models keep theirs. Labels do not see materials
and do not change. The ground of a photo (a shadow catcher) is left as it is."""
from __future__ import annotations

from typing import Any, Dict, Mapping, Optional

from ..._core import TextureRef
from ...scene import wear
from ...schema.fields import Number, Record
from ...schema.random import R
from . import Condition, WeatherContext, register
from ._surface import wrap_surfaces


class Snow(Condition):
    key = "snow"
    group = "surface"
    order = 10
    doc = "snow on up-facing surfaces (the ground, the tops of objects), in patches"
    schema = Record({
        "amount": R(Number(0.85, min=0.0, max=1.0, doc="share of the objects' up-facing surfaces under snow")),
        "ground": R(Number(0.95, min=0.0, max=1.0, doc="share of the ground under snow")),
        "scale": R(Number(1.5, min=0.01, max=1000.0, doc="size of the snow's patches, metres")),
        "max_slope": R(Number(45.0, min=0.0, max=90.0, doc="steepest slope snow stays on, degrees from "
                                                           "horizontal (it thins out over +-10 degrees)")),
        "bump": R(Number(0.004, min=0.0, max=0.05, doc="height of the snow's relief, metres")),
    })

    def params(self, value: Mapping[str, Any]) -> Dict[str, Any]:
        return {k: float(value[k]) for k in ("amount", "ground", "scale", "max_slope", "bump")}

    def apply(self, ctx: WeatherContext, params: Mapping[str, Any]) -> Optional[Dict[str, Any]]:
        seed = int(ctx.rng.integers(0, 1 << 31))
        lib = ctx.renderer.library
        common = {k: params[k] for k in ("scale", "max_slope", "bump")}
        on_ground = wear.snow_layer(lib, seed=seed, amount=params["ground"], **common)
        on_objects = wear.snow_layer(lib, seed=seed, amount=params["amount"], **common)

        def mix(layer: Any, m: int) -> int:
            return lib.add_material("mix", {"material_a": int(m), "material_b": int(layer[0]),
                                            "weight": TextureRef(layer[1])})

        wrap_surfaces(ctx, lambda m: mix(on_ground, m), lambda m: mix(on_objects, m))
        return {"seed": seed}


register(Snow())
