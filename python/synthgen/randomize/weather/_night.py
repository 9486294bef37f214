"""Shared by the light conditions ``dusk`` and ``night`` (the time of day): the frame's lights
replaced by

- the sky with the sun below the horizon (the ``twilight`` light: USNO's measured twilight
  illuminance, a glow over the sun, a blue zenith, the night sky and a city's sky glow; the
  ``sky`` light for a sun still above it), keeping the scenario's sun azimuth;
- the vehicles' lamps switched on (``lamps`` values for every vehicle whose model declares
  lamps and whose scenario entry gives none) and a ``headlamp`` beam at each lit headlamp,
  aimed along the vehicle;
- street lights along the road: ``spot`` lights pointing down from unlabelled poles (class 0)
  with a lit lens, every ``spacing`` metres on one or both sides;
- the moon (night), a 0.52-degree disc of the illuminance Krisciunas & Schaefer give;

all in the ``sky`` light's units (luminance / 683 lm/W per linear sRGB channel, times the
sky's ``strength``), so lamps and daylight keep their proportion. The frame's exposure is
chosen like a camera's auto-exposure (a metering pre-pass at a quarter of the resolution:
the log-average luminance mapped to ``key``) or given in EV; it is the condition's
image-space step and is recorded in the metadata with the metered scene's EV100."""
from __future__ import annotations

import math
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from ...post.exposure import metering_pass
from ...schema.fields import EMPTY, Bool, Choice, Number, Record
from ...schema.random import R
from ..lamps import sky_units
from . import Condition, WeatherContext

#: NOTE: Rec. 709 luminance weights of linear sRGB; radiance = colour / Y(colour) x L / 683,
#: the sky's units (cpp/light/sky.cpp), as the lamps randomizer's.
_Y = np.array([0.2126, 0.7152, 0.0722])
LM_PER_W = 683.0
#: The sky's strength when the scenario has no sky light to take it from (the daylight
#: scenarios' sky strength: a clear day in display range).
DEFAULT_STRENGTH = 0.02
#: Peak luminous intensity of a headlamp (cd): low beam (UN ECE R112 requires at least
#: 10.1 kcd at its 75R test point; 10-20 kcd is typical) and high beam (R113: tens of kcd).
HEADLAMP_CD = {"low": 15000.0, "high": 45000.0}
#: Street lamps: correlated colour temperature (K) of a high-pressure sodium and a white LED lamp.
STREET_CCT = {"sodium": 2000.0, "led": 4000.0}
#: Moonlight's colour temperature (K): sunlight reddened by the Moon's reflectance.
MOON_CCT = 4100.0
#: Street light luminaire: its lens (metres, along and across the arm), and the share of the
#: spot's intensity the lit lens adds straight down: it is there to be seen (80 cd/m^2 for a
#: 5000 cd lamp: white at any night or dusk exposure), the spot does the lighting. All lenses
#: are one emitter (one light to weigh per shading point, not one per street light), found
#: mostly by BSDF sampling: a larger share would be noise under the lamps.
LENS_SIZE = (0.5, 0.25)
LENS_SHARE = 0.002


def cct_rgb(kelvin: float) -> List[float]:
    """Linear sRGB of a Planckian radiator at ``kelvin``, its luminance normalised to 1.
    NOTE: the Planckian locus' chromaticity by the cubic fits of B. Kang et al., "Design of
    advanced color temperature control system for HDTV applications", J. Korean Phys. Soc.
    41(6), 2002 (1667-25000 K); XYZ -> linear sRGB by the IEC 61966-2-1 matrix."""
    t = float(kelvin)
    if t <= 4000.0:
        x = -0.2661239e9 / t ** 3 - 0.2343589e6 / t ** 2 + 0.8776956e3 / t + 0.179910
    else:
        x = -3.0258469e9 / t ** 3 + 2.1070379e6 / t ** 2 + 0.2226347e3 / t + 0.240390
    if t <= 2222.0:
        y = -1.1063814 * x ** 3 - 1.34811020 * x ** 2 + 2.18555832 * x - 0.20219683
    elif t <= 4000.0:
        y = -0.9549476 * x ** 3 - 1.37418593 * x ** 2 + 2.09137015 * x - 0.16748867
    else:
        y = 3.0817580 * x ** 3 - 5.87338670 * x ** 2 + 3.75112997 * x - 0.37001483
    xyz = np.array([x / y, 1.0, (1.0 - x - y) / y])
    m = np.array([[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560],
                  [0.0556434, -0.2040259, 1.0572252]])
    rgb = np.maximum(m @ xyz, 0.0)
    return [float(c) for c in rgb / float(rgb @ _Y)]


