"""Wear effects as material presets: rust, scratches, ice, snow, dirt (gravity and noise), and
the water film of wet surfaces (:func:`wet`).

Each function adds textures and materials to a :class:`synthgen.Scene` and returns the id of
a ``mix`` material that blends a wear material over ``base`` (a material id) with a procedural
mask (``base`` may be a list of material ids -- the materials of a multi-material model --:
the result is then the list of their mixes, sharing one mask and wear layer) -- the seed's equation (4-8), ``m(x) = (1 - mask(x)) m_base(x) + mask(x) m_wear(x)``.
Masks and wear colours use the procedural textures (``noise``, ``cellular``, ``gradient``,
``blend``; see docs/wear.md): 3D mappings, so models without uvs carry
wear too, band-limited by the ray footprint, deterministic for a given ``seed``.

Coverage parameters (``amount``) are calibrated: the mask threshold is the quantile of the
mask's own values over the object's relative-local unit cube that leaves ``amount`` of it
covered (computed with :meth:`Scene.texture_values` on a fixed point set).

Parameter ranges (checked): amounts in [0, 1]; scales > 0 (features per object extent for
relative mapping, per metre for object/world); roughness in [0, 1]; bump heights in metres
[0, 0.05].
"""
from __future__ import annotations

import os
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from .._core import Scene, SynthgenError, TextureRef

__all__ = ["rust", "scratches", "add_scratch_lines", "ice", "snow", "snow_layer", "wet", "wet_twin", "wet_ground",
           "dirt", "decal", "RUST_COLORS", "WATER_IOR", "SNOW_COLOR", "world_points"]

#: Colour ramp of rust (linear RGB): dark brown to orange (the seed's rust colour map).
RUST_COLORS = ((0.0, (0.05, 0.02, 0.01)), (0.35, (0.16, 0.05, 0.015)), (0.7, (0.42, 0.14, 0.03)),
               (1.0, (0.55, 0.25, 0.06)))


def _check(name: str, v: float, lo: float, hi: float) -> float:
    v = float(v)
    if not (lo <= v <= hi):
        raise SynthgenError(f"wear: '{name}' = {v} is out of range [{lo}, {hi}]")
    return v


def _ramp(colors: Sequence) -> Dict[str, Any]:
    return {"ramp_positions": [float(p) for p, _ in colors],
            "ramp_colors": [float(c) for _, rgb in colors for c in rgb]}


_CALIBRATION = np.random.default_rng(12345).random((4096, 3)).astype(np.float32)


def _threshold(scene: Scene, tex: int, amount: float, points: Optional[np.ndarray] = None) -> float:
    """Value t such that a fraction `amount` of the mask's raw values over the unit cube (or
    over ``points``: world-mapped masks, whose features are metres) exceeds t."""
    v = scene.texture_values(tex, _CALIBRATION if points is None else points)[:, 0]
    return float(np.quantile(v, 1.0 - amount)) if 0.0 < amount < 1.0 else (-1e9 if amount >= 1.0 else 1e9)


def _mask(scene: Scene, raw: Dict[str, Any], amount: float, softness: float,
          points: Optional[np.ndarray] = None) -> int:
    """A [0, 1] mask covering `amount` of the object (or of ``points``): the blend with
    parameters `raw` remapped around its calibrated threshold (soft edge of width `softness`
    in raw units).
    The remap goes into that blend itself (one texture lookup less per hit than a blend
    over it): the unshaped blend exists only while the threshold is calibrated."""
    if amount <= 0.0 or amount >= 1.0:
        # Nothing or everything: a constant mask (a threshold beyond the values would make the
        # remap's two ends equal in float precision).
        return scene.add_texture("constant", {"value": 1.0 if amount >= 1.0 else 0.0})
    probe = scene.add_texture("blend", raw)
    t = _threshold(scene, probe, amount, points)
    scene.remove_texture(probe)
    return scene.add_texture("blend", dict(raw, remap=[t - 0.5 * softness, t + 0.5 * softness], smooth=True))


Base = Union[int, Sequence[int]]


def _mix(scene: Scene, base: Base, wear: int, mask: int, stochastic: bool = False) -> Any:
    """The preset's result: ``wear`` over ``base`` weighted by ``mask``; a list of bases (the
    materials of a multi-material model) gives a list of mixes sharing the one mask and wear
    layer, so the model keeps its materials under the wear. ``stochastic``
    (rust, dirt: wear layers that are diffuse) shades secondary hits where the mask is
    fractional -- soft edges, and most indirect hits, whose footprints filter the mask to its
    mean -- with one material instead of two. Not for glossy wear layers (scratches, ice,
    decals): a rarely chosen glossy layer reflecting the sun would show as fireflies in
    indirect light."""
    if not isinstance(base, (int, np.integer)):
        return [_mix(scene, b, wear, mask, stochastic) for b in base]
    return scene.add_material("mix", {"material_a": int(base), "material_b": int(wear), "weight": TextureRef(mask),
                                      "stochastic": bool(stochastic)})


