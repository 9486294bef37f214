"""Randomizer ``wear``: rust, dirt, scratches and ice over the object's material (the
:mod:`synthgen.scene.wear` presets), each with its own probability per instance; the
effects applied and their parameters (seeds included) go into the metadata."""
from __future__ import annotations

from typing import Any, Dict, List, Mapping, Tuple

from ..schema.fields import REQUIRED, Bool, Choice, Field, Integer, ListOf, Number, Record, Vector
from ..schema.random import R
from ..scene import wear
from . import ObjectContext, Randomizer, register

#: The effects, in the order they are applied.
EFFECTS = ("rust", "dirt", "scratches", "ice")


def _wear_effect(amount: float, params: Dict[str, Field], doc: str) -> Record:
    return Record(dict({"probability": Number(1.0, min=0.0, max=1.0, doc="chance that an instance gets the effect"),
                        "amount": R(Number(amount, min=0.0, max=1.0, doc="covered fraction")),
                        "seed": R(Integer(None, min=0, max=(1 << 31) - 1, doc="pattern seed (default: drawn)"))},
                       **params), default=None, doc=doc)


_RAMP_STOP = Record({"position": Number(REQUIRED, min=0.0, max=1.0, doc="position in the ramp"),
                     "color": R(Vector(3, REQUIRED, min=0.0, max=1.0, broadcast=True, doc="linear RGB at that position"))})

_STOCHASTIC = Bool(True, doc="shade secondary hits where the mask is fractional with one material, chosen by the "
                               "mask (cheaper; noisier where the object is seen in a mirror or a wet road: "
                               "docs/failure_modes.md); false: blend both")

_SCALE_DOC = "noise features across the object (relative mapping: the same pattern at any model size)"

