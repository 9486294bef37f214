"""Shared by the surface conditions (wet, snow): their materials wrap the frame's materials,
each one, so that every model keeps its own (as the wear randomizer does), and the labels,
which never see materials, stay exact."""
from __future__ import annotations

from typing import Callable, Dict, Optional

from . import WeatherContext

__all__ = ["wrap_surfaces"]


def wrap_surfaces(ctx: WeatherContext, ground: Optional[Callable[[int], int]],
                  objects: Optional[Callable[[int], int]]) -> Dict[str, int]:
    """Replaces the ground's material by ``ground(its material)`` and every material of every
    object of the frame by ``objects(material)`` (a model with materials of its own: each one,
    as a per-instance material map). A material several objects share is wrapped once. A
    ground that catches shadows (a photo's, a backplate's) is left as it is, and so are the
    unlabelled posts under signs and plates. Returns how many were wrapped."""
    r = ctx.renderer
    scene = r.scene
    n = {"ground": 0, "materials": 0}
    if ground is not None and r.ground is not None and r.photos is None and r.ground_material is not None \
            and not scene.instance_catcher(r.ground):
        scene.set_instance_material(r.ground, int(ground(r.ground_material)))
        n["ground"] = 1
    if objects is None:
        return n
    done: Dict[int, int] = {}

    def wrap(m: int) -> int:
        if m not in done:
            done[m] = int(objects(int(m)))
        return done[m]

    for o in r.objects:
        if o.materials:
            scene.set_instance_material_map(o.instance, {k: wrap(m) for k, m in o.materials.items()})
            r.mapped.add(o.instance)  # the next frame resets the map (FrameRenderer._set_material_map)
        elif o.material >= 0:
            scene.set_instance_material(o.instance, wrap(o.material))
    n["materials"] = len(done)
    return n

