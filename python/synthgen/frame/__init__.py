"""Frames: a worker turns one scenario frame into arrays and metadata.

- :mod:`.renderer` -- :class:`FrameRenderer`, the orchestration of a frame (sample, set up,
  place, render, record);
- :mod:`.resources` -- what a worker keeps across frames (meshes, instance pools) and what
  lives one frame (generated textures and materials);
- :mod:`.layout` -- placement with visibility checks (label-only renders, amodal masks);
- :mod:`.records` -- placed objects, the frame's camera and the per-object metadata;
- :mod:`.gallery` -- the wear gallery (``synthgen gallery``): effects on a sign, a panel, a
  sphere and a library car, and a scenario's frame under each weather condition;
- :mod:`.api` -- :class:`synthgen.Scenario`: frames rendered in memory, as
  :class:`synthgen.FrameData` (:mod:`synthgen.outputs.data`).
"""
from .renderer import FrameRenderer, light_plugin  # noqa: F401