def moon_illuminance(elevation: float, phase: float) -> float:
    """Illuminance (lx) on a surface facing the Moon at ``elevation`` degrees with the
    illuminated ``phase`` fraction (1: full).
    NOTE: K. Krisciunas, B. E. Schaefer, "A model of the brightness of moonlight", PASP 103
    (1991): outside the atmosphere I* = 10^(-0.4 (3.84 + 0.026 |a| + 4e-9 a^4)) foot-candles
    (eq. 20; a the phase angle in degrees, 0.31 lx at full moon: -12.7 mag at 2.54e-6 lx per
    0 mag), dimmed by 10^(-0.4 k X), k = 0.172 mag per air mass, X = (1 - 0.96 sin^2 Z)^-1/2
    (eqs. 2-3)."""
    if elevation <= 0.0 or phase <= 0.0:
        return 0.0
    a = math.degrees(math.acos(max(-1.0, min(1.0, 2.0 * float(phase) - 1.0))))
    fc = 10.0 ** (-0.4 * (3.84 + 0.026 * a + 4e-9 * a ** 4))
    z = math.radians(90.0 - float(elevation))
    airmass = 1.0 / math.sqrt(1.0 - 0.96 * math.sin(z) ** 2)
    return fc * 10.7639 * 10.0 ** (-0.4 * 0.172 * airmass)