def rust(scene: Scene, base: Base, *, seed: int = 0, amount: float = 0.35, scale: float = 3.0,
         bottom_bias: float = 0.6, roughness: float = 0.85, bump: float = 0.002,
         colors: Sequence = RUST_COLORS, edges: float = 1.0, edge_radius: float = 0.03,
         streaks: float = 0.5, from_scratches: float = 1.0,
         scratch_lines: Optional[Mapping[str, Any]] = None, stochastic: bool = True) -> Any:
    """Rust over ``base``, as it grows on painted steel: it starts at convex edges and sheet
    borders, where paint is thinnest and chips first (the ``edges`` texture: short rays along
    the surface, ``edge_radius`` metres; weight ``edges``), spreads as an fBm front in
    relative-local coordinates (``scale`` features across the object), more towards the bottom
    (``bottom_bias``: 0 = none, 1 = strong), and runs down in vertical streaks (noise stretched
    along the object's height, weight ``streaks``), creeps out from scratches through the paint
    (``scratch_lines``: the line parameters of the scratches the object also gets, those of
    :func:`add_scratch_lines` -- the rust then follows those strokes, a halo four times their
    width, weight ``from_scratches``), covering ``amount`` of the object; the rust
    has a colour-ramp fBm and a turbulence bump of ``bump`` metres: Lambertian for ``roughness``
    >= 0.8 (the default 0.85), else a principled material of that roughness. ``stochastic``: the
    mix shades secondary hits where the mask is fractional with one material, chosen by the mask
    (cheaper, unbiased, noisier in reflections: docs/failure_modes.md); False blends both."""
    amount = _check("amount", amount, 0.0, 1.0)
    _check("scale", scale, 1e-3, 1e3)
    bottom_bias = _check("bottom_bias", bottom_bias, 0.0, 2.0)
    _check("roughness", roughness, 0.0, 1.0)
    _check("bump", bump, 0.0, 0.05)
    edges = _check("edges", edges, 0.0, 4.0)
    _check("edge_radius", edge_radius, 1e-4, 1.0)
    streaks = _check("streaks", streaks, 0.0, 4.0)
    from_scratches = _check("from_scratches", from_scratches, 0.0, 4.0)
    # Octave counts: the mask's shape is large-scale (4 octaves), colour and bump carry the
    # fine detail (4 and 3 octaves); each octave costs one noise evaluation per lookup.
    noise = scene.add_texture("noise", {"pattern": "fbm", "octaves": 4, "mapping": "relative", "scale": float(scale),
                                        "seed": int(seed), "remap": [-1.0, 1.0]})
    height = scene.add_texture("gradient", {"axis": "y", "mapping": "relative", "invert": True})
    raw: Dict[str, Any] = {"a": TextureRef(noise), "b": TextureRef(height), "op": "add", "factor": bottom_bias * 0.25}
    if streaks > 0.0:
        # Run-off: noise 12 times finer across than along the height (vertical streaks).
        run = scene.add_texture("noise", {"pattern": "fbm", "octaves": 3, "mapping": "relative",
                                          "scale": [float(scale) * 6.0, float(scale) * 0.5, float(scale) * 6.0],
                                          "seed": int(seed) + 3, "remap": [-1.0, 1.0]})
        raw = {"a": TextureRef(scene.add_texture("blend", raw)), "b": TextureRef(run), "op": "add",
               "factor": streaks * 0.3}
    if edges > 0.0:
        edge = scene.add_texture("edges", {"radius": float(edge_radius), "samples": 8})
        raw = {"a": TextureRef(scene.add_texture("blend", raw)), "b": TextureRef(edge), "op": "add",
               "factor": edges * 1.5}
    if scratch_lines is not None and from_scratches > 0.0:
        # Paint scratched to the steel rusts there first, and the rust creeps under the paint
        # on either side: the scratches' own strokes, four times as wide (a strokes texture's
        # profile is 1 on the centre line, so the halo is densest at the scratch).
        creep = add_scratch_lines(scene, **dict(scratch_lines, width=min(0.5, 4.0 * float(scratch_lines["width"]))))
        raw = {"a": TextureRef(scene.add_texture("blend", raw)), "b": TextureRef(creep), "op": "add",
               "factor": from_scratches * 1.5}
    mask = _mask(scene, raw, amount, 0.04)
    color = scene.add_texture("noise", dict({"pattern": "fbm", "octaves": 4, "mapping": "object", "scale": 12.0,
                                             "seed": int(seed) + 1, "remap": [-0.6, 0.6]}, **_ramp(colors)))
    bump_tex = scene.add_texture("noise", {"pattern": "turbulence", "octaves": 3, "mapping": "object", "scale": 40.0,
                                           "seed": int(seed) + 2})
    if roughness >= 0.8:
        # Very rough rust: Lambertian (a GGX lobe this rough adds little but costs a principled
        # evaluation per hit).
        wear = scene.add_material("diffuse", {"albedo": TextureRef(color), "bump_map": TextureRef(bump_tex),
                                              "bump_scale": float(bump)})
    else:
        wear = scene.add_material("principled", {"base_color": TextureRef(color), "roughness": float(roughness),
                                                 "metallic": 0.0, "bump_map": TextureRef(bump_tex),
                                                 "bump_scale": float(bump)})
    return _mix(scene, base, wear, mask, stochastic=bool(stochastic))


