"""PyTorch, imported lazily: :func:`torch` returns the ``torch`` module or raises a
:class:`synthgen.SynthgenError` naming the Debian packages to install.

PyTorch is optional for synthgen (only ``synthgen.evaluate`` needs it), so no module of the
package imports it at the top: each function that needs it calls :func:`torch` (or
:func:`nn`), and the message says what to install instead of a bare ``ModuleNotFoundError``.
"""
from __future__ import annotations

import os
from types import ModuleType
from typing import Any

from .._core import SynthgenError

__all__ = ["torch", "nn", "load_file", "PACKAGES"]

#: The Debian packages that provide PyTorch and torchvision (what the Makefile installs).
PACKAGES = "python3-torch python3-torchvision"


def torch() -> ModuleType:
    """The ``torch`` module; SynthgenError naming :data:`PACKAGES` when it is not installed."""
    try:
        import torch as _t
    except ImportError as e:
        raise SynthgenError(f"synthgen.evaluate needs PyTorch, which is not installed ({e}); "
                            f"install it with: apt-get install {PACKAGES} "
                            f"(or pip install torch torchvision)") from None
    return _t


def nn() -> ModuleType:
    """``torch.nn`` (see :func:`torch`)."""
    return torch().nn


def load_file(path: str, max_bytes: int, what: str, file_kind: str, limit: str, read_as: str) -> Any:
    """``torch.load`` of a file of plain contents (``weights_only``: tensors, dicts, lists, numbers,
    strings; never a pickled object), bounded in size. SynthgenError naming ``path``: "{what}
    not found", "a {file_kind} of N bytes is larger than the {max_bytes} bytes {limit}", "cannot
    read {read_as} (...)"."""
    t = torch()
    if not os.path.isfile(path):
        raise SynthgenError(f"{path}: {what} not found")
    size = os.path.getsize(path)
    if size > max_bytes:
        raise SynthgenError(f"{path}: a {file_kind} of {size} bytes is larger than the {max_bytes} bytes {limit}")
    try:
        return t.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # a pickle of anything else, a truncated file, not a torch file
        why = str(e).split("WeightsUnpickler error:")[-1].strip()[:200]  # not torch's advice to unpickle
        raise SynthgenError(f"{path}: cannot read {read_as} ({type(e).__name__}: {why})") from None
