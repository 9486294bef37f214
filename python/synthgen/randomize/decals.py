"""Randomizer ``decals``: images projected onto the object's front (the side its forward axis points to) from a
projector in object space -- image files, generated sign pictograms or licence plates --
over its material, before wear. Each decal's kind, text and size go into the metadata."""
from __future__ import annotations

import functools
import os
from typing import Any, Dict, List, Mapping, Tuple

import numpy as np

from .._core import SynthgenError, read_image
from ..schema.fields import REQUIRED, Choice, FilePath, ListOf, Number, Record, String
from ..schema.random import R
from ..scene import plates, signs, wear
from . import ObjectContext, Randomizer, register

DECAL = Record({
    "image": FilePath(None, doc="an image file (PNG with alpha, JPEG, EXR)"),
    "pictogram": Record({"family": R(Choice(list(signs.FAMILIES), REQUIRED, doc="sign family (shape and colours)")),
                         "text": R(String(None, doc="text on the sign, e.g. a speed limit '70' (default: the "
                                                    "family's own)"))}, default=None, doc="a generated sign pictogram"),
    "plate": Record({"country": R(Choice(list(plates.COUNTRIES), REQUIRED,
                                         doc="registration format and plate layout (ru: GOST R 50577, de: DIN 74069)"))},
                    default=None,
                    doc="a generated licence plate"),
    "probability": Number(1.0, min=0.0, max=1.0, doc="chance that an instance gets the decal"),
    "size": R(Number(0.4, min=0.01, max=1.0, doc="decal width as a fraction of the object's width (across its "
                                                 "forward axis)")),
    "height": R(Number(0.5, min=0.0, max=1.0, doc="decal centre height, fraction of the object's height (0: bottom)")),
}, one_of=[("image", "pictogram", "plate")],
    doc="an image projected onto the object's front: the side its forward axis points to (objects[].forward or "
        "the asset's; +x for primitives), upright along its up axis, read from in front")

SCHEMA = ListOf(DECAL, [], doc="decals projected onto the front, before wear")


@functools.lru_cache(maxsize=256)
def _image_aspect(path: str, mtime_ns: int) -> float:
    h, w = read_image(path).shape[:2]
    return float(w) / float(max(h, 1))


def image_aspect(path: str) -> float:
    """Width / height of an image file (decoded once per file version by the isolated reader)."""
    try:
        mtime = os.stat(path).st_mtime_ns
    except OSError as e:
        raise SynthgenError(f"{path}: cannot read the image: {e.strerror}") from None
    return _image_aspect(path, mtime)


class Decals(Randomizer):
    key = "decals"
    schema = SCHEMA
    sample_order = 40
    apply_order = 30

    def apply(self, ctx: ObjectContext, value: Any, materials: List[int]) -> Tuple[List[int], Any]:
        if not value:
            return materials, None
        rng = ctx.rng
        mats = list(materials)
        lo, hi = np.asarray(ctx.shape_lo, np.float64), np.asarray(ctx.shape_hi, np.float64)
        ext = np.maximum(hi - lo, 1e-6)
        centre = 0.5 * (lo + hi)
        done: List[Dict[str, Any]] = []
        for d in value:
            if float(rng.random()) >= float(d["probability"]):
                continue
            if d.get("plate") is not None:
                reg = plates.random_registration(d["plate"]["country"], rng)
                w_mm, h_mm = plates.SIZE_MM[reg["country"]]
                image, aspect = np.asarray(plates.render_plate(reg, px_per_mm=1.0)["rgb"], np.float32), w_mm / h_mm
                info: Dict[str, Any] = {"kind": "plate", "country": reg["country"], "text": reg["text"]}
            elif d.get("pictogram") is not None:
                sg_ = signs.render_sign(d["pictogram"]["family"], d["pictogram"].get("text"), 128)
                image, aspect = np.asarray(signs.on_background(sg_["rgba"]), np.float32), 1.0
                info = {"kind": "pictogram", "class_name": sg_["class_name"]}
            else:
                image, aspect = d["image"], image_aspect(d["image"])
                info = {"kind": "image", "file": os.path.basename(d["image"])}
            # The front: the side the shape's forward axis points to, the image upright along its
            # up axis; sizes along the remaining (lateral) axis and up.
            f, u = np.asarray(ctx.forward, np.float64), np.asarray(ctx.up, np.float64)
            fi, ui = int(np.argmax(np.abs(f))), int(np.argmax(np.abs(u)))
            li = 3 - fi - ui
            width = float(d["size"]) * float(ext[li])
            target = centre + (float(d["height"]) - 0.5) * float(ext[ui]) * u
            dist = 2.0 * float(ext.max()) + 1e-3
            position = target + (0.5 * float(ext[fi]) + dist) * f
            fov = float(np.degrees(2.0 * np.arctan(0.5 * width / aspect / (dist + 0.5 * ext[fi]))))
            mats = wear.decal(ctx.scene, mats, image, position=[float(v) for v in position],
                              look_at=[float(v) for v in target], up=[float(v) for v in u], fov=max(fov, 0.1),
                              aspect=aspect, occlusion=False, space="object")
            # The decal's size on the object's front (object units): the image keeps its aspect.
            info["size"] = [round(width, 6), round(width / aspect, 6)]
            done.append(info)
        return mats, done


register(Decals())
