"""synthgen: photoreal synthetic training data for computer vision.

The native core (``synthgen._core``) is an Embree-based path tracer with an integration API
(typed libraries with stable ids, incremental ``commit()``), exact label outputs and a
registry of plugins whose parameters are declared once, in C++. The Python package is laid
out by workflow stage, a subpackage each:

====================  ===================================================================
``schema``            YAML with positions, typed fields, errors, distributions; the plugin
                      records generated from the C++ declarations
``scene``             scene files, primitives, the demo, wear presets, plates, signs, assets
``background``        real photos: calibrations, real labels, the photos of a run
``post``              image-space steps (exposure, ...; ``post.photo``: compositing into
                      photos, camera matching)
``outputs``           one module per output format, verification, reading a dataset back
``randomize``         object randomizers: sign, plate, decals, wear; weather
``scenario``          scenarios: validation and the typed records of one frame
``frame``             the per-worker frame renderer (set-up, layout, records), the gallery
``run``               executors, resume, run summaries
``bench``             speed against accuracy, peer renderers
``cli``               one module per ``synthgen`` command
====================  ===================================================================

Each stage imports only from the stages listed before it (docs/architecture.md;
tests/python/test_import_graph.py).

In memory and back: ``synthgen.Scenario(path).frames()`` renders frames as arrays and labels
(:class:`synthgen.FrameData`) without files; ``synthgen.read_dataset(dir)`` reads a dataset
back the same way (and as a torch ``Dataset`` when torch is installed).
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
    plugin_info,
    plugin_kinds,
    plugin_names,
    read_image,
)
from .schema.errors import SceneFileError  # noqa: F401


def _srgb8(self: RenderResult):
    """H x W x 3 uint8 sRGB-encoded image of :attr:`rgb` (IEC 61966-2-1, clipped to [0, 1]),
    for viewing; :attr:`rgb` itself is linear radiance."""
    from .outputs.files import to_srgb8

    return to_srgb8(self.rgb)


RenderResult.srgb8 = _srgb8

#: Public names imported on first use (they pull in the scenario and frame machinery).
_LAZY = {"Scenario": ("frame.api", "Scenario"), "FrameData": ("outputs.data", "FrameData"),
         "read_dataset": ("outputs.read", "read_dataset"), "Dataset": ("outputs.read", "Dataset")}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        value = getattr(importlib.import_module(f"{__name__}.{module}"), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'synthgen' has no attribute {name!r}")
from .scene import extensions, journal, primitives, wear  # noqa: F401
from .scene.scene_file import build_scene, load_scene  # noqa: F401

__all__ = [
    "Dataset",
    "FileError",
    "FrameData",
    "PinholeCamera",
    "RenderResult",
    "Scenario",
    "Scene",
    "SceneFileError",
    "SynthgenError",
    "TextureRef",
    "__version__",
    "build_scene",
    "load_image_plugin",
    "load_scene",
    "plugin_info",
    "plugin_kinds",
    "plugin_names",
    "primitives",
    "read_dataset",
    "read_image",
    "wear",
]