def time_of_day_schema(elevation: Mapping[str, Any], sky_glow: Any, key: float, moon: bool) -> Record:
    """The parameters of a time of day (every leaf a distribution), with the condition's own
    defaults: the sun's elevation, the sky glow, the auto-exposure key, whether a moon."""
    fields: Dict[str, Any] = {
        "elevation": R(Number(min=-90.0, max=5.0, doc="sun elevation in degrees (0 sunset; -6, -12, -18 the ends of "
                                                      "civil, nautical, astronomical twilight; above 0: the day sky)"),
                       default=dict(elevation)),
        "azimuth": R(Number(None, doc="sun compass bearing in degrees (the sky's convention); default: the "
                                      "scenario's sky or sun, else drawn uniformly")),
        "turbidity": R(Number(3.0, min=1.7, max=10.0, doc="the day sky's turbidity at sunset (the twilight sky "
                                                          "hands over from it)")),
        "strength": R(Number(None, min=0.0, doc="scale of every light's radiance, as the sky's strength; default: "
                                                "the scenario's sky's, else 0.02")),
        "sky_glow": R(Number(None, min=0.0, doc="artificial sky glow at the zenith, cd/m^2 (a city's light "
                                                "pollution; the natural night sky is 1.7e-4)"),
                      default=sky_glow),
        "lamps": Record({
            "head": R(Choice(["off", "low", "high"], "low", doc="vehicles' headlamps (where their scenario entry "
                                                               "gives no lamps)")),
            "high_beam": R(Number(0.1, min=0.0, max=1.0, doc="share of those vehicles on high beam instead "
                                                            "(drawn per vehicle)")),
            "tail": R(Bool(True, doc="tail lamps lit")),
            "beams": R(Bool(True, doc="a headlamp beam (the headlamp light) at every lit headlamp")),
            "intensity": R(Number(HEADLAMP_CD["low"], min=0.0, doc="a low beam's peak intensity, cd (ECE R112: "
                                                                   "10-20 kcd); high beams 3 x")),
        }, default=EMPTY, doc="the vehicles' lamps: models that declare lamps (assets_manifest) light them"),
        "street_lights": Record({
            "enabled": R(Bool(True, doc="street lights along the road")),
            "spacing": R(Number(30.0, min=5.0, doc="metres between street lights along the road")),
            "sides": R(Choice(["both", "one", "staggered"], "both", doc="both sides of the road, one (the left "
                                                                        "seen along it) or alternating")),
            "offset": R(Number(6.0, min=0.5, doc="distance of the poles from the road's centre line, metres")),
            "height": R(Number(8.0, min=3.0, max=20.0, doc="mounting height of the lamps, metres")),
            "intensity": R(Number(5000.0, min=0.0, doc="luminous intensity of a lamp towards the road, cd "
                                                       "(2000-10000)")),
            "lamp": R(Choice(["sodium", "led"], "sodium", doc="high-pressure sodium (2000 K) or white LED (4000 K); "
                                                              "the sky glow takes its colour")),
            "road_yaw": R(Number(0.0, doc="the road's direction, degrees about +y as objects' yaw (0: along +x)")),
            "road_offset": R(Number(0.0, doc="the centre line's lateral position, metres")),
            "range": R(Number(90.0, min=0.0, doc="street lights within this distance along the road from the "
                                                 "camera")),
            "poles": R(Bool(True, doc="poles and luminaires as geometry (unlabelled, class 0)")),
        }, default=EMPTY, doc="street lights: spot lights pointing down from poles along the road"),
        "exposure": Record({
            "ev": R(Number(None, min=-40.0, max=40.0, doc="exposure in stops (the image x 2^ev); default: "
                                                          "auto-exposure")),
            "key": R(Number(key, min=0.001, max=1.0, doc="auto-exposure: the log-average luminance the frame is "
                                                         "exposed to (0.18 mid-grey; lower keeps night dark)")),
        }, default=EMPTY, doc="the frame's exposure: like a camera's auto-exposure, or given in EV"),
    }
    if moon:
        fields["moon"] = Record({
            "probability": Number(0.3, min=0.0, max=1.0, doc="chance that the moon is up"),
            "elevation": R(Number(min=0.0, max=90.0, doc="the moon's elevation, degrees"),
                           default={"uniform": [10.0, 60.0]}),
            "azimuth": R(Number(min=-360.0, max=720.0, doc="the moon's compass bearing, degrees"),
                         default={"uniform": [0.0, 360.0]}),
            "phase": R(Number(min=0.0, max=1.0, doc="illuminated fraction (1: full moon)"),
                       default={"uniform": [0.3, 1.0]}),
        }, default=EMPTY, doc="the moon: a disc light of Krisciunas & Schaefer's illuminance")
    return Record(fields)


def _light_param(lights: Sequence[Any], name: str) -> Optional[float]:
    """A parameter of the frame's sky (or sun) light: (type, params) pairs or PluginSpecs."""
    for li in lights:
        kind, params = (li.type, li.params) if hasattr(li, "type") else li
        if kind == "sky" or (kind == "sun" and name == "azimuth"):
            if name in params:
                return float(params[name])
            if kind == "sun" and "direction" in params:
                d = params["direction"]
                return math.degrees(math.atan2(float(d[0]), -float(d[2]))) % 360.0
            return {"strength": 1.0, "azimuth": 0.0}[name] if kind == "sky" else None
    return None


def strength_of(params: Mapping[str, Any], lights: Sequence[Any]) -> float:
    """The strength of the frame's lights: the condition's, else the scenario's sky's, else 0.02."""
    if params.get("strength") is not None:
        return float(params["strength"])
    s = _light_param(lights, "strength")
    return DEFAULT_STRENGTH if s is None else s


