"""Output kinds ``instance`` (uint16 instance ids, 1..N per frame, 0 = background) and
``semantic`` (uint16 class ids: 1 + index in the scenario's class list), 16-bit PNGs."""
from __future__ import annotations

import numpy as np

from .files import write_id_png
from .registry import Frame, OutputKind, register


def write_instance(path: str, frame: Frame) -> str:
    return write_id_png(path, np.asarray(frame.arrays["instance_id"]))


def write_semantic(path: str, frame: Frame) -> str:
    return write_id_png(path, frame.arrays["class_id"])


register(OutputKind("instance", "instance ids, uint16 PNG (1..N per frame, 0 = background and ground)", order=50,
                    directory="instance", extension=".png", write=write_instance, module=__name__))
register(OutputKind("semantic", "class ids, uint16 PNG (1 + index in the class list)", order=60,
                    directory="semantic", extension=".png", write=write_semantic, module=__name__))
