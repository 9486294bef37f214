"""Randomizer ``plates``: licence plates on a vehicle, front and rear, at the mounting
rectangles its library entry declares (``plates`` in assets_manifest; the quads are part of the
vehicle's mesh, a blank plate until this randomizer gives them a registration). One random
valid registration per vehicle (as on a real car, the same front and rear); the texture is
drawn to the standard (:mod:`synthgen.scene.plates`). The text, and where each plate and each
of its characters is in the image, go into the metadata (for OCR datasets: see
:func:`project_plates`)."""
from __future__ import annotations

from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import SynthgenError, TextureRef
from ..schema.fields import REQUIRED, Bool, Choice, Record
from ..schema.random import R
from ..scene import plates as P
from . import ObjectContext, Randomizer, register

SCHEMA = Record({
    "country": R(Choice(list(P.COUNTRIES), REQUIRED,
                        doc="registration format and plate layout (ru: GOST R 50577, de: DIN 74069)")),
    "front": R(Bool(True, doc="a plate at the front mount too (some countries have rear plates only)")),
}, default=None, doc="licence plates on a vehicle's front and rear mounts (its library entry declares them); the "
                     "registration, the plates' corners and every character's box in the image go into the metadata")

#: Texture resolution of vehicle plates (pixels per millimetre).
PX_PER_MM = 1.5


class Plates(Randomizer):
    key = "plates"
    schema = SCHEMA
    sample_order = 25
    apply_order = 25  # after a sign or a shape plate, before decals and wear (dirt on plates too)

    def apply(self, ctx: ObjectContext, value: Mapping[str, Any], materials: List[int]) -> Tuple[List[int], Any]:
        if not ctx.plates or ctx.plate_material is None:
            raise SynthgenError(f"objects[{ctx.spec.index}].plates: its model declares no plate mounts (a library "
                                f"vehicle's `plates` in assets_manifest)")
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
        return out, {"country": reg["country"], "text": reg["text"], "text_latin": tex["text_latin"],
                     "mounts": mounts, "texture_size": [w_px, h_px],
                     "characters": [{"char": c["char"], "bbox": c["bbox"]} for c in tex["characters"]]}


register(Plates())


def project_plates(info: Mapping[str, Any], mounts: Mapping[str, np.ndarray], world_from_object: np.ndarray,
                   camera: Any, depth: Optional[np.ndarray] = None) -> List[Dict[str, Any]]:
    """Where a vehicle's plates are in the image: per mount, its corners (pixels: top left, top
    right, bottom right, bottom left), its box, and each character's box (the projection of its
    box on the plate texture) with whether it is seen (the depth buffer at the character's
    centre is the plate's, within 2 cm: nothing in front of it)."""
    K = np.array([[camera.fx, 0.0, camera.cx], [0.0, camera.fy, camera.cy], [0.0, 0.0, 1.0]])
    cfw = np.linalg.inv(np.asarray(camera.world_from_camera, np.float64))
    w_px, h_px = info["texture_size"]
    out = []
    for name in info["mounts"]:
        q = np.asarray(mounts[name], np.float64)  # TL, TR, BR, BL in object space
        tl, tr, bl = q[0], q[1], q[3]

        def at(u: float, v: float) -> np.ndarray:
            """Object-space point of texture pixel coordinates (u right, v down)."""
            return tl + (tr - tl) * (u / w_px) + (bl - tl) * (v / h_px)

        def image(pts: Sequence[np.ndarray]) -> Tuple[np.ndarray, np.ndarray]:
            p = np.c_[np.asarray(pts), np.ones(len(pts))]
            c = (cfw @ np.asarray(world_from_object, np.float64) @ p.T)[:3]
            uv = K @ c
            return (uv[:2] / uv[2]).T, c[2]

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