class TimeOfDay(Condition):
    """A time of day: the lights, lamps and exposure of dusk or night (module docstring)."""

    group = "light"
    exposes = True

    def check(self, value: Mapping[str, Any], spec: Mapping[str, Any], fail: Any, photos: Any = None) -> None:
        if spec.get("background") is not None:
            fail("not available with photo backgrounds: the photo has its own time of day")

    def object_values(self, params: Mapping[str, Any], spec: Any, obj: Any, shape: Any,
                      rng: np.random.Generator) -> Optional[Dict[str, Any]]:
        lamps = params["lamps"]
        if not getattr(shape, "lamps", None) or getattr(shape, "lamp_material", None) is None:
            return None
        head = lamps["head"]
        if head == "low" and float(rng.random()) < float(lamps["high_beam"]):
            head = "high"
        if head == "off" and not lamps["tail"]:
            return None
        return {"lamps": {"head": head, "tail": bool(lamps["tail"]), "brake": False, "indicators": "off",
                          "strength": strength_of(params, spec.lights)}}

    def apply(self, ctx: WeatherContext, params: Mapping[str, Any]) -> Optional[Dict[str, Any]]:
        r = ctx.renderer
        strength = strength_of(params, r.light_specs)
        azimuth = params.get("azimuth")
        if azimuth is None:
            azimuth = _light_param(r.light_specs, "azimuth")
        if azimuth is None:
            azimuth = float(ctx.rng.uniform(0.0, 360.0))
        elevation = float(params["elevation"])
        street = params["street_lights"]
        colour = cct_rgb(STREET_CCT[street["lamp"]])
        glow = float(params.get("sky_glow") or 0.0)
        lights: List[Tuple[str, Dict[str, Any]]] = []
        if elevation > 0.0:
            lights.append(("sky", {"elevation": elevation, "azimuth": azimuth, "turbidity": float(params["turbidity"]),
                                   "strength": strength}))
        else:
            lights.append(("twilight", {"elevation": elevation, "azimuth": azimuth,
                                        "turbidity": float(params["turbidity"]), "strength": strength,
                                        "sky_glow": glow, "glow_color": colour}))
        # What meta adds to the drawn parameters: the resolved azimuth and strength, what was lit.
        info: Dict[str, Any] = {"azimuth": float(azimuth), "strength": strength, "sky_light": lights[0][0]}
        info["moon_up"] = self._moon(ctx, params, strength, lights)
        info["headlamp_beams"] = _headlamps(r, params["lamps"], lights)
        info["street_light_count"] = _street_lights(ctx, street, strength, colour, lights)
        r.replace_lights(lights)
        info["exposure"] = _expose(ctx, params["exposure"], strength)
        return info

    def _moon(self, ctx: WeatherContext, params: Mapping[str, Any], strength: float,
              lights: List[Tuple[str, Dict[str, Any]]]) -> Optional[Dict[str, Any]]:
        moon = params.get("moon")
        if not moon or not float(ctx.rng.random()) < float(moon["probability"]):
            return None
        e = moon_illuminance(float(moon["elevation"]), float(moon["phase"]))
        if e <= 0.0:
            return None
        lights.append(("sun", {"elevation": float(moon["elevation"]), "azimuth": float(moon["azimuth"]),
                               "irradiance": sky_units(cct_rgb(MOON_CCT), e, strength), "angular_diameter": 0.52}))
        return {"elevation": float(moon["elevation"]), "azimuth": float(moon["azimuth"]),
                "phase": float(moon["phase"]), "illuminance_lx": round(e, 6)}

    def post(self, ctx: WeatherContext, arrays: Dict[str, np.ndarray], params: Mapping[str, Any]
             ) -> Dict[str, np.ndarray]:
        if ctx.exposure == 1.0:
            return arrays
        out = dict(arrays)
        out["rgb"] = (np.asarray(arrays["rgb"], np.float32) * np.float32(ctx.exposure)).astype(np.float32)
        return out


