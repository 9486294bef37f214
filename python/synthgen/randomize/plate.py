"""Randomizer ``plate``: the object is a licence plate with a random valid registration
(Russian or German sizes, fonts and embossing) on a post (``mount_height``). The
registration text goes into the metadata."""
from __future__ import annotations

from typing import Any, List, Mapping, Tuple

import numpy as np

from .._core import TextureRef
from ..schema.fields import REQUIRED, Choice, Number, Record
from ..schema.random import R
from ..scene import plates
from ..scene import primitives as P
from . import ObjectContext, Randomizer, register

SCHEMA = Record({
    "country": R(Choice(list(plates.COUNTRIES), REQUIRED,
                        doc="registration format and plate layout (ru: GOST R 50577, de: DIN 74069)")),
    "mount_height": R(Number(0.6, min=0.0, max=10.0, doc="height of the plate's lower edge; a post below it")),
}, default=None, doc="a licence plate with a random valid registration (its text goes into the metadata)")


class Plate(Randomizer):
    key = "plate"
    schema = SCHEMA
    sample_order = 20
    apply_order = 20
    shape = True

    def make_shape(self, scene: Any) -> Tuple[int, np.ndarray, np.ndarray]:
        b = P.box((1.0, 1.0, 1.0))
        mid = scene.add_mesh(b["positions"], b["indices"], normals=b["normals"], uvs=b["uvs"], name="plate")
        return mid, np.full(3, -0.5), np.full(3, 0.5)

    def placement(self, value: Mapping[str, Any], scale: float) -> Tuple[np.ndarray, float, np.ndarray, float]:
        w, h = 0.52 * scale, (0.112 if value["country"] == "ru" else 0.11) * scale
        mount = float(value["mount_height"])
        m = np.eye(4)
        m[:3, :3] = np.diag([w, h, 0.01])
        m[1, 3] = mount + 0.5 * h
        return m, 0.5 * w, np.array([w, h + mount, 0.01]), mount + 0.5 * h

    def apply(self, ctx: ObjectContext, value: Mapping[str, Any], materials: List[int]) -> Tuple[List[int], Any]:
        reg = plates.random_registration(value["country"], ctx.rng)
        p = plates.render_plate(reg, px_per_mm=1.5)
        linear = {"wrap": "clamp", "colorspace": "linear"}
        col = ctx.scene.add_image_texture(np.asarray(p["rgb"], np.float32), linear)
        nrm = ctx.scene.add_image_texture(np.asarray(p["normal"], np.float32), linear)
        mat = ctx.scene.add_material("principled", {"base_color": TextureRef(col), "normal_map": TextureRef(nrm),
                                                    "roughness": 0.35, "metallic": 0.0})
        return [mat], {"country": reg["country"], "text": reg["text"], "text_latin": p["text_latin"]}


register(Plate())