def add_scratch_lines(scene: Scene, *, seed: int = 0, density: float = 8.0, width: float = 0.04,
                      direction: Optional[str] = None, elongation: float = 8.0, style: str = "strokes",
                      spread: float = 12.0) -> int:
    """The texture of scratches' lines (see :func:`scratches`, whose parameters these are;
    :func:`rust` draws the same lines, wider, to creep out from them)."""
    if style not in ("strokes", "swirl", "cells"):
        raise SynthgenError(f"wear: 'style' must be strokes, swirl or cells, got {style!r}")
    axis = None
    if direction is not None:
        axis = {"x": 0, "y": 1, "z": 2}.get(str(direction))
        if axis is None:
            raise SynthgenError(f"wear: 'direction' must be x, y or z, got {direction!r}")
    if style == "cells":
        sc = [float(density)] * 3
        if axis is not None:
            sc[axis] = float(density) / float(elongation)
        return scene.add_texture("cellular", {"output": "f2_minus_f1", "mapping": "object", "scale": sc,
                                              "seed": int(seed), "remap": [0.0, width], "invert": True,
                                              "smooth": True})
    params: Dict[str, Any] = {"mode": "straight" if style == "strokes" else "swirl", "mapping": "object",
                              "scale": float(density), "seed": int(seed), "width": min(0.5, float(width)),
                              "density": 4}
    if style == "strokes":
        longest = min(2.0, max(0.1, float(elongation) / 8.0))
        params.update(length=[0.3 * longest, longest], spread=float(spread))
        if axis is not None:
            params["direction"] = [1.0 if i == axis else 0.0 for i in range(3)]
    return scene.add_texture("strokes", params)


def scratches(scene: Scene, base: Base, *, seed: int = 0, density: float = 8.0, width: float = 0.04,
              amount: float = 1.0, direction: Optional[Sequence[float]] = None, elongation: float = 8.0,
              metal: str = "aluminium", roughness: float = 0.35, depth: float = 0.0, style: str = "strokes",
              spread: float = 12.0, edges: float = 1.0, edge_radius: float = 0.03) -> Any:
    """Scratches through ``base`` down to bare metal, ``density`` cells per metre (object
    mapping), lines ``width`` of a cell wide. ``style``:

    - ``strokes`` (default): straight strokes of random length (up to ``elongation`` / 8 cells)
      and depth, tapering to their ends (the ``strokes`` texture); with ``direction`` ('x', 'y'
      or 'z') they run along that axis within ``spread`` degrees (a wiper, a brush, a key along
      a door), else in every direction;
    - ``swirl``: swirl marks, circular arcs around random centres in the surface's plane, as
      polishing leaves them on paint;
    - ``cells``: the former look, the edges of a cellular pattern (F2 - F1 below ``width``),
      stretched ``elongation`` times along ``direction``.

    ``amount`` < 1 keeps only a part, in clusters: where a noise plus ``edges`` times the
    ``edges`` texture (convex edges and borders within ``edge_radius`` metres: door edges,
    handles, bumper corners -- where keys, rings and stones hit) is highest. The scratch
    material is a rough ``metal`` conductor (changes albedo and roughness); with ``depth`` > 0
    (metres, [0, 0.01]) its shading normal follows the walls of a groove that deep (a bump map
    of the line profile)."""
    _check("density", density, 1e-3, 1e4)
    width = _check("width", width, 1e-4, 1.0)
    amount = _check("amount", amount, 0.0, 1.0)
    _check("elongation", elongation, 1.0, 100.0)
    _check("roughness", roughness, 0.0, 1.0)
    depth = _check("depth", depth, 0.0, 0.01)
    spread = _check("spread", spread, 0.0, 90.0)
    edges = _check("edges", edges, 0.0, 4.0)
    _check("edge_radius", edge_radius, 1e-4, 1.0)
    lines = add_scratch_lines(scene, seed=seed, density=density, width=width, direction=direction,
                              elongation=elongation, style=style, spread=spread)
    mask = lines
    if amount < 1.0:
        sel = scene.add_texture("noise", {"pattern": "fbm", "mapping": "object", "scale": float(density) / 4.0,
                                          "seed": int(seed) + 7})
        raw: Dict[str, Any] = {"a": TextureRef(sel), "b": 0.0, "op": "add"}
        if edges > 0.0:
            edge = scene.add_texture("edges", {"radius": float(edge_radius), "samples": 8})
            raw = {"a": TextureRef(sel), "b": TextureRef(edge), "op": "add", "factor": edges}
        keep = _mask(scene, raw, amount, 0.02)
        mask = scene.add_texture("blend", {"a": TextureRef(lines), "b": TextureRef(keep), "op": "multiply",
                                           "factor": 1.0})
    mparams: Dict[str, Any] = {"metal": metal, "roughness": float(roughness)}
    if depth > 0.0:
        # Height = -depth x the line profile (1 at the groove's centre line, 0 beyond `width`).
        mparams.update(bump_map=TextureRef(lines), bump_scale=-depth)
    wear = scene.add_material("conductor", mparams)
    return _mix(scene, base, wear, mask)