def _headlamps(r: Any, lamps: Mapping[str, Any], lights: List[Tuple[str, Dict[str, Any]]]) -> int:
    """A headlamp beam at each lit headlamp of the frame's visible vehicles; their count."""
    from ...scene.vehicles import AXES, LAMP_KINDS

    if not lamps["beams"]:
        return 0
    n = 0
    for o in r.objects:
        info = o.info.get("lamps")
        if o.world is None or not info or info.get("head", "off") == "off" or not r.scene.instance_visible(o.instance):
            continue
        world = np.asarray(o.world, np.float64)
        fwd = world[:3, :3] @ np.asarray(o.forward, np.float64)
        up = world[:3, :3] @ np.asarray(AXES[o.spec.up or o.shape.up or "+y"], np.float64)
        fwd, up = fwd / np.linalg.norm(fwd), up / np.linalg.norm(up)
        cd = float(lamps["intensity"]) * (3.0 if info["head"] == "high" else 1.0)
        intensity = sky_units(LAMP_KINDS["head"]["light"], cd, float(info.get("strength", 1.0)))
        for name in info.get("lit", ()):
            lamp = o.shape.lamps.get(name)
            if lamp is None or lamp["kind"] != "head":
                continue
            # The beam starts 5 cm in front of the lens (its light is not cut by the lens itself).
            pos = (world @ np.r_[np.asarray(lamp["centre"], np.float64), 1.0])[:3] + 0.05 * fwd
            lights.append(("headlamp", {"position": [float(v) for v in pos], "direction": [float(v) for v in fwd],
                                        "up": [float(v) for v in up], "intensity": intensity,
                                        "beam": "high" if info["head"] == "high" else "low"}))
            n += 1
    return n


def road_frame(street: Mapping[str, Any]) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(direction along the road, lateral direction, a point of the centre line), y up."""
    yaw = math.radians(float(street["road_yaw"]))
    u = np.array([math.cos(yaw), 0.0, -math.sin(yaw)])
    n = np.array([math.sin(yaw), 0.0, math.cos(yaw)])
    return u, n, float(street["road_offset"]) * n


def street_light_positions(street: Mapping[str, Any], camera_position: Sequence[float]
                           ) -> List[Tuple[np.ndarray, float]]:
    """(base of the pole on the ground, side: +1 or -1 along the lateral direction) of the street
    lights within ``range`` of the camera along the road: at multiples of ``spacing`` from the
    road's origin (so they stay in place as the camera moves)."""
    u, n, c0 = road_frame(street)
    spacing, offset = float(street["spacing"]), float(street["offset"])
    s_cam = float(np.dot(np.asarray(camera_position, np.float64) - c0, u))
    reach = float(street["range"])
    lo, hi = math.ceil((s_cam - reach) / spacing), math.floor((s_cam + reach) / spacing)
    out = []
    for k in range(int(lo), int(hi) + 1):
        sides = {"both": (1.0, -1.0), "one": (1.0,), "staggered": (1.0 if k % 2 == 0 else -1.0,)}[street["sides"]]
        for side in sides:
            out.append((c0 + k * spacing * u + side * offset * n, side))
    return out


