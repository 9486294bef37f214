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
    load_image_plugin,
)
from .scene_file import SceneFileError, build_scene, load_scene  # noqa: F401

__all__ = [
    "FileError",
    "PinholeCamera",
    "RenderResult",
    "Scene",
    "SceneFileError",
    "SynthgenError",
    "TextureRef",
    "__version__",
    "build_scene",
    "load_image_plugin",
    "load_scene",
]
