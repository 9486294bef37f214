"""Randomizer ``sign``: the object is a road sign -- a generated pictogram (alpha cut-out)
on a square panel, on a pole (``mount_height``). The sign's family, text and class name go
into the metadata."""
from __future__ import annotations

from typing import Any, List, Mapping, Tuple

import numpy as np

from .._core import TextureRef
from ..schema.fields import REQUIRED, Choice, Number, Record, String
from ..schema.random import R
from ..scene import signs
from . import ObjectContext, Randomizer, register

SCHEMA = Record({
    "family": R(Choice(list(signs.FAMILIES), REQUIRED, doc="sign family (shape and colours)")),
    "text": R(String(None, doc="number of a prohibitory sign, symbol of a warning / information sign")),
    "size": R(Number(0.7, min=0.05, max=5.0, doc="sign width in metres")),
    "mount_height": R(Number(1.5, min=0.0, max=10.0, doc="height of the sign's lower edge; a pole below it")),
}, default=None, doc="a road sign: a generated pictogram (alpha cut-out) on a pole")


class Sign(Randomizer):
    key = "sign"
    schema = SCHEMA
    sample_order = 10
    apply_order = 10
    shape = True

    def make_shape(self, scene: Any) -> Tuple[int, np.ndarray, np.ndarray]:
        # A unit square in the x-y plane facing -z (towards a camera at azimuth 0, whose image
        # right is world -x): u runs along -x so the pictogram reads correctly from the front.
        q = np.array([[-0.5, 0, 0], [0.5, 0, 0], [0.5, 1, 0], [-0.5, 1, 0]], np.float32)
        mid = scene.add_mesh(q, np.array([[0, 2, 1], [0, 3, 2]], np.uint32),
                             uvs=np.array([[1, 0], [0, 0], [0, 1], [1, 1]], np.float32), name="sign")
        return mid, np.array([-0.5, 0.0, 0.0]), np.array([0.5, 1.0, 0.0])

    def placement(self, value: Mapping[str, Any], scale: float) -> Tuple[np.ndarray, float, np.ndarray, float]:
        s = float(value["size"]) * scale
        mount = float(value["mount_height"])
        m = np.eye(4)
        m[:3, :3] = np.diag([s, s, 1.0])
        m[1, 3] = mount
        return m, 0.5 * s, np.array([s, s + mount, 0.02]), mount + 0.5 * s

    def apply(self, ctx: ObjectContext, value: Mapping[str, Any], materials: List[int]) -> Tuple[List[int], Any]:
        s = signs.render_sign(value["family"], value.get("text"), 256)
        tex = ctx.scene.add_image_texture(np.asarray(s["rgba"], np.float32), {"wrap": "clamp", "colorspace": "linear"})
        mat = ctx.scene.add_material("principled", {"base_color": TextureRef(tex), "alpha": TextureRef(tex),
                                                    "alpha_mode": "mask", "roughness": 0.45})
        return [mat], {"family": s["family"], "text": s["text"], "class_name": s["class_name"]}


register(Sign())
