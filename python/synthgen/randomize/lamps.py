"""Randomizer ``lamps``: a vehicle's lamps switched on or off -- headlamps (low or high beam),
tail lamps, brake lamps, indicators -- at the positions its library entry declares (``lamps``
in assets_manifest; the lenses are part of the vehicle's mesh, unlit until this randomizer
lights them).

A lit lens is an area emitter (the ``emissive`` material, diffuse-reflecting its lens colour
too) whose luminance is that of the real lamp kind, averaged over its lens (ECE R112 / R7 / R6
luminous intensities over typical lens areas): low beam 1e5 cd/m^2, high beam 4e5, tail lamps
800, brake lamps 8000, indicators 6000. Radiance follows the ``sky`` light's units (luminance /
683 lm/W per linear sRGB channel) times ``strength``: give the lamps the sky's ``strength`` and
they keep their proportion to daylight -- a brake lamp shows by day, a tail lamp hardly, a
headlamp glares; at night (a dim sky or environment) they are what lights the scene's
vehicles. A model without a brake lamp of its own has combined tail / brake lamps: braking
brightens its tail lamps. Indicators blink: ``indicators`` says which are lit in the frame
(a ``choice`` with ``off`` models the blinking). What was lit, and where each lamp is in the
image (centre, box, whether it faces the camera unoccluded), goes into the metadata: key
points for night-scene datasets (see :func:`project_lamps`)."""
from __future__ import annotations

from typing import Any, Dict, List, Mapping, Optional, Tuple

import numpy as np

from ..schema.fields import Bool, Choice, Number, Record
from ..schema.random import R
from ..scene.vehicles import LAMP_KINDS
from . import ModelParts, ObjectContext, Randomizer, register

#: Luminance of a lit lens (cd/m^2), by kind and state.
LUMINANCE = {"head.low": 1.0e5, "head.high": 4.0e5, "tail": 800.0, "brake": 8000.0, "indicator": 6000.0}

#: NOTE: Rec. 709 luminance weights of linear sRGB; radiance = colour / Y(colour) x L / 683
#: (the photometric efficacy, lm/W), as the sky light's units (cpp/light/sky.cpp).
_Y = np.array([0.2126, 0.7152, 0.0722])

SCHEMA = Record({
    "head": R(Choice(["off", "low", "high"], "low", doc="headlamps: off, low or high beam")),
    "tail": R(Bool(True, doc="tail (position) lamps lit")),
    "brake": R(Bool(False, doc="brake lamps lit (a model without brake lamps brightens its tail lamps)")),
    "indicators": R(Choice(["off", "left", "right", "hazard"], "off",
                           doc="indicators lit in this frame: left, right or both (hazard); they blink, so a "
                               "choice with off models a turning vehicle")),
    "strength": R(Number(1.0, min=0.0, max=1.0e6, doc="scale of the lamps' radiance, as the sky's strength "
                                                      "(give both the same to keep lamps and daylight in "
                                                      "proportion)")),
}, default=None, doc="a vehicle's lamps lit or not (head, tail, brake, indicators) at the positions its library "
                     "entry declares; what was lit and where each lamp is in the image go into the metadata")


def sky_units(colour: Any, luminance: float, strength: float) -> List[float]:
    """Linear sRGB radiance of a light of ``colour`` at ``luminance`` (cd/m^2; or cd, or lx, for
    intensities and illuminances) in the sky light's units, times ``strength``."""
    c = np.asarray(colour, np.float64)
    return [float(v) for v in c / float(c @ _Y) * float(luminance) / 683.0 * float(strength)]


def lit_lamps(lamps: Mapping[str, Mapping[str, Any]], value: Mapping[str, Any]) -> Dict[str, str]:
    """{lamp name: luminance key} of the lamps ``value`` lights (a lamp not in it is unlit)."""
    kinds = {v["kind"] for v in lamps.values()}
    out: Dict[str, str] = {}
    for name, lamp in lamps.items():
        kind, side = lamp["kind"], lamp["side"]
        key = None
        if kind == "head" and value["head"] != "off":
            key = f"head.{value['head']}"
        elif kind == "tail":
            if value["brake"] and "brake" not in kinds:
                key = "brake"
            elif value["tail"]:
                key = "tail"
        elif kind == "brake" and value["brake"]:
            key = "brake"
        elif kind.startswith("indicator"):
            ind = value["indicators"]
            if ind == "hazard" or (ind == side and side != "centre"):
                key = "indicator"
        if key is not None:
            out[name] = key
    return out