def ice(scene: Scene, base: Base, *, seed: int = 0, amount: float = 0.5, scale: float = 4.0,
        bump: float = 0.003, top_bias: float = 0.5, softness: float = 0.25) -> Any:
    """Ice / frost over ``base``: a white glossy layer (principled, clearcoat 1, roughness
    0.15) with a turbulence bump of ``bump`` metres, where an fBm mask (relative mapping,
    ``scale``, biased towards the top by ``top_bias``) covers ``amount`` of the object, thinning
    out over ``softness`` (mask units) at its edges, as frost does (not a sharp-edged patch)."""
    amount = _check("amount", amount, 0.0, 1.0)
    _check("scale", scale, 1e-3, 1e3)
    _check("bump", bump, 0.0, 0.05)
    top_bias = _check("top_bias", top_bias, 0.0, 2.0)
    softness = _check("softness", softness, 0.01, 2.0)
    noise = scene.add_texture("noise", {"pattern": "fbm", "mapping": "relative", "scale": float(scale),
                                        "seed": int(seed), "remap": [-1.0, 1.0]})
    height = scene.add_texture("gradient", {"axis": "y", "mapping": "relative"})
    mask = _mask(scene, {"a": TextureRef(noise), "b": TextureRef(height), "op": "add", "factor": top_bias * 0.25},
                 amount, softness)
    bump_tex = scene.add_texture("noise", {"pattern": "turbulence", "mapping": "object", "scale": 60.0,
                                           "seed": int(seed) + 3})
    wear = scene.add_material("principled", {"base_color": [0.85, 0.9, 0.95], "roughness": 0.15, "clearcoat": 1.0,
                                             "bump_map": TextureRef(bump_tex), "bump_scale": float(bump)})
    return _mix(scene, base, wear, mask)


#: Refractive index of water: the film of wet surfaces, puddles.
WATER_IOR = 1.33

#: Fresh snow's albedo (linear RGB): 0.8-0.9 in the visible, a little less towards the red
#: (Warren 1982, "Optical properties of snow", Reviews of Geophysics 20(1), fig. 9).
SNOW_COLOR = (0.8, 0.84, 0.88)


def world_points(feature: float, n: int = 4096, seed: int = 12345, flat: bool = False) -> np.ndarray:
    """Points for calibrating the threshold of a world-mapped mask (features of ``feature``
    metres): uniform over a square of 32 features on a side, on the ground plane y = 0
    (``flat``) or in a cube, so that the quantiles see many features."""
    rng = np.random.default_rng(seed)
    p = (rng.random((n, 3)) - 0.5) * 32.0 * float(feature)
    if flat:
        p[:, 1] = 0.0
    return p.astype(np.float32)


