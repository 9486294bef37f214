"""Shared by the medium conditions: :class:`Layer`, whose medium is the ``homogeneous`` plugin (a
layer of constant density, cpp/medium/homogeneous.cpp) -- fog and haze; over photo backgrounds
the same layer in image space (Koschmieder's law from the photo's depth map) -- and
:class:`NoiseMedium`, a heterogeneous noise medium whose noise each frame draws anew -- ground fog
and clouds."""
from __future__ import annotations

from typing import Any, Dict, Mapping, Optional, Tuple

import numpy as np

from ...schema import distributions as D
from ...schema.fields import Number, Record
from ...schema.random import R
from . import Condition, WeatherContext


def refuse_photos(spec: Mapping[str, Any], fail: Any, what: str) -> None:
    """A medium rendered around the inserted objects only would not match the photo."""
    if spec.get("background") is not None:
        fail(f"not available with photo backgrounds: the photo has no {what} of its own, and a depth map does not "
             "say where it would be (fog and haze over photos are applied from their depth: docs/weather.md)")


def layer_schema(visibility: float, top: float, albedo: float, g: float) -> Record:
    """The layer's parameters, each value also a distribution."""
    return Record({
        "visibility": R(Number(visibility, min=0.0, min_open=True,
                               doc="meteorological visibility in metres (contrast 2% at this distance: extinction "
                                   "3.912 / visibility)")),
        "top": R(Number(top, doc="height of the layer's top in metres (clear air above)")),
        "albedo": R(Number(albedo, min=0.0, max=1.0, doc="single-scattering albedo")),
        "g": R(Number(g, min=-0.99, max=0.99, doc="Henyey-Greenstein asymmetry (> 0: forward scattering)")),
    })


def _highest(v: Any) -> float:
    """The largest value a number or a distribution over numbers may take."""
    if isinstance(v, D.Choice):
        return max(_highest(o) for o in v.options)
    if isinstance(v, (D.Uniform, D.IntUniform, D.LogUniform)):
        return float(np.max(v.hi))
    if isinstance(v, D.Normal):
        return float("inf") if v.hi is None else float(v.hi)
    if isinstance(v, D.Distribution):
        return float("inf")
    return float(v)


#: Why a layer whose top is at or below the ground does nothing.
_BELOW_GROUND = ("at or below the ground (y = 0, where the objects stand): the layer, from the ground up to top, "
                 "would hold nothing of the scene")


class Layer(Condition):
    """A homogeneous layer from the ground up to ``top``: the path-traced medium, or over a
    photo background Koschmieder's law in image space from the photo's depth map
    (synthgen.post.photo.fog), with the same extinction. A ``top`` at or below the ground
    (y = 0) is refused when no frame could draw one above it; a frame that draws one has no
    layer (:meth:`no_effect`)."""

    group = "medium"

    def check(self, value: Mapping[str, Any], spec: Mapping[str, Any], fail: Any, photos: Any = None) -> None:
        top = _highest(value["top"])
        if top <= 0.0:  # every frame would draw a layer below the ground
            what = "at most " if isinstance(value["top"], D.Distribution) else ""
            args = (getattr(value, "locs", {})["top"],) if "top" in getattr(value, "locs", {}) else ()
            fail(f"{what}{top:g} m, {_BELOW_GROUND}; give a top above 0 m (the layer's depth)", *args)
        if spec.get("background") is None or photos is None:
            return
        for i, path in enumerate(photos.paths):
            if photos.setup(i).depth is None:
                fail(f"over a photo background it needs the photo's depth map: {path} has none (its calibration's "
                     "'depth': the distance of what each pixel shows, from which the fog is applied to the photo "
                     "and the inserted objects alike; docs/weather.md)")

    def params(self, value: Mapping[str, Any]) -> Dict[str, Any]:
        return {k: float(value[k]) for k in ("visibility", "top", "albedo", "g")}

    def no_effect(self, params: Mapping[str, Any]) -> Optional[str]:
        if float(params["top"]) <= 0.0:
            return f"top {float(params['top']):.3g} m was drawn, {_BELOW_GROUND}: the frame has no {self.key}"
        return None

    def apply(self, ctx: WeatherContext, params: Mapping[str, Any]) -> Optional[Dict[str, Any]]:
        if ctx.photo is not None:
            return {"on_photo": "koschmieder"}  # image space, after the composite (post)
        ctx.renderer.scene.set_medium("homogeneous", dict(params))
        return None

    def post(self, ctx: WeatherContext, arrays: Dict[str, np.ndarray], params: Mapping[str, Any]
             ) -> Dict[str, np.ndarray]:
        """Over a photo: I = J t + A (1 - t), t = exp(-3.912 / visibility x the pixel's path in
        the layer), the path up to the composite's depth (the photo's depth map, the inserted
        objects' own where they show; where the photo's depth is unknown, the calibrated ground
        for rays that reach it, else the sky: the whole path); A from the photo's dark channel.
        Sets ``ctx.transmittance`` for the objects' weather labels."""
        if ctx.photo is None:
            return arrays
        from ...post.photo import fog

        camera = ctx.renderer.scene.camera
        depth = np.asarray(arrays["depth"], np.float64)
        dirs, per_z = fog.ray_directions(camera, depth.shape)
        origin_y = float(np.asarray(camera.world_from_camera, np.float64)[1, 3])
        dist = depth * per_z
        with np.errstate(divide="ignore", invalid="ignore"):
            ground = np.where(dirs[..., 1] < 0, -origin_y / dirs[..., 1], np.inf)
        dist = np.where(np.isfinite(dist), dist, ground)
        beta = 3.912 / float(params["visibility"])
        t = np.exp(-beta * fog.layer_path(origin_y, dirs[..., 1], dist, float(params["top"])))
        a = fog.airlight(ctx.photo.pixels)
        ctx.transmittance = t.astype(np.float32)
        ctx.extra.update(extinction=round(beta, 9), airlight=[round(float(v), 6) for v in a])
        out = dict(arrays)
        out["rgb"] = fog.koschmieder(arrays["rgb"], t, a)
        return out


class NoiseMedium(Condition):
    """A noise medium plugin (``plugin``: ground_fog, clouds) with the drawn values of ``keys``
    and a noise seed of the frame's own (recorded in meta). Not over photos (``what``: the
    medium's name in the error)."""

    group = "medium"
    plugin: str = ""
    keys: Tuple[str, ...] = ()
    what: str = ""

    def check(self, value: Mapping[str, Any], spec: Mapping[str, Any], fail: Any, photos: Any = None) -> None:
        refuse_photos(spec, fail, self.what)

    def params(self, value: Mapping[str, Any]) -> Dict[str, Any]:
        return {k: float(value[k]) for k in self.keys}

    def apply(self, ctx: WeatherContext, params: Mapping[str, Any]) -> Optional[Dict[str, Any]]:
        seed = int(ctx.rng.integers(0, 2 ** 31 - 1))
        ctx.renderer.scene.set_medium(self.plugin, {**dict(params), "seed": seed})
        return {"seed": seed}