def _street_lights(ctx: WeatherContext, street: Mapping[str, Any], strength: float, colour: List[float],
                   lights: List[Tuple[str, Dict[str, Any]]]) -> int:
    """Street lights: a spot light pointing down from each luminaire, and (``poles``) the pole, its
    arm, the luminaire and its lit lens as unlabelled geometry; a street light whose pole would
    stand within half a metre of a visible object's footprint is left out. Their count."""
    from ...scene import primitives as P

    if not street["enabled"] or ctx.camera is None:
        return 0
    r = ctx.renderer
    cam = np.asarray(ctx.camera.world_from_camera, np.float64)[:3, 3]
    u, n, _ = road_frame(street)
    h = float(street["height"])
    arm = min(2.0, 0.35 * float(street["offset"]))
    intensity = sky_units(colour, float(street["intensity"]), strength)
    # The lens: a Lambertian emitter facing down whose intensity straight down is LENS_SHARE of
    # the spot's (L = share x I / area).
    lens_l = sky_units(colour, LENS_SHARE * float(street["intensity"]) / (LENS_SIZE[0] * LENS_SIZE[1]), strength)
    kit = _StreetKit.of(r)
    obstacles = [(np.asarray(o.world, np.float64)[[0, 2], 3], float(o.radius)) for o in r.objects
                 if o.world is not None and r.scene.instance_visible(o.instance)]
    pool = r.weather_pool("street_lights")
    yaw = float(street["road_yaw"])
    turn = P.rotate([0.0, 1.0, 0.0], yaw).astype(np.float64)
    lenses: List[np.ndarray] = []
    count = 0
    for base, side in street_light_positions(street, cam):
        if any(np.hypot(*(base[[0, 2]] - c)) < rad + 0.5 for c, rad in obstacles):
            continue
        head = base - side * arm * n + np.array([0.0, h, 0.0])  # the luminaire over the road side of the pole
        # NOTE: a flat beam to 30 degrees from the nadir, fading out by 65: under the lamp the
        # road gets I / h^2 (78 lx for 5000 cd at 8 m), midway between lamps 30 m apart a tenth
        # of it -- the pools of light of sodium street lighting (cut-off luminaires, EN 13201's
        # uniformity U0 = E_min / E_mean of 0.2-0.4 on minor roads).
        lights.append(("spot", {"position": [float(v) for v in head - np.array([0.0, 0.03, 0.0])],
                                "direction": [0.0, -1.0, 0.0], "intensity": intensity,
                                "cone_angle": 65.0, "falloff_start": 30.0}))
        if street["poles"]:
            parts = [  # (mesh, material, centre, size along (road, up, lateral))
                (kit.box, kit.pole_material, base + np.array([0.0, 0.5 * h + 0.1, 0.0]), (0.16, h + 0.2, 0.16)),
                (kit.box, kit.pole_material, base + np.array([0.0, h + 0.14, 0.0]) - side * 0.5 * arm * n,
                 (0.08, 0.08, arm + 0.1)),
                (kit.box, kit.head_material, head + np.array([0.0, 0.07, 0.0]), (LENS_SIZE[1] + 0.06, 0.14,
                                                                                  LENS_SIZE[0] + 0.1)),
            ]
            for p, (mesh, mat, centre, size) in enumerate(parts):
                m = (P.translate(centre).astype(np.float64) @ turn @ P.scale(size).astype(np.float64))
                inst, existed = pool.take(3 * count + p, lambda: r.scene.add_instance(
                    mesh, np.eye(4), class_id=0, instance_id=0, material_id=mat))
                r.scene.set_instance_transform(inst, m.astype(np.float32))
                r.scene.set_instance_visible(inst, True)
            lens = turn[:3, :3] @ np.diag([LENS_SIZE[1], 1.0, LENS_SIZE[0]])
            lenses.append(head - np.array([0.0, 0.01, 0.0]) + _LENS_CORNERS @ lens.T)
        count += 1
    if lenses:
        kit.show_lenses(r, np.concatenate(lenses), lens_l)
    return count


#: A lens's corners in its own frame (a unit square at y = 0), wound to face down (-y).
_LENS_CORNERS = np.array([[-0.5, 0.0, -0.5], [0.5, 0.0, -0.5], [0.5, 0.0, 0.5], [-0.5, 0.0, 0.5]])


class _StreetKit:
    """A worker's meshes and materials of street lights (made once per renderer)."""

    def __init__(self, scene: Any):
        from ...scene import primitives as P

        b = P.box()
        self.box = scene.add_mesh(b["positions"], b["indices"], normals=b["normals"], uvs=b["uvs"], name="street box")
        self.pole_material = scene.add_material("coated", {"albedo": [0.32, 0.33, 0.34], "roughness": 0.4})
        self.head_material = scene.add_material("coated", {"albedo": [0.08, 0.08, 0.085], "roughness": 0.3})
        self.lens_material = scene.add_material("emissive", {"radiance": [0.0, 0.0, 0.0]})
        self.lens_mesh: Optional[int] = None

    def show_lenses(self, r: Any, corners: np.ndarray, radiance: List[float]) -> None:
        """Every lens of the frame (4 world corners each, facing down) as one mesh, lit."""
        k = len(corners) // 4
        quads = np.arange(4 * k, dtype=np.uint32).reshape(k, 4)
        # Wound clockwise seen from above: the triangles face down (-y), as their normals.
        idx = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.uint32)
        arrays = dict(positions=np.asarray(corners, np.float32), indices=idx,
                      normals=np.tile(np.array([[0.0, -1.0, 0.0]], np.float32), (4 * k, 1)))
        if self.lens_mesh is None:
            self.lens_mesh = r.scene.add_mesh(name="street lenses", **arrays)
        else:
            r.scene.update_mesh(self.lens_mesh, name="street lenses", **arrays)
        r.scene.update_material(self.lens_material, "emissive", {"radiance": radiance, "albedo": [0.6, 0.6, 0.6]})
        inst, _ = r.weather_pool("street_lenses").take(0, lambda: r.scene.add_instance(
            self.lens_mesh, np.eye(4), class_id=0, instance_id=0, material_id=self.lens_material))
        r.scene.set_instance_visible(inst, True)

    @classmethod
    def of(cls, r: Any) -> "_StreetKit":
        kit = getattr(r, "_street_kit", None)
        if kit is None:
            kit = r._street_kit = cls(r.scene)
        return kit


