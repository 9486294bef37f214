"""PyTorch, imported lazily: :func:`torch` returns the ``torch`` module or raises a
:class:`synthgen.SynthgenError` naming the Debian packages to install.

PyTorch is optional for synthgen (only ``synthgen.evaluate`` needs it), so no module of the
package imports it at the top: each function that needs it calls :func:`torch` (or
:func:`nn`), and the message says what to install instead of a bare ``ModuleNotFoundError``.
"""
from __future__ import annotations

from types import ModuleType

from .._core import SynthgenError

__all__ = ["torch", "nn", "PACKAGES"]

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
