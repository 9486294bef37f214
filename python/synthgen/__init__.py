"""synthgen: photoreal synthetic training data for computer vision.

The native core (``synthgen._core``) is an Embree-based path tracer with an
integration API (typed libraries with stable ids, incremental ``commit()``) and
exact label outputs. This package adds the Pythonic layer: scene files, writers
and the ``synthgen`` command line.
"""
from ._core import (  # noqa: F401
    FileError,
    PinholeCamera,
    RenderResult,
    Scene,
    SynthgenError,
    TextureRef,
    __version__,
)

__all__ = [
    "FileError",
    "PinholeCamera",
    "RenderResult",
    "Scene",
    "SynthgenError",
    "TextureRef",
    "__version__",
]
