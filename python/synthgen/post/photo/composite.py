"""Compositing a differential render into a photo (shadow catcher).

A scene whose real-world stand-ins (the photo's ground, proxy geometry) are catchers
(``Scene.set_instance_catcher``) renders, per pixel and with the same samples
(``RenderResult``):

* ``synthetic_rgb`` O and ``synthetic_alpha`` a: samples whose camera ray first hit an inserted
  object (premultiplied);
* ``catcher_with`` W: the other samples' radiance with the inserted objects;
* ``catcher_without`` Wo: the same samples' radiance without them;
* ``behind_synthetic`` B: the synthetic samples' radiance without them (what they hide).

Paths that never meet an inserted object are the same paths in both scenes, so W == Wo bit for
bit wherever the objects have no influence, and both modes return the photo's own values there.

Modes, with P the linear photo:

* ``ratio`` (Cycles' shadow catcher): ``O + P * W / (Wo + B)``. The photo is scaled by how much
  of the light the objects leave (shadows darken, reflections brighten); the catcher's own
  albedo cancels, so a rough guess of the ground's material suffices. Where the render without
  the objects is black (Wo + B == 0) the objects' light is added instead.
* ``additive`` (Debevec 1998, "differential rendering"): ``O + (1 - a) P + (W - Wo)``. Needs the
  catcher's material to match the photo's (the difference is in absolute radiance); clamped at 0.

NOTE: with P the render without the objects (a converged one), the ratio composite is an
unbiased estimate of the full render up to the ratio of two correlated estimates: E[O] + P W/(Wo+B)
with P = E[Wo + B]; the additive one is exact in expectation outside object edges.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from ...schema.errors import SynthgenError

__all__ = ["composite", "MODES", "influence_mask"]

MODES = ("ratio", "additive")


def _buffers(render: Mapping[str, np.ndarray] | object):
    get = render.get if isinstance(render, Mapping) else (lambda k: getattr(render, k))
    out = []
    for k in ("synthetic_rgb", "synthetic_alpha", "catcher_with", "catcher_without", "behind_synthetic"):
        v = get(k)
        if v is None:
            raise SynthgenError(f"composite: the render has no '{k}' (a scene without catchers does not render "
                                "differentially: mark the ground with Scene.set_instance_catcher)")
        out.append(np.asarray(v, np.float32))
    return out


def composite(photo: np.ndarray, render, mode: str = "ratio", exposure: float = 1.0) -> np.ndarray:
    """The photo (H x W x 3, linear float) with the render's inserted objects, their shadows and
    reflections. ``render``: a RenderResult or a mapping with its five differential buffers.
    ``exposure`` scales the render into the photo's units, one number or one per channel (white
    balance; radiance is linear in the lights, so this equals scaling every light); ratios are
    unchanged by it."""
    if mode not in MODES:
        raise SynthgenError(f"composite: mode '{mode}' is not one of {', '.join(MODES)}")
    O, a, W, Wo, B = _buffers(render)
    k = np.asarray(exposure, np.float32)
    if k.shape not in ((), (3,)) or not (np.all(np.isfinite(k)) and np.all(k > 0)):
        raise SynthgenError(f"composite: exposure must be a positive number or 3 of them, got {exposure}")
    P = np.asarray(photo, np.float32)
    if P.shape != W.shape:
        raise SynthgenError(f"composite: the photo is {P.shape[1]} x {P.shape[0]} but the render "
                            f"{W.shape[1]} x {W.shape[0]}")
    if mode == "additive":
        out = k * O + (np.float32(1.0) - a)[..., None] * P + k * (W - Wo)
        return np.maximum(out, 0.0).astype(np.float32)
    denom = Wo + B
    lit = denom > 0
    safe = np.where(lit, denom, np.float32(1.0))
    # NOTE: where the objects have no influence W == Wo and B == 0 bit for bit, so W / denom == 1
    # exactly and P * 1 == P: the photo's own values.
    ratio = np.where(lit, W / safe, (np.float32(1.0) - a)[..., None])
    out = k * O + P * ratio + np.where(lit, np.float32(0.0), k * W)
    return out.astype(np.float32)


def influence_mask(render) -> np.ndarray:
    """H x W bool: pixels the inserted objects change (object samples, shadows, reflections)."""
    O, a, W, Wo, B = _buffers(render)
    return (a > 0) | np.any(W != Wo, axis=2)
