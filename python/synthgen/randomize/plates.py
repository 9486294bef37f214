"""Randomizer ``plates``: licence plates on a vehicle, front and rear, at the mounting
rectangles its library entry declares (``plates`` in assets_manifest; the quads are part of the
vehicle's mesh, a blank plate until this randomizer gives them a registration). One random
valid registration per vehicle (as on a real car, the same front and rear); the texture is
drawn to the standard (:mod:`synthgen.scene.plates`). The text, and where each plate and each
of its characters is in the image, go into the metadata (for OCR datasets: see
:func:`project_plates`)."""
from __future__ import annotations

import math
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import TextureRef
from ..schema.fields import REQUIRED, Bool, Choice, Record, String
from ..schema.random import R
from ..scene import plates as P
from ..scene.vehicles import PLATE_MM
from . import ModelParts, ObjectContext, Randomizer, register

SCHEMA = Record({
    "country": R(Choice(list(P.COUNTRIES), REQUIRED,
                        doc="registration format and plate layout (ru: GOST R 50577, de: DIN 74069)")),
    "front": R(Bool(True, doc="a plate at the front mount too (some countries have rear plates only)")),
    "class": String(None, doc="label every visible plate with a box of this class too (COCO, YOLO, KITTI: plate-only "
                              "labels for plate detectors); default: none"),
}, default=None, doc="licence plates on a vehicle's front and rear mounts (its library entry declares them); the "
                     "registration, the plates' corners and every character's box in the image go into the metadata")

#: Texture resolution of vehicle plates (pixels per millimetre).
PX_PER_MM = 1.5


class Plates(Randomizer):
    key = "plates"
    schema = SCHEMA
    sample_order = 25
    apply_order = 25  # after a sign or a shape plate, before decals and wear (dirt on plates too)

    def needs(self, parts: ModelParts) -> Optional[str]:
        if not parts.plates:
            return "its model declares no plate mounts (a library vehicle's `plates` in assets_manifest)"
        return None

    def apply(self, ctx: ObjectContext, value: Mapping[str, Any], materials: List[int]) -> Tuple[List[int], Any]:
        self.refuse(ctx, materials)
        reg = P.random_registration(value["country"], ctx.rng)
        tex = P.render_plate(reg, px_per_mm=PX_PER_MM)
        linear = {"wrap": "clamp", "colorspace": "linear"}
        col = ctx.scene.add_image_texture(np.asarray(tex["rgb"], np.float32), linear)
        nrm = ctx.scene.add_image_texture(np.asarray(tex["normal"], np.float32), linear)
        mat = ctx.scene.add_material("principled", {"base_color": TextureRef(col), "normal_map": TextureRef(nrm),
                                                    "roughness": 0.35, "metallic": 0.0})
        # The mounts' placeholders get the registration (the same front and rear, as on a real
        # car); without a front plate, the front mount stays a blank plate holder.
        mounts = [m for m in ("front", "rear") if m in ctx.plates and (m == "rear" or value["front"])]
        swap = {ctx.plate_material[m]: mat for m in mounts}
        out = [swap.get(m, m) for m in materials]
        w_px, h_px = tex["rgb"].shape[1], tex["rgb"].shape[0]
        info = {"country": reg["country"], "text": reg["text"], "text_latin": tex["text_latin"],
                "mounts": mounts, "texture_size": [w_px, h_px],
                "characters": [{"char": c["char"], "bbox": c["bbox"]} for c in tex["characters"]]}
        if value.get("class"):
            info["class"] = value["class"]
        return out, info


register(Plates())


def project_plates(info: Mapping[str, Any], mounts: Mapping[str, np.ndarray], world_from_object: np.ndarray,
                   camera: Any, depth: Optional[np.ndarray] = None) -> List[Dict[str, Any]]:
    """Where a vehicle's plates are in the image: per mount, its corners (pixels: top left, top
    right, bottom right, bottom left), its box, and each character's box (the projection of its
    box on the plate texture) with whether it is seen (the depth buffer at the character's
    centre is the plate's, within 2 cm: nothing in front of it)."""
    from ..outputs.render import image_points

    w_px, h_px = info["texture_size"]
    out = []
    for name in info["mounts"]:
        q = np.asarray(mounts[name], np.float64)  # TL, TR, BR, BL in object space
        tl, tr, bl = q[0], q[1], q[3]

        def at(u: float, v: float) -> np.ndarray:
            """Object-space point of texture pixel coordinates (u right, v down)."""
            return tl + (tr - tl) * (u / w_px) + (bl - tl) * (v / h_px)

        def image(pts: Sequence[np.ndarray]) -> Tuple[np.ndarray, np.ndarray]:
            return image_points(camera, world_from_object, np.asarray(pts))

        corners, z = image(list(q))
        if (z <= 0).any():
            continue  # behind the camera
        chars = []
        for c in info["characters"]:
            x0, y0, x1, y1 = c["bbox"]
            uv, zc = image([at(x0, y0), at(x1, y0), at(x1, y1), at(x0, y1), at(0.5 * (x0 + x1), 0.5 * (y0 + y1))])
            box = [float(uv[:4, 0].min()), float(uv[:4, 1].min()), float(uv[:4, 0].max()), float(uv[:4, 1].max())]
            seen = True
            if depth is not None:
                u, v = int(uv[4, 0]), int(uv[4, 1])
                h, w = depth.shape
                if not (0 <= u < w and 0 <= v < h):
                    seen = False
                else:
                    # depth is along the camera's z (metres), as the renderer writes it.
                    seen = bool(abs(float(depth[v, u]) - float(zc[4])) < 0.02)
            chars.append({"char": c["char"], "bbox": [round(b, 2) for b in box], "visible": seen})
        out.append({"mount": name, "corners": [[round(float(a), 2), round(float(b), 2)] for a, b in corners],
                    "bbox": [round(float(corners[:, 0].min()), 2), round(float(corners[:, 1].min()), 2),
                             round(float(corners[:, 0].max()), 2), round(float(corners[:, 1].max()), 2)],
                    "characters": chars})
    return out


