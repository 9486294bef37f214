"""Randomizer ``paint``: a vehicle's body paint from a realistic palette of car colours.

The vehicle's library entry names its paint materials (``materials: {<name in the model>:
paint}``); this randomizer gives them a car paint -- a clear-coated base (a Lambertian base
under a smooth dielectric coat, the ``coated`` material) -- whose colour is drawn per vehicle.
The ``cars`` palette follows the shares of new cars' colours worldwide (Axalta Global
Automotive Color Popularity Report 2022: white 35 %, black 18 %, grey 18 %, silver 8 %, blue
7 %, red 6 %, brown / beige 3 %, green 2 %, yellow / gold 2 %, other 1 %), each colour with a
small spread in lightness and hue, so that a detector sees what roads show rather than uniform
RGB. The colour drawn goes into the metadata."""
from __future__ import annotations

import colorsys
from typing import Any, List, Mapping, Optional, Tuple

import numpy as np

from ..schema.fields import Choice, Number, Record
from ..schema.random import R
from . import ModelParts, ObjectContext, Randomizer, register

#: (name, share, linear albedo of the base) of the ``cars`` palette.
CARS = (
    ("white", 0.35, (0.80, 0.80, 0.78)),
    ("black", 0.18, (0.015, 0.015, 0.017)),
    ("grey", 0.18, (0.16, 0.165, 0.17)),
    ("silver", 0.08, (0.45, 0.46, 0.47)),
    ("blue", 0.07, (0.025, 0.06, 0.22)),
    ("red", 0.06, (0.42, 0.025, 0.03)),
    ("brown", 0.03, (0.22, 0.13, 0.07)),
    ("green", 0.02, (0.04, 0.16, 0.07)),
    ("yellow", 0.02, (0.70, 0.48, 0.04)),
    ("other", 0.01, (0.40, 0.12, 0.35)),
)
PALETTES = {"cars": CARS}

SCHEMA = Record({
    "palette": R(Choice(list(PALETTES), "cars", doc="colour palette: cars (the shares of new cars' colours "
                                                    "worldwide)")),
    "roughness": R(Number(0.06, min=0.0, max=1.0, doc="clear coat roughness (new cars about 0.03 to 0.1, "
                                                      "weathered ones more)")),
}, default=None, doc="the body paint of a library vehicle (its entry names the paint materials) from a realistic "
                     "palette; the colour drawn goes into the metadata")


def draw(palette: str, rng: np.random.Generator) -> Tuple[str, List[float]]:
    """(colour name, linear albedo) from the palette: a colour by its share, then a spread of
    +-15 % in lightness and +-0.02 in hue."""
    names, shares, rgbs = zip(*PALETTES[palette])
    p = np.asarray(shares, float)
    i = int(rng.choice(len(p), p=p / p.sum()))
    h, l, s = colorsys.rgb_to_hls(*rgbs[i])
    l = float(np.clip(l * rng.uniform(0.85, 1.15), 0.0, 0.95))
    h = float((h + rng.uniform(-0.02, 0.02)) % 1.0)
    return names[i], [float(np.clip(c, 0.0, 1.0)) for c in colorsys.hls_to_rgb(h, l, s)]


class Paint(Randomizer):
    key = "paint"
    schema = SCHEMA
    sample_order = 22
    apply_order = 22  # before the plates, decals and wear (which wrap the paint)

    def needs(self, parts: ModelParts) -> Optional[str]:
        if "paint" not in parts.roles:
            return ("its model names no paint material (a library vehicle's `materials: {<name>: paint}` in "
                    "assets_manifest)")
        return None

    def apply(self, ctx: ObjectContext, value: Mapping[str, Any], materials: List[int]) -> Tuple[List[int], Any]:
        self.refuse(ctx, materials)
        paint = set(ctx.roles.get("paint", ())) if ctx.roles else set()
        name, albedo = draw(value["palette"], ctx.rng)
        mat = ctx.scene.add_material("coated", {"albedo": albedo, "roughness": float(value["roughness"]),
                                                "ior": 1.5})
        return [mat if m in paint else m for m in materials], {"colour": name, "albedo": albedo}


register(Paint())