def snow_layer(scene: Scene, *, seed: int = 0, amount: float = 0.85, scale: float = 1.5,
               max_slope: float = 45.0, color: Sequence[float] = SNOW_COLOR, bump: float = 0.004,
               softness: float = 0.15) -> Tuple[int, int]:
    """(snow material, its mask texture) of :func:`snow`, to lay over many materials."""
    amount = _check("amount", amount, 0.0, 1.0)
    _check("scale", scale, 1e-3, 1e3)
    max_slope = _check("max_slope", max_slope, 0.0, 90.0)
    _check("bump", bump, 0.0, 0.05)
    softness = _check("softness", softness, 0.01, 2.0)
    lo, hi = np.radians(min(90.0, max_slope + 10.0)), np.radians(max(0.0, max_slope - 10.0))
    facing = scene.add_texture("facing", {"remap": [float(np.cos(lo)), float(np.cos(hi))], "smooth": True})
    noise = scene.add_texture("noise", {"pattern": "fbm", "octaves": 4, "mapping": "world",
                                        "scale": 1.0 / float(scale), "seed": int(seed), "remap": [-1.0, 1.0]})
    patches = _mask(scene, {"a": TextureRef(noise), "b": 0.0, "op": "add"}, amount, softness,
                    world_points(scale))
    mask = scene.add_texture("blend", {"a": TextureRef(facing), "b": TextureRef(patches), "op": "multiply",
                                       "factor": 1.0})
    col = [float(c) for c in color]
    grain = scene.add_texture("noise", {"pattern": "fbm", "octaves": 3, "mapping": "world", "scale": 4.0,
                                        "seed": int(seed) + 1, "remap": [-1.0, 1.0],
                                        "ramp_positions": [0.0, 1.0],
                                        "ramp_colors": [0.9 * c for c in col] + col})
    params: Dict[str, Any] = {"albedo": TextureRef(grain)}
    if bump > 0.0:
        relief = scene.add_texture("noise", {"pattern": "turbulence", "octaves": 3, "mapping": "world",
                                             "scale": 8.0, "seed": int(seed) + 2})
        params.update(bump_map=TextureRef(relief), bump_scale=float(bump))
    return scene.add_material("diffuse", params), mask


def snow(scene: Scene, base: Base, *, seed: int = 0, amount: float = 0.85, scale: float = 1.5,
         max_slope: float = 45.0, color: Sequence[float] = SNOW_COLOR, bump: float = 0.004,
         softness: float = 0.15) -> Any:
    """Snow over ``base``: it lies on surfaces that face up and slides off steep ones -- the
    ``facing`` texture (the shading normal's up component in world space), 1 on faces within
    ``max_slope`` - 10 degrees of horizontal, 0 beyond ``max_slope`` + 10, smooth between --
    in patches: an fBm of features ``scale`` metres in world coordinates (patches run on from the
    ground onto objects) covering ``amount`` of the up-facing area, thinning out over
    ``softness`` (mask units). Snow is a white Lambertian ``color`` (fresh snow reflects 80-90%
    of visible light, diffusely: no specular glare; Warren 1982) varied by a faint noise (its
    grain, drifts) with a turbulence bump of ``bump`` metres. Extends :func:`ice` (frost: a glossy
    film anywhere) to what falls and settles."""
    wear, mask = snow_layer(scene, seed=seed, amount=amount, scale=scale, max_slope=max_slope, color=color,
                            bump=bump, softness=softness)
    return _mix(scene, base, wear, mask)


def _given(v: Any) -> Any:
    """A material parameter as material_info gives it, for add_material (texture references)."""
    if isinstance(v, tuple) and len(v) == 2 and v[0] == "texture":
        return TextureRef(int(v[1]))
    return v


#: Internal reflectance of diffuse light at a water-air interface, 1 - (1 - F_dr,ext) / n^2
#: with F_dr,ext = 0.066 for n = 1.33 (Lekner & Dorf 1988, eq. 3).
_WATER_F_INT = 1.0 - (1.0 - 0.066) / WATER_IOR ** 2


