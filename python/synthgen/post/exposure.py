"""Post-processing step ``exposure``: scales the linear image by 2^ev (photographic stops).
For example to bring a physically scaled sky into display range or to vary brightness across a
dataset (``ev: {uniform: [-1, 1]}``). Labels are untouched."""
from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from ..schema.fields import Number, Record
from . import Arrays, PostStep, register

SCHEMA = Record({"ev": Number(0.0, min=-20.0, max=20.0, doc="exposure change in stops (the image x 2^ev)")},
                doc="exposure")


def apply(arrays: Mapping[str, np.ndarray], params: Mapping[str, Any]) -> Arrays:
    out = dict(arrays)
    out["rgb"] = (np.asarray(arrays["rgb"], np.float32) * np.float32(2.0 ** float(params["ev"]))).astype(np.float32)
    return out


register(PostStep("exposure", "scales the linear image by 2^ev (stops)", SCHEMA, apply, module=__name__))
