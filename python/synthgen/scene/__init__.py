"""Scenes: building a :class:`synthgen.Scene` from a file or from code.

- :mod:`.scene_file` -- YAML scene files (the plugin vocabulary from the C++ declarations);
- :mod:`.primitives` -- spheres, boxes, planes and transform helpers;
- :mod:`.demo` -- the built-in demo scene;
- :mod:`.wear` -- rust, dirt, scratches, ice and decals as material presets;
- :mod:`.plates`, :mod:`.signs`, :mod:`.raster` -- generated licence plates and road-sign
  pictograms (a small SDF rasterizer and text);
- :mod:`.assets` -- the asset manifest (ids, sources, licences, checksums) and its cache;
- :mod:`.extensions` -- user extensions in C (compiled, cached, loaded on consent); :mod:`.wear_ext` -- the
  rust preset on the example extension.
"""