def wet_twin(scene: Scene, material: int, *, roughness: float = 0.05) -> Optional[int]:
    """The wet look of an existing material (by id; its textures are kept), or None for
    materials a film does not change here (metals, glass, emitters, cut-outs, mixes).

    A water film over a rough surface darkens it and adds a smooth reflection of its own:
    light enters the film, is reflected diffusely by the surface below, and of what travels back
    up more than half is reflected down again at the water-air interface (total internal
    reflection beyond 49 degrees), to be absorbed in part at the next bounce (Lekner & Dorf
    1988, "Why some things are darker when wet", Applied Optics 27(7); Jensen, Legakis & Dorsey
    1999, "Rendering of wet materials"). The ``coated`` material is exactly that model (a clear
    coat of index ``ior`` over a Lambertian base with the inter-reflections summed), so:

    - ``diffuse`` -> ``coated`` of the same albedo under a water film (ior 1.33, ``roughness``);
    - ``coated`` (paint, plastic: not porous, water beads on it) -> the same, its coat at most
      ``roughness`` rough;
    - ``principled`` (dielectric parts) -> the same with a clear coat of ``roughness`` and the
      base colour darkened by the film's factor (1 - F_int) / (1 - a F_int) (a = 0.3) in
      proportion to its roughness (rough = porous; smooth ones keep their colour).
    """
    _check("roughness", roughness, 0.0, 1.0)
    info = scene.material_info(int(material))
    kind, p = info["type"], {k: _given(v) for k, v in info["params"].items()}
    if kind == "diffuse":
        if "alpha" in p:
            return None
        return scene.add_material("coated", {"albedo": p.get("albedo", 0.5), "ior": WATER_IOR,
                                             "roughness": float(roughness), "specular": 1.0})
    if kind == "coated":
        q = dict(p, roughness=min(float(p.get("roughness", 0.0)), float(roughness)))
        return scene.add_material("coated", q)
    if kind == "principled":
        if "alpha" in p or float(p.get("transmission", 0.0)) > 0.0 or p.get("alpha_mode", "blend") != "blend":
            return None
        rough = p.get("roughness", 0.5)
        rough = float(rough) if not isinstance(rough, TextureRef) else 0.5
        metal = p.get("metallic", 0.0)
        metal = float(metal) if not isinstance(metal, TextureRef) else 0.0
        if "metallic_roughness" in p:
            rough, metal = 0.5, 0.0
        a = 0.3
        k = 1.0 - rough * (1.0 - metal) * (1.0 - (1.0 - _WATER_F_INT) / (1.0 - a * _WATER_F_INT))
        color = p.get("base_color", [0.8, 0.8, 0.8])
        if isinstance(color, TextureRef):
            color = TextureRef(scene.add_texture("blend", {"a": color, "b": [k, k, k], "op": "multiply",
                                                           "factor": 1.0}))
        else:
            color = [float(c) * k for c in (color if isinstance(color, (list, tuple)) else [color] * 3)]
        coat = float(roughness)
        if float(p.get("clearcoat", 0.0)) > 0.0:  # a clear coat of its own: the smoother of the two
            coat = min(coat, float(p.get("clearcoat_roughness", 0.03)))
        q = dict(p, base_color=color, clearcoat=1.0, clearcoat_roughness=coat)
        return scene.add_material("principled", q)
    return None


def wet(scene: Scene, base: Base, *, wetness: Union[float, int, TextureRef] = 1.0, roughness: float = 0.05) -> Any:
    """``base`` under a water film (:func:`wet_twin`) where ``wetness`` (a constant in [0, 1] or
    a mask texture) says: the mix of the dry and the wet material. A list of bases gives the
    list of their mixes; materials without a wet look stay as they are."""
    if not isinstance(base, (int, np.integer)):
        return [wet(scene, b, wetness=wetness, roughness=roughness) for b in base]
    if not isinstance(wetness, TextureRef):
        wetness = _check("wetness", wetness, 0.0, 1.0)
        if wetness == 0.0:
            return int(base)
    twin = wet_twin(scene, int(base), roughness=roughness)
    if twin is None:
        return int(base)
    return scene.add_material("mix", {"material_a": int(base), "material_b": int(twin), "weight": wetness})


def wet_ground(scene: Scene, base: int, *, seed: int = 0, wetness: float = 0.9, roughness: float = 0.1,
               puddles: float = 0.1, puddle_scale: float = 3.0) -> int:
    """A wet ground over ``base`` (its material id): a water film (:func:`wet_twin`, ``roughness``)
    over the fraction ``wetness`` of it in fBm patches (features 2 ``puddle_scale`` metres: a
    drying road is wet in blotches), and puddles over the fraction ``puddles``: the low end of
    another fBm of features ``puddle_scale`` metres, flat water with a mirror surface (the film
    with roughness 0: it reflects the sky, the objects and the lights) and a wet rim (the film
    wherever that noise covers twice the puddles' share). World mapping on the plane y = 0;
    both shares are calibrated over it. The base unchanged when it has no wet look."""
    wetness = _check("wetness", wetness, 0.0, 1.0)
    puddles = _check("puddles", puddles, 0.0, 1.0)
    _check("puddle_scale", puddle_scale, 1e-2, 1e3)
    film = wet_twin(scene, int(base), roughness=roughness)
    if film is None:
        return int(base)
    pts = world_points(2.0 * puddle_scale, flat=True)
    cover = scene.add_texture("noise", {"pattern": "fbm", "octaves": 4, "mapping": "world",
                                        "scale": 0.5 / float(puddle_scale), "seed": int(seed), "remap": [-1.0, 1.0]})
    wet_mask = _mask(scene, {"a": TextureRef(cover), "b": 0.0, "op": "add"}, wetness, 0.3, pts)
    out = int(base)
    if puddles > 0.0:
        water = scene.add_texture("noise", {"pattern": "fbm", "octaves": 5, "mapping": "world",
                                            "scale": 1.0 / float(puddle_scale), "seed": int(seed) + 1,
                                            "remap": [-1.0, 1.0]})
        raw = {"a": TextureRef(water), "b": 0.0, "op": "add"}
        rim = _mask(scene, raw, min(1.0, 2.0 * puddles), 0.05, pts)
        wet_mask = scene.add_texture("blend", {"a": TextureRef(wet_mask), "b": TextureRef(rim), "op": "max",
                                               "factor": 1.0})
    if wetness > 0.0 or puddles > 0.0:
        out = scene.add_material("mix", {"material_a": out, "material_b": int(film), "weight": TextureRef(wet_mask)})
    if puddles > 0.0:
        pool = wet_twin(scene, int(base), roughness=0.0)
        puddle = _mask(scene, raw, puddles, 0.02, pts)
        out = scene.add_material("mix", {"material_a": out, "material_b": int(pool), "weight": TextureRef(puddle)})
    return int(out)


