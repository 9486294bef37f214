"""Wear presets on user extensions: :func:`rust` is :func:`synthgen.wear.rust` with its three
texture graphs (mask, colour, bump) replaced by the textures of the example extension
``rust.c`` (:func:`synthgen.scene.extensions.example`), one C function each. The same
parameters give the same image (tests/python/test_extensions.py); bench/extension_overhead.py
measures what the extension mechanism costs against the built-in graph. Loading compiles and
runs the example's code (extensions run with your rights; this one ships with synthgen).
"""
from __future__ import annotations

from typing import Any

from .._core import Scene, TextureRef
from . import extensions
from .wear import Base, _check, _mix, _threshold

__all__ = ["rust"]


def rust(scene: Scene, base: Base, *, seed: int = 0, amount: float = 0.35, scale: float = 3.0,
         bottom_bias: float = 0.6, bump: float = 0.002, edges: float = 1.0, edge_radius: float = 0.03,
         streaks: float = 0.5, stochastic: bool = True) -> Any:
    """Rust over ``base`` as :func:`synthgen.wear.rust` (Lambertian rust, the default colour
    ramp, no scratch lines), its textures computed by the ``rust`` example extension."""
    extensions.load_extension(extensions.example("rust"), scene=scene)
    amount = _check("amount", amount, 0.0, 1.0)
    args = {"scale": float(scale), "seed": int(seed), "bottom_bias": _check("bottom_bias", bottom_bias, 0.0, 2.0),
            "streaks": _check("streaks", streaks, 0.0, 4.0), "edges": _check("edges", edges, 0.0, 4.0)}
    if args["edges"] > 0.0:
        args["edge"] = TextureRef(scene.add_texture("edges", {"radius": float(edge_radius), "samples": 8}))
    if 0.0 < amount < 1.0:
        probe = scene.add_texture("rust_mask", args)
        t = _threshold(scene, probe, amount)
        scene.remove_texture(probe)
        mask = scene.add_texture("rust_mask", dict(args, threshold=t, softness=0.04))
    else:
        mask = scene.add_texture("constant", {"value": 1.0 if amount >= 1.0 else 0.0})
    color = scene.add_texture("rust_color", {"seed": int(seed) + 1})
    bump_tex = scene.add_texture("rust_bump", {"seed": int(seed) + 2})
    wear = scene.add_material("diffuse", {"albedo": TextureRef(color), "bump_map": TextureRef(bump_tex),
                                          "bump_scale": _check("bump", bump, 0.0, 0.05)})
    return _mix(scene, base, wear, mask, stochastic=bool(stochastic))