class Lamps(Randomizer):
    key = "lamps"
    schema = SCHEMA
    sample_order = 26
    apply_order = 26  # after the plates, before decals and wear (dirt on lenses too)

    def needs(self, parts: ModelParts) -> Optional[str]:
        if not parts.lamps:
            return "its model declares no lamps (a library vehicle's `lamps` in assets_manifest)"
        return None

    def apply(self, ctx: ObjectContext, value: Mapping[str, Any], materials: List[int]) -> Tuple[List[int], Any]:
        self.refuse(ctx, materials)
        lit = lit_lamps(ctx.lamps, value)
        emitters: Dict[Tuple[str, str], int] = {}
        swap: Dict[int, int] = {}
        for name, key in lit.items():
            kind = ctx.lamps[name]["kind"]
            if (kind, key) not in emitters:
                info = LAMP_KINDS[kind]
                radiance = sky_units(info["light"], LUMINANCE[key], value["strength"])
                emitters[(kind, key)] = ctx.scene.add_material("emissive", {
                    "radiance": radiance, "albedo": list(info["lens"])})
            swap[ctx.lamp_material[name]] = emitters[(kind, key)]
        out = [swap.get(m, m) for m in materials]
        return out, {"head": value["head"], "tail": bool(value["tail"]), "brake": bool(value["brake"]),
                     "indicators": value["indicators"], "strength": float(value["strength"]),
                     "lit": sorted(lit)}


register(Lamps())


def project_lamps(info: Mapping[str, Any], lamps: Mapping[str, Mapping[str, Any]], world_from_object: np.ndarray,
                  camera: Any, depth: Optional[np.ndarray] = None) -> List[Dict[str, Any]]:
    """Where a vehicle's lamps are in the image: per lamp, its name, kind, side, whether it is
    lit, its centre and box (pixels, the projection of its lens's corners), and whether it is
    seen (its lens faces the camera and the depth buffer at its centre is the lens's, within
    3 cm: nothing in front of it). Lamps behind the camera are left out."""
    from ..outputs.render import image_points

    cam_from_object = np.linalg.inv(np.asarray(camera.world_from_camera, np.float64)) @ \
        np.asarray(world_from_object, np.float64)
    lit = set(info.get("lit", ()))
    out = []
    for name in sorted(lamps):
        lamp = lamps[name]
        pts = np.vstack([np.asarray(lamp["centre"], np.float64)[None], np.asarray(lamp["corners"], np.float64)])
        uv, z = image_points(camera, world_from_object, pts)
        if (z <= 0).any():
            continue
        # Facing the camera: the lens's outward normal against the direction to the camera.
        centre_cam = (cam_from_object @ np.r_[pts[0], 1.0])[:3]
        n_cam = cam_from_object[:3, :3] @ np.asarray(lamp["normal"], np.float64)
        seen = bool(n_cam @ (-centre_cam) > 0.0)
        if seen and depth is not None:
            u, v = int(uv[0, 0]), int(uv[0, 1])
            h, w = depth.shape
            seen = 0 <= u < w and 0 <= v < h and abs(float(depth[v, u]) - float(z[0])) < 0.03
        out.append({"name": name, "kind": lamp["kind"], "side": lamp["side"], "lit": name in lit,
                    "centre": [round(float(uv[0, 0]), 2), round(float(uv[0, 1]), 2)],
                    "bbox": [round(float(uv[1:, 0].min()), 2), round(float(uv[1:, 1].min()), 2),
                             round(float(uv[1:, 0].max()), 2), round(float(uv[1:, 1].max()), 2)],
                    "visible": bool(seen)})
    return out
