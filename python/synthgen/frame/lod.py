"""Levels of detail per frame: each shown library model that has them at the coarsest level
the frame allows (docs/geometry_lod.md; the error and its projection: synthgen.scene.lod)."""
from __future__ import annotations

from typing import Any, Dict, List, Mapping, Optional, Tuple

import numpy as np

from ..scene.lod import choose_level
from .layout import FrameView, amodal_masks, amodal_pixels
from .records import PlacedObject
from .resources import Shapes

__all__ = ["levels_of_detail", "amodal_and_levels"]


def amodal_and_levels(shapes: Shapes, view: FrameView, objects: List[PlacedObject], keep: List[bool], camera: Any,
                      rs: Mapping[str, Any]) -> Tuple[Dict[int, Tuple[int, int]], Optional[Dict[str, Any]]]:
    """The amodal pixels (layout.amodal_masks: all from one pass) of each shown labelled object,
    and the frame's :func:`levels_of_detail` by the render settings ``rs`` (the finest levels'
    amodal masks are what the coarser ones' are measured against)."""
    ks = [k for k in range(len(objects)) if keep[k] and objects[k].spec.labelled]
    found = amodal_masks(view, camera, ks, [k for k in ks if objects[k].shape.lod_meshes])
    masks = {k: v[2] for k, v in found.items() if len(v) > 2}
    return ({k: v[:2] for k, v in found.items()},
            levels_of_detail(shapes, view, objects, keep, camera, masks, rs["geometry_lod"], rs["geometry_lod_iou"]))


def levels_of_detail(shapes: Shapes, view: FrameView, objects: List[PlacedObject], keep: List[bool], camera: Any,
                     masks: Mapping[int, np.ndarray], max_px: float, min_iou: float) -> Optional[Dict[str, Any]]:
    """Each shown library model that has levels of detail at the coarsest whose geometric
    error projects under ``max_px`` (render.geometry_lod) pixels and, for a labelled object, whose
    amodal mask keeps an IoU of ``min_iou`` (render.geometry_lod_iou) or more with the finest level's
    (``masks``: those of the finest; each candidate level's rendered alone the same way,
    coarsest first). The layout was searched with the finest (synthgen.scene.lod). Returns
    what the levels saved, None when no such model is shown."""
    max_px, min_iou = float(max_px), float(min_iou)
    levels: Dict[str, int] = {}
    ious: Dict[str, float] = {}
    finest = used = finest_bytes = used_bytes = 0
    for k, o in enumerate(objects):
        shape = o.shape
        if not keep[k] or len(shape.lod_errors) < 2:
            continue
        level = choose_level(shape.lod_errors, o.world, shape.lo, shape.hi, camera, max_px)
        while level:
            mesh = shapes.level_mesh(shape, level)
            if mesh is None:  # a level that lost a lamp or plate mount: the next finer one
                level -= 1
                continue
            shapes.scene.set_instance_mesh(o.instance, mesh)
            if k not in masks:
                break
            coarse = amodal_pixels(view, camera, k, mask=True)[2]
            iou = float(np.count_nonzero(coarse & masks[k])) / max(1, np.count_nonzero(coarse | masks[k]))
            if iou >= min_iou:
                ious[str(k)] = round(iou, 4)
                break
            level -= 1
        if not level:
            shapes.scene.set_instance_mesh(o.instance, shape.mesh_id)
        levels[str(k)] = level
        finest += shape.lod_meshes[0][1]
        used += shape.lod_meshes[level][1]
        finest_bytes += shape.lod_meshes[0][2]
        used_bytes += shape.lod_meshes[level][2]
    if not levels:
        return None
    return {"max_error_px": max_px, "min_iou": min_iou, "levels": levels, "mask_iou": ious,
            "triangles_finest": finest, "triangles": used, "mesh_bytes_finest": finest_bytes, "mesh_bytes": used_bytes}
