"""The formats: YAML with positions, typed fields, errors with "did you mean",
random distributions, and the plugin records generated from the C++ declarations.

- :mod:`.errors` -- :class:`SceneFileError` (``FILE:LINE:COLUMN: key.path: reason``),
  :class:`Loc`, :class:`ValidationContext`;
- :mod:`.yaml_io` -- safe YAML that remembers the line and column of every key and value;
- :mod:`.fields` -- the typed field tree (:class:`Record`, :class:`Number`, ...);
- :mod:`.distributions` and :mod:`.random` -- ``{uniform: [a, b]}`` and friends in any slot;
- :mod:`.plugins` -- materials, textures, lights, camera and render settings as records,
  from ``synthgen._core.plugin_info`` (parameters are declared once, in C++);
- :mod:`.reference` -- the reference text of a schema (``synthgen schema``, the docs).
"""
from .errors import Loc, SceneFileError, ValidationContext  # noqa: F401
from .fields import (EMPTY, REQUIRED, Bool, Choice, ColorOrTexture, Field, FilePath, Integer, ListOf,  # noqa: F401
                     MapOf, Matrix4, Number, NumberList, Record, String, TextureName, Validated, Vector, map_values)
from .reference import format_schema  # noqa: F401
from .yaml_io import parse_yaml, read_yaml  # noqa: F401
