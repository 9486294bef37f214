"""Weather ``rain`` (group precipitation): falling rain as an image-space step after the render
(synthgen.post.rain, also a ``post:`` step of its own): motion-blurred streaks of the drops
between the camera and the scene -- their number, sizes and speeds from the rain rate
(Marshall-Palmer; terminal velocities), their length from the exposure, their brightness from
the environment the drops refract (Garg & Nayar 2006, "Photorealistic rendering of rain
streaks"), drawn only where they are nearer than the surface the pixel sees -- and the veil of
the rain beyond them. Rain is not an object: labels (instances, classes, depth) are the
render's. Deterministic: the streaks come from the condition's own generator. Pair it with
``wet`` (group surface) for wet roads under the rain."""
from __future__ import annotations

from typing import Any, Dict, Mapping

import numpy as np

from ...post.rain import rain_streaks
from ...schema.fields import Number, Record
from ...schema.random import R
from . import Condition, WeatherContext, register


class Rain(Condition):
    key = "rain"
    group = "precipitation"
    order = 0
    doc = "rain streaks and the rain's veil (an image-space step; labels unchanged)"
    schema = Record({
        "rate": R(Number(10.0, min=0.0, max=500.0, doc="rain rate, mm/h (drizzle 1, moderate 5-10, heavy 20-50)")),
        "exposure": R(Number(0.004, min=1e-5, max=1.0, doc="the camera's exposure time, s (the streaks' length)")),
        "wind": R(Number(0.0, min=-50.0, max=50.0, doc="wind across the view, m/s (positive: to the right)")),
        "brightness": R(Number(1.0, min=0.0, max=100.0, doc="drop radiance / the environment's (the mean of the "
                                                            "image's brightest 10%)")),
        "veil": R(Number(1.0, min=0.0, max=100.0, doc="scales the rain's extinction beyond the streaks "
                                                      "(0: no veil)")),
    })

    def params(self, value: Mapping[str, Any]) -> Dict[str, Any]:
        return {k: float(value[k]) for k in ("rate", "exposure", "wind", "brightness", "veil")}

    def post(self, ctx: WeatherContext, arrays: Dict[str, np.ndarray], params: Mapping[str, Any]
             ) -> Dict[str, np.ndarray]:
        camera = ctx.renderer.scene.camera
        out = dict(arrays)
        out["rgb"], info = rain_streaks(arrays["rgb"], arrays["depth"], ctx.rng, fx=camera.fx, fy=camera.fy,
                                        cx=camera.cx, cy=camera.cy,
                                        world_from_camera=np.asarray(camera.world_from_camera), **params)
        ctx.extra.update(drops=info["drops"], extinction=info["extinction"])
        return out


register(Rain())