# NOTE: the defaults are the presets' (synthgen.scene.wear), so that a scenario's
# `rust: {}` and `wear.rust(scene, base)` make the same rust.
SCHEMA = Record({
    "rust": _wear_effect(0.35, {
        "scale": R(Number(3.0, min=0.001, max=1000.0, doc=_SCALE_DOC)),
        "bottom_bias": R(Number(0.6, min=0.0, max=2.0, doc="more rust low on the object (0: none, 2: strongly)")),
        "roughness": R(Number(0.85, min=0.0, max=1.0, doc="rust roughness (>= 0.8: Lambertian)")),
        "bump": R(Number(0.002, min=0.0, max=0.05, doc="height of the rust's relief, metres")),
        "colors": ListOf(_RAMP_STOP, None, min_items=1, doc="colour ramp of the rust (default: dark brown to orange)"),
        "edges": R(Number(1.0, min=0.0, max=4.0, doc="rust starting at convex edges and sheet borders (0: none)")),
        "edge_radius": R(Number(0.03, min=0.0001, max=1.0, doc="how sharp an edge must be, metres (edges sharper "
                                                               "than about 0.75 of it count)")),
        "streaks": R(Number(0.5, min=0.0, max=4.0, doc="rust running down in vertical streaks (0: none)")),
        "from_scratches": R(Number(1.0, min=0.0, max=4.0, doc="rust creeping out from the scratches, when the "
                                                              "instance also gets scratches (0: none)")),
        "stochastic": _STOCHASTIC},
        "rust with relief, starting at edges and scratches, more towards the bottom, running down in streaks "
        "(synthgen.scene.wear.rust)"),
    "dirt": _wear_effect(0.4, {
        "scale": R(Number(5.0, min=0.001, max=1000.0, doc=_SCALE_DOC)),
        "bottom_bias": R(Number(1.0, min=0.0, max=4.0, doc="more dirt low on the object, as gravity leaves it "
                                                           "(0: none)")),
        "ao_radius": R(Number(0.3, min=0.0001, max=100.0, doc="crease search distance, metres")),
        "ao_weight": R(Number(1.0, min=0.0, max=4.0, doc="dirt in creases (ambient occlusion)")),
        "color": R(Vector(3, (0.12, 0.09, 0.06), min=0.0, max=1.0, broadcast=True, doc="dirt colour (linear RGB; "
                                                                                       "darker in creases)")),
        "roughness": R(Number(0.95, min=0.0, max=1.0, doc="dirt roughness")),
        "splash": R(Number(1.0, min=0.0, max=4.0, doc="droplets thrown up by the wheels, low on the body (0: none)")),
        "softness": R(Number(0.3, min=0.01, max=2.0, doc="how gradually the film thins out at its edges (mask "
                                                         "units; small: sharp-edged patches)")),
        "stochastic": _STOCHASTIC},
        "road grime: a film densest low on the body, in creases and where the wheels splash, thinning with height "
        "(synthgen.scene.wear.dirt)"),
    "scratches": _wear_effect(1.0, {
        "density": R(Number(8.0, min=0.001, max=10000.0, doc="cells of the scratch pattern per metre")),
        "width": R(Number(0.04, min=0.0001, max=1.0, doc="line width, as a fraction of a cell")),
        "direction": R(Choice(["x", "y", "z"], None, doc="object axis the scratches run along "
                                                          "(default: random directions)")),
        "elongation": R(Number(8.0, min=1.0, max=100.0, doc="strokes: the longest is elongation / 8 cells "
                                                            "(at most 2); cells: stretch along direction")),
        "metal": R(Choice(["aluminium", "chrome", "copper", "gold", "iron", "silver"], "aluminium",
                          doc="the bare metal under the scratched paint")),
        "roughness": R(Number(0.35, min=0.0, max=1.0, doc="roughness of the bare metal")),
        "depth": R(Number(0.0, min=0.0, max=0.01, doc="groove depth in metres (tilts the "
                                                      "metal's normal; 0: flat)")),
        "style": R(Choice(["strokes", "swirl", "cells"], "strokes",
                          doc="strokes: straight strokes of random length and depth; swirl: polishing arcs; cells: "
                              "the edges of a cellular pattern")),
        "spread": R(Number(12.0, min=0.0, max=90.0, doc="angular spread of directed strokes, degrees")),
        "edges": R(Number(1.0, min=0.0, max=4.0, doc="with amount < 1: the scratched clusters gather at convex edges "
                                                     "and borders -- door edges, handles, bumper corners (0: anywhere)")),
        "edge_radius": R(Number(0.03, min=0.0001, max=1.0, doc="how sharp an edge must be, metres"))},
        "scratches through the paint down to bare metal (synthgen.scene.wear.scratches)"),
    "ice": _wear_effect(0.5, {
        "scale": R(Number(4.0, min=0.001, max=1000.0, doc=_SCALE_DOC)),
        "top_bias": R(Number(0.5, min=0.0, max=2.0, doc="more ice high on the object (0: none)")),
        "bump": R(Number(0.003, min=0.0, max=0.05, doc="height of the frost's relief, metres")),
        "softness": R(Number(0.25, min=0.01, max=2.0, doc="how gradually the frost thins out at its edges (mask "
                                                          "units)"))},
        "ice and frost with soft edges, more towards the top (synthgen.scene.wear.ice)"),
}, default=None, doc="wear effects (synthgen.wear presets), applied in the order rust, dirt, scratches, ice")


#: The scratches' parameters that shape their lines (:func:`synthgen.scene.wear.add_scratch_lines`).
LINE_KEYS = ("seed", "density", "width", "direction", "elongation", "style", "spread")


class Wear(Randomizer):
    key = "wear"
    schema = SCHEMA
    sample_order = 30
    apply_order = 40

    def apply(self, ctx: ObjectContext, value: Mapping[str, Any], materials: List[int]) -> Tuple[List[int], Any]:
        rng = ctx.rng
        # Which effects the instance gets, with their parameters and seeds (drawn in the
        # effects' order), then applied: rust needs to know the scratches it creeps out from.
        chosen: Dict[str, Dict[str, Any]] = {}
        for effect in EFFECTS:
            spec = value.get(effect)
            if spec is None:
                continue
            if float(rng.random()) >= float(spec["probability"]):
                continue
            kw = {k: v for k, v in spec.items() if k not in ("probability", "seed") and v is not None}
            if "colors" in kw:  # ramp stops {position, color} -> (position, (r, g, b))
                kw["colors"] = sorted((float(c["position"]), tuple(float(x) for x in c["color"])) for c in kw["colors"])
            seed = spec.get("seed")
            kw["seed"] = int(seed) if seed is not None else int(rng.integers(0, 1 << 31))
            chosen[effect] = kw
        mats = list(materials)
        for effect, kw in chosen.items():
            extra: Dict[str, Any] = {}
            if effect == "rust" and "scratches" in chosen:
                extra["scratch_lines"] = {k: v for k, v in chosen["scratches"].items() if k in LINE_KEYS}
            mats = getattr(wear, effect)(ctx.scene, mats, **kw, **extra)
        return mats, chosen


register(Wear())