def dirt(scene: Scene, base: Base, *, seed: int = 0, amount: float = 0.4, scale: float = 5.0,
         bottom_bias: float = 1.0, ao_radius: float = 0.3, ao_weight: float = 1.0,
         color: Sequence[float] = (0.12, 0.09, 0.06), roughness: float = 0.95, splash: float = 1.0,
         wheels: Sequence[float] = (), softness: float = 0.3, stochastic: bool = True) -> Any:
    """Dirt on ``base``, as road grime settles: a film that is densest low on the body and thins
    with height (relative-local height, ``bottom_bias``), gathers in creases and corners (1 - AO
    from 4 rays of ``ao_radius`` metres at the shading point, ``ao_weight``), is splashed up by
    the wheels (``splash``: fine droplets, densest low and at the wheels' positions along the
    body, ``wheels``: relative positions along the object's x, e.g. its axles; none: the whole
    length), varies softly over the body (fBm, ``scale``) with soft edges (``softness``, in
    mask units: a film, not blobs), and is darker in creases (its colour times 0.55 + 0.45 AO).
    ``amount`` is the fraction covered in the open (AO 1), creases get more. The dirt is a rough
    principled material of ``color``. ``stochastic``: as for :func:`rust`."""
    amount = _check("amount", amount, 0.0, 1.0)
    _check("scale", scale, 1e-3, 1e3)
    bottom_bias = _check("bottom_bias", bottom_bias, 0.0, 4.0)
    _check("ao_radius", ao_radius, 1e-4, 100.0)
    ao_weight = _check("ao_weight", ao_weight, 0.0, 4.0)
    splash = _check("splash", splash, 0.0, 4.0)
    softness = _check("softness", softness, 0.01, 2.0)
    noise = scene.add_texture("noise", {"pattern": "fbm", "octaves": 3, "mapping": "relative", "scale": float(scale),
                                        "seed": int(seed), "remap": [-1.0, 1.0]})
    height = scene.add_texture("gradient", {"axis": "y", "mapping": "relative", "invert": True})
    raw: Dict[str, Any] = {"a": TextureRef(noise), "b": TextureRef(height), "op": "add", "factor": bottom_bias * 0.25}
    if splash > 0.0:
        # Droplets thrown up by the wheels: fine noise, weighted by the height (squared: they
        # fall back within a wheel's height) and, along the body, by the wheels' positions.
        drops = scene.add_texture("noise", {"pattern": "plain", "mapping": "relative", "scale": float(scale) * 12.0,
                                            "seed": int(seed) + 5, "remap": [-1.0, 1.0]})
        low = scene.add_texture("gradient", {"axis": "y", "mapping": "relative", "invert": True, "remap": [0.5, 1.0],
                                             "smooth": True})
        weight = TextureRef(low)
        if len(wheels):
            pos, col = [0.0], [0.25]
            for w in sorted(float(np.clip(v, 0.0, 1.0)) for v in wheels):
                for p_, c_ in ((w - 0.15, 0.25), (w, 1.0), (w + 0.15, 0.25)):
                    if pos[-1] < p_ < 1.0:
                        pos.append(p_)
                        col.append(c_)
            pos.append(1.0)
            col.append(0.25)
            along = scene.add_texture("gradient", {"axis": "x", "mapping": "relative", "ramp_positions": pos,
                                                   "ramp_colors": [c for c_ in col for c in (c_, c_, c_)]})
            weight = TextureRef(scene.add_texture("blend", {"a": TextureRef(low), "b": TextureRef(along),
                                                            "op": "multiply", "factor": 1.0}))
        spl = scene.add_texture("blend", {"a": TextureRef(drops), "b": weight, "op": "multiply", "factor": 1.0})
        raw = {"a": TextureRef(scene.add_texture("blend", raw)), "b": TextureRef(spl), "op": "add",
               "factor": splash * 0.35}
    ao_open = None
    if ao_weight > 0.0:
        occl = scene.add_texture("ao", {"radius": float(ao_radius), "samples": 4, "invert": True})  # 1 - AO
        raw = {"a": TextureRef(scene.add_texture("blend", raw)), "b": TextureRef(occl), "op": "add",
               "factor": ao_weight * 0.5}
        ao_open = scene.add_texture("ao", {"radius": float(ao_radius), "samples": 4})
    mask = _mask(scene, raw, amount, softness)
    col = [float(c) for c in color]
    if ao_open is not None:
        # Darker in creases: the colour times 0.55 + 0.45 AO.
        shade = scene.add_texture("blend", {"a": [0.55 * c for c in col], "b": col, "op": "mix",
                                            "factor": TextureRef(ao_open)})
        wear = scene.add_material("principled", {"base_color": TextureRef(shade), "roughness": float(roughness)})
    else:
        wear = scene.add_material("principled", {"base_color": col, "roughness": float(roughness)})
    return _mix(scene, base, wear, mask, stochastic=bool(stochastic))