def plate_parts(info: Mapping[str, Any], mounts: Mapping[str, np.ndarray], world_from_object: np.ndarray,
                camera: Any, depth: np.ndarray, instance_id: np.ndarray, parent: Mapping[str, Any],
                class_name: str, class_id: int, level_from_world: np.ndarray) -> List[Dict[str, Any]]:
    """Plate-only labels (``plates: {class: ...}``): per mount with visible pixels, a record like
    an object's -- its class, box (x, y, w, h: the tight box of its visible pixels), visible
    pixels and their mask (COCO RLE), visible fraction, truncation, and its 3D box in KITTI's
    frame (height x width x thickness of the plate, bottom centre, facing its outward normal).
    Its visible pixels are exact from the first camera-ray hits: pixel centres inside the
    projected plate whose first hit is the vehicle (``instance_id``) at the plate's depth
    (``depth`` within 1 cm of the plate's plane along the pixel's ray)."""
    from ..outputs.coco import mask_bbox, rle_encode, rle_to_string
    from ..outputs.kitti import wrap_angle
    from ..outputs.render import image_points

    cfo = np.linalg.inv(np.asarray(camera.world_from_camera, np.float64)) @ np.asarray(world_from_object, np.float64)
    h_img, w_img = depth.shape
    out = []
    for name in info["mounts"]:
        q = np.asarray(mounts[name], np.float64)  # TL, TR, BR, BL (object space)
        uv, z = image_points(camera, world_from_object, q)
        if (z <= 0).any():
            continue
        c = (cfo @ np.c_[q, np.ones(4)].T)[:3]  # the corners in camera space, for the plate's plane
        # The plate's plane in camera space, n . X = n . c0.
        n = np.cross(c[:, 1] - c[:, 0], c[:, 3] - c[:, 0])
        n /= np.linalg.norm(n)
        d0 = float(n @ c[:, 0])
        x0, y0 = np.floor(uv.min(axis=0)).astype(int)
        x1, y1 = np.ceil(uv.max(axis=0)).astype(int)
        area = 0.5 * abs(float(np.dot(uv[:, 0], np.roll(uv[:, 1], 1)) - np.dot(uv[:, 1], np.roll(uv[:, 0], 1))))
        bx0, by0, bx1, by1 = max(x0, 0), max(y0, 0), min(x1, w_img), min(y1, h_img)
        mask = np.zeros((h_img, w_img), bool)
        inside_img = 0
        if bx1 > bx0 and by1 > by0:
            ys, xs = np.mgrid[by0:by1, bx0:bx1] + 0.5
            s = [(b[0] - a[0]) * (ys - a[1]) - (b[1] - a[1]) * (xs - a[0]) for a, b in zip(uv, np.roll(uv, -1, 0))]
            inside = np.all(np.stack(s) >= 0, axis=0) | np.all(np.stack(s) <= 0, axis=0)
            inside_img = int(inside.sum())
            rx, ry = (xs - camera.cx) / camera.fx, (ys - camera.cy) / camera.fy
            denom = n[0] * rx + n[1] * ry + n[2]
            z = np.where(np.abs(denom) > 1e-9, d0 / np.where(np.abs(denom) > 1e-9, denom, 1.0), np.inf)
            seen = inside & (instance_id[by0:by1, bx0:bx1] == parent["instance_id"]) & \
                (np.abs(depth[by0:by1, bx0:bx1] - z) < 0.01)
            mask[by0:by1, bx0:bx1] = seen
        vis = int(mask.sum())
        if vis == 0:
            continue
        rle = rle_encode(mask)
        # 3D: the plate's bottom centre, its size, and its outward normal as the heading.
        bottom = 0.5 * (q[2] + q[3])
        wfo = np.asarray(world_from_object, np.float64)
        loc = np.asarray(level_from_world, np.float64) @ (wfo @ np.r_[bottom, 1.0])
        normal_obj = np.cross(q[3] - q[0], q[1] - q[0])
        heading = np.asarray(level_from_world, np.float64)[:3, :3] @ (wfo[:3, :3] @ normal_obj)
        ry_ = math.atan2(-heading[2], heading[0])
        out.append({"class": class_name, "class_id": int(class_id), "parent_instance_id": int(parent["instance_id"]),
                    "mount": name, "corners": [[round(float(a), 2), round(float(b), 2)] for a, b in uv],
                    "bbox": mask_bbox(mask), "visible_pixels": vis,
                    "visible_fraction": float(min(1.0, vis / max(inside_img, 1))),
                    "truncation": float(max(0.0, 1.0 - inside_img / area)) if area > 0 else 1.0,
                    "mask": {"size": rle["size"], "counts": rle_to_string(rle["counts"])},
                    "dimensions_hwl": [PLATE_MM[1] / 1000.0, PLATE_MM[0] / 1000.0, 0.005],
                    "location_camera": [float(v) for v in loc[:3]], "rotation_y": float(wrap_angle(ry_)),
                    "alpha": float(wrap_angle(ry_ - math.atan2(loc[0], loc[2])))})
    return out