def meter(ctx: WeatherContext, quarter: int = 4, spp: int = 8) -> np.ndarray:
    """The frame's luminance (linear, the render's units) from a metering pre-pass: the camera
    at a quarter of the resolution, ``spp`` samples, the condition's lights, averaged over 2 x 2
    pixels (a camera's light meter; about 1.5% of a 32-spp render)."""
    r = ctx.renderer
    pre = metering_pass(r.scene, ctx.camera, ctx.seed, r.threads, quarter, spp)
    y = np.asarray(pre, np.float64)[..., :3] @ _Y
    hh, ww = (y.shape[0] // 2) * 2, (y.shape[1] // 2) * 2
    if hh and ww:
        y = y[:hh, :ww].reshape(hh // 2, 2, ww // 2, 2).mean(axis=(1, 3))
    return y


def auto_exposure(y: np.ndarray, key: float) -> Tuple[float, float]:
    """(ev, log-average) of an auto-exposure that maps the frame's log-average luminance to
    ``key``, unless that would push more than 3% of the frame past white.
    NOTE: the log-average (geometric mean) luminance as the scene's key, E. Reinhard et al.,
    "Photographic Tone Reproduction for Digital Images", SIGGRAPH 2002, eq. 1; each pixel
    floored at 1% of the median, so a black night sky does not drag the exposure up. The
    highlight limit (the 97th percentile at white) is a camera's highlight-weighted metering at
    night: the pools under street lamps stay below clipping, the lamps themselves (a few
    pixels) clip."""
    y = np.asarray(y, np.float64).ravel()
    floor = max(float(np.median(y)) * 0.01, 1e-30)
    log_avg = float(np.exp(np.mean(np.log(np.maximum(y, floor)))))
    ev = math.log2(float(key) / log_avg)
    high = float(np.percentile(y, 97.0))
    if high > 0.0:
        ev = min(ev, math.log2(1.0 / high))
    return ev, log_avg


def _expose(ctx: WeatherContext, exposure: Mapping[str, Any], strength: float) -> Dict[str, Any]:
    """Sets the frame's exposure (ctx.exposure = 2^ev): given, or metered; what meta records."""
    if exposure.get("ev") is not None:
        ev = float(exposure["ev"])
        ctx.exposure = 2.0 ** ev
        return {"ev": ev, "auto": False}
    y = meter(ctx)
    ev, log_avg = auto_exposure(y, float(exposure["key"]))
    ctx.exposure = 2.0 ** ev
    # NOTE: the metered scene's exposure value at ISO 100, EV100 = log2(L S / K), L the
    # log-average luminance in cd/m^2, S = 100, K = 12.5 (ISO 2720's reflected-light meter
    # calibration): a lit street at night is about -2 to 3, daylight 12 to 15.
    cd = log_avg * LM_PER_W / strength if strength > 0 else float("nan")
    return {"ev": round(ev, 6), "auto": True, "key": float(exposure["key"]),
            "scene_ev100": round(math.log2(cd * 100.0 / 12.5), 3) if cd > 0 else None}