def decal(scene: Scene, base: Base, image: Union[str, os.PathLike, np.ndarray], *, position: Sequence[float],
          look_at: Sequence[float], up: Sequence[float] = (0.0, 1.0, 0.0), fov: float = 20.0, aspect: float = 1.0,
          occlusion: bool = True, depth_resolution: int = 512, roughness: float = 0.4, space: str = "world",
          facing: Optional[bool] = None) -> Any:
    """An image (sticker, graffiti, stripes, a plate; a file or an array of linear values)
    projected onto ``base`` by a pinhole
    projector at ``position`` looking at ``look_at`` (vertical ``fov`` degrees, width/height
    ``aspect``), for models with no or unusable uvs. Returns a mix of ``base`` and a principled
    decal material weighted by the projector's frustum mask. With ``occlusion`` the scene as it
    is now is rendered (depth only) from the projector into a shadow map (an in-memory
    texture), so surfaces hidden from the projector stay clean; move nothing in front of the
    projector afterwards.
    ``space="object"`` puts the projector in the object space of the instances using the
    material (it moves with them; no shadow-map test then). With ``facing`` (default: in
    object space) only surfaces whose normal faces the projector receive the decal: it stays
    off the far side of an object (exact for convex objects with outward normals; surfaces that
    face the projector but are hidden behind other parts of a concave object are still
    painted; single-sided sheets whose normal points away lose the decal)."""
    if space not in ("world", "object"):
        raise SynthgenError(f"wear: 'space' must be world or object, got {space!r}")
    if space == "object":
        occlusion = False
    if facing is None:
        facing = space == "object"
    from .._core import PinholeCamera

    _check("fov", fov, 0.1, 170.0)
    _check("aspect", aspect, 1e-3, 1e3)
    common = {"position": [float(v) for v in position], "look_at": [float(v) for v in look_at],
              "up": [float(v) for v in up], "fov": float(fov), "width": float(aspect), "height": 1.0,
              "space": space, "facing": bool(facing)}
    if occlusion:
        w = max(8, int(round(depth_resolution * aspect))) if aspect >= 1 else int(depth_resolution)
        h = max(8, int(round(w / aspect)))
        wfp = PinholeCamera.look_at(common["position"], common["look_at"], common["up"])
        previous = scene.camera
        scene.set_camera(PinholeCamera.from_fov(float(fov), w, h, wfp))
        try:
            depth = np.asarray(scene.render(spp=1, labels_only=True).depth, np.float32)
            depth = np.where(np.isfinite(depth), depth, np.float32(1e30))  # nothing seen: never occluded
        finally:
            scene.set_camera(previous)
        dm = scene.add_image_texture(depth, {"colorspace": "linear", "wrap": "clamp"})
        common["depth_map"] = TextureRef(dm)
    if isinstance(image, np.ndarray):
        img = scene.add_image_texture(image, {"wrap": "clamp"})
    else:
        img = scene.add_texture("image", {"file": os.fspath(image), "wrap": "clamp"})
    color = scene.add_texture("projector", dict(common, texture=TextureRef(img)))
    mask = scene.add_texture("projector", dict(common, texture=TextureRef(img), output="mask"))
    sticker = scene.add_material("principled", {"base_color": TextureRef(color), "roughness": float(roughness)})
    return _mix(scene, base, sticker, mask)
