"""The built-in demo scene: procedural primitives only (no files, no downloads).

A grey ground plane with spheres and boxes of car paint (coated), gold (rough
conductor), glass (dielectric), brushed aluminium (anisotropic conductor), green plastic
and white diffuse, lit by a physical sun and sky (Preetham 1999).
Class ids: 1 = ground, 2 = sphere, 3 = box; every object has its own instance id.
Renders 640x480 at 64 spp in a few seconds on two cores.

:data:`DEMO_SCENE` is in the scene file format; ``scenarios/demo_scene.yaml`` holds the
same description as YAML (a test checks that they agree).
"""
from __future__ import annotations

import copy
from typing import Any, Dict, Optional, Tuple

from .._core import Scene
from .scene_file import build_scene

__all__ = ["DEMO_SCENE", "demo_scene_dict", "build_demo_scene"]

#: Class ids used by the demo scene.
CLASSES = {1: "ground", 2: "sphere", 3: "box"}

DEMO_SCENE: Dict[str, Any] = {
    "version": 1,
    "description": "synthgen demo: metal, glass, car paint and plastic on a ground plane under a physical sun and sky",
    "camera": {
        "width": 640,
        "height": 480,
        "fov_y": 38.0,
        "look_at": {"eye": [0.6, 2.4, -7.0], "target": [0.0, 0.6, 0.6], "up": [0.0, 1.0, 0.0]},
    },
    "materials": {
        "ground": {"type": "diffuse", "albedo": [0.5, 0.48, 0.45]},
        "car_paint": {"type": "coated", "albedo": [0.75, 0.06, 0.05], "roughness": 0.08, "ior": 1.5},
        "gold": {"type": "conductor", "metal": "gold", "roughness": 0.18},
        "glass": {"type": "dielectric", "ior": 1.5, "roughness": 0.0},
        "white": {"type": "diffuse", "albedo": [0.82, 0.82, 0.8]},
        "green_plastic": {"type": "coated", "albedo": [0.15, 0.55, 0.2], "roughness": 0.35},
        "brushed_aluminium": {"type": "conductor", "metal": "aluminium", "roughness": 0.3, "anisotropy": 0.8},
    },
    "objects": [
        {"name": "ground", "primitive": "ground", "material": "ground", "class_id": 1},
        {"name": "car-paint sphere", "primitive": "sphere", "radius": 0.7, "translate": [-1.5, 0.7, 0.4],
         "material": "car_paint", "class_id": 2},
        {"name": "gold sphere", "primitive": "sphere", "radius": 0.45, "translate": [0.35, 0.45, -0.9],
         "material": "gold", "class_id": 2},
        {"name": "glass sphere", "primitive": "sphere", "radius": 0.9, "translate": [1.9, 0.9, 1.5],
         "material": "glass", "class_id": 2},
        {"name": "white box", "primitive": "box", "size": [1.0, 1.0, 1.0], "translate": [-0.1, 0.5, 1.7],
         "rotate": {"axis": [0.0, 1.0, 0.0], "angle": 25.0}, "material": "white", "class_id": 3},
        {"name": "plastic box", "primitive": "box", "size": [0.6, 1.6, 0.6], "translate": [-2.8, 0.8, 2.4],
         "rotate": {"axis": [0.0, 1.0, 0.0], "angle": -15.0}, "material": "green_plastic", "class_id": 3},
        {"name": "brushed metal box", "primitive": "box", "size": 0.5, "translate": [1.5, 0.25, -1.3],
         "rotate": {"euler": [0.0, 40.0, 0.0]}, "material": "brushed_aluminium", "class_id": 3},
    ],
    "lights": [
        {"name": "sun and sky", "type": "sky", "elevation": 35.0, "azimuth": 220.0, "turbidity": 2.5,
         "strength": 0.02},
    ],
    # clamp_indirect: the caustics of the glass and gold spheres as fireflies (docs/failure_modes.md).
    "render": {"spp": 64, "max_depth": 8, "rr_depth": 5, "seed": 0, "clamp_indirect": 3.0},
}


def demo_scene_dict(width: Optional[int] = None, height: Optional[int] = None, **render: Any) -> Dict[str, Any]:
    """A copy of :data:`DEMO_SCENE` with another image size (the vertical field of view
    is kept) and render settings overridden by keyword (``spp``, ``seed``, ...; None
    values are ignored)."""
    d = copy.deepcopy(DEMO_SCENE)
    if width is not None:
        d["camera"]["width"] = int(width)
    if height is not None:
        d["camera"]["height"] = int(height)
    d["render"].update({k: v for k, v in render.items() if v is not None})
    return d


def build_demo_scene(width: Optional[int] = None, height: Optional[int] = None,
                     **render: Any) -> Tuple[Scene, Dict[str, Any], Dict[str, Any]]:
    """Builds the demo scene: ``(scene, render_settings, meta)`` like
    :func:`synthgen.scene.scene_file.build_scene`; arguments as :func:`demo_scene_dict`."""
    scene, settings, meta = build_scene(demo_scene_dict(width, height, **render), source_name="<demo>")
    meta["classes"] = dict(CLASSES)
    return scene, settings, meta
