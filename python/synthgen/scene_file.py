"""Static scene files: a thin, validated YAML layer over :class:`synthgen.Scene`.

A scene file is a YAML mapping::

    version: 1                     # optional, the format version (only 1 exists)
    description: "..."             # optional free text
    camera:
      width: 640                   # pixels
      height: 480
      fov_y: 40                    # vertical field of view in degrees ...
      # fx: 500, fy: 500, cx: 320, cy: 240   # ... or OpenCV intrinsics (cx, cy default
      #                                       #     to the image centre)
      look_at: {eye: [0, 2, -6], target: [0, 0.5, 0], up: [0, 1, 0]}
      # world_from_camera: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]  # or a 4x4 pose
    textures:                      # named; referenced by name from materials
      wood: {type: image, file: textures/wood.png, colorspace: srgb, wrap: repeat}
      grey: {type: constant, value: 0.5}
    materials:                     # named; referenced by name from objects
      red: {type: diffuse, albedo: [0.8, 0.1, 0.1]}
      floor: {type: diffuse, albedo: {texture: wood}}
      lamp: {type: emissive, radiance: [10, 10, 10], strength: 1, two_sided: false}
    objects:                       # at least one
      - name: ball                 # optional, reported in meta.json
        primitive: sphere          # sphere {radius, segments, rings} | box {size} |
        radius: 0.5                #   plane {size} (the y = 0 plane, normal +y)
        class_id: 1                # 0..65535 (0 is also the background's label)
        instance_id: 7             # optional, 1..65535; default: instance handle + 1
        material: red              # optional; default: the mesh file's materials / grey
        translate: [0, 0.5, 0]     # world_from_object = T * R * S ...
        rotate: {axis: [0, 1, 0], angle: 30}      # degrees; or {euler: [x, y, z],
        scale: 1.0                                #   order: xyz} (extrinsic, degrees)
        # world_from_object: 4x4   # ... or a matrix (then no translate/rotate/scale)
      - mesh: {file: meshes/bunny.obj}           # OBJ / PLY / glTF / GLB
        class_id: 2
    lights:
      - {type: sun, direction: [0.3, 1, 0.2], irradiance: 3, angular_diameter: 0.53}
      - {type: environment, radiance: [0.3, 0.4, 0.6]}
      - {type: point, position: [0, 3, 0], intensity: 10}
    render: {spp: 64, max_depth: 8, rr_depth: 5, seed: 0, threads: 0, tile_size: 16}

Relative file paths are resolved against the directory of the YAML file. Colours are a
number (grey) or a list of three numbers. :func:`format_schema` prints every key with
its type, default, allowed range and documentation.

Errors
------
Every problem raises :class:`SceneFileError` (a :class:`synthgen.SynthgenError`, hence a
:class:`ValueError`) whose message reads ``FILE:LINE:COLUMN: key.path: reason``, e.g.::

    scene.yaml:12:5: objects[1].materal: unknown key 'materal' (did you mean
    'material'?); allowed keys: class_id, instance_id, material, ...

Bad values name the allowed range or values. Errors raised by the native core while
building (a mesh file that cannot be read, an inconsistent parameter) are re-raised
with the location of the YAML entry that caused them. Line numbers come from a
:class:`yaml.SafeLoader` subclass that records the position of every key and value
(only safe YAML is accepted; duplicate keys are errors).

Typed fields, and the extension point for random distributions
---------------------------------------------------------------
The schema is a tree of small :class:`Field` objects (:class:`Number`,
:class:`Integer`, :class:`Bool`, :class:`String`, :class:`Choice`, :class:`Vector`,
:class:`Matrix4`, :class:`FilePath`, :class:`Record`, :class:`MapOf`,
:class:`ListOf`, :class:`ColorOrTexture`), each with a type, a default, a range and a
doc string. ``field.validate(value, loc, ctx)`` returns plain Python values (records
become :class:`Validated` dicts that remember the YAML location of each key).

Every numeric slot -- scalar fields and each component of vectors, colours and
matrices -- is validated through one hook, :meth:`ValidationContext.number`, which by
default calls ``field.check(value, loc, ctx)`` (type and range check). A scenario
runner adds random distributions by subclassing the context::

    class RandomizingContext(ValidationContext):
        def number(self, field, value, loc):
            if isinstance(value, dict) and list(value) == ["uniform"]:
                bounds = value["uniform"]        # (check it is a list of 2 first)
                lo, hi = (field.check(v, loc.key("uniform", value).index(i, bounds), self)
                          for i, v in enumerate(bounds))
                return Uniform(lo, hi)          # bounds checked against the field range
            return super().number(field, value, loc)

    spec = SCENE_SCHEMA.validate(data, Loc.root(data), RandomizingContext(path, base))
    frame_spec = map_values(spec, lambda v: v.sample(rng) if isinstance(v, Uniform) else v)
    scene, settings, meta = build_validated(frame_spec, ctx)

so ``{uniform: [0.2, 0.8]}`` works in any scalar slot without touching the schema.
:meth:`Record.extend` derives a schema with extra keys (e.g. a top-level ``frames:``)
and :func:`map_values` rebuilds a validated tree keeping its locations, so each frame is
built with :func:`build_validated` and its errors still point into the YAML file.
"""
from __future__ import annotations

import contextlib
import copy
import difflib
import hashlib
import math
import numbers
import os
import re
from collections.abc import Mapping, Sequence
from typing import Any, Callable, Dict, Iterable, Iterator, List, NoReturn, Optional, Tuple

import numpy as np
import yaml

from . import primitives
from ._core import PinholeCamera, Scene, SynthgenError, TextureRef

__all__ = [
    "SceneFileError",
    "load_scene",
    "build_scene",
    "build_validated",
    "validate_scene",
    "validate_render_settings",
    "read_yaml",
    "format_schema",
    "map_values",
    "ValidationContext",
    "Loc",
    "Validated",
    "TextureName",
    "Field",
    "Number",
    "Integer",
    "Bool",
    "String",
    "Choice",
    "Vector",
    "Matrix4",
    "FilePath",
    "Record",
    "MapOf",
    "ListOf",
    "ColorOrTexture",
    "SCENE_SCHEMA",
]


# ---------------------------------------------------------------------------------------
# Errors and locations


class SceneFileError(SynthgenError):
    """A problem in a scene file, located as ``source:line:column: key.path: reason``.

    Attributes: ``source`` (file name or description), ``line`` and ``column``
    (1-based, or None when unknown, e.g. for dicts built in Python), ``key_path`` (e.g.
    ``objects[2].rotate.angle``; empty for the top level) and ``reason``.
    """

    def __init__(self, source: str, line: Optional[int], column: Optional[int], key_path: str, reason: str):
        self.source = source
        self.line = line
        self.column = column
        self.key_path = key_path
        self.reason = reason
        where = str(source)
        if line is not None:
            where += f":{line}"
            if column is not None:
                where += f":{column}"
        msg = f"{where}: {key_path}: {reason}" if key_path else f"{where}: {reason}"
        super().__init__(msg)


class Loc:
    """Position of a value: its key path and (when known) its 1-based line and column."""

    __slots__ = ("path", "line", "column")

    def __init__(self, path: str = "", line: Optional[int] = None, column: Optional[int] = None):
        self.path = path
        self.line = line
        self.column = column

    @staticmethod
    def root(data: Any = None) -> "Loc":
        """Location of the document root (uses the mark of a :class:`MarkedDict`)."""
        mark = getattr(data, "mark", None)
        return Loc("", *(mark or (None, None)))

    def _join(self, key: Any) -> str:
        if isinstance(key, int) and not isinstance(key, bool):
            return f"{self.path}[{key}]"
        return f"{self.path}.{key}" if self.path else str(key)

    def key(self, key: Any, container: Any) -> "Loc":
        """Location of the *key* ``key`` of mapping ``container``."""
        mark = getattr(container, "key_marks", {}).get(key) if _hashable(key) else None
        return Loc(self._join(key), *(mark or (self.line, self.column)))

    def value(self, key: Any, container: Any) -> "Loc":
        """Location of the value stored under ``key`` in mapping ``container``."""
        mark = getattr(container, "value_marks", {}).get(key) if _hashable(key) else None
        return Loc(self._join(key), *(mark or (self.line, self.column)))

    def index(self, i: int, container: Any) -> "Loc":
        """Location of item ``i`` of sequence ``container``."""
        marks = getattr(container, "item_marks", None)
        mark = marks[i] if marks is not None and i < len(marks) else None
        return Loc(self._join(i), *(mark or (self.line, self.column)))

    def __repr__(self) -> str:
        return f"Loc({self.path!r}, {self.line}, {self.column})"


def _hashable(x: Any) -> bool:
    try:
        hash(x)
    except TypeError:
        return False
    return True


class ValidationContext:
    """State shared while validating and building one scene description.

    ``source`` names the file in messages; ``base_dir`` resolves relative paths.
    Override :meth:`number` to accept more than plain numbers in numeric slots (see the
    module docstring).
    """

    def __init__(self, source: str = "<scene>", base_dir: Optional[str] = None):
        self.source = str(source)
        self.base_dir = os.path.abspath(base_dir if base_dir is not None else os.getcwd())

    def number(self, field: "Number", value: Any, loc: Loc) -> Any:
        """Validates one numeric slot. The extension point for random distributions."""
        return field.check(value, loc, self)

    def error(self, loc: Loc, reason: str) -> NoReturn:
        """Raises :class:`SceneFileError` at ``loc``."""
        raise SceneFileError(self.source, loc.line, loc.column, loc.path, reason)

    @contextlib.contextmanager
    def core(self, loc: Loc, what: Optional[str] = None) -> Iterator[None]:
        """Re-raises errors of the native core inside the block at the YAML location
        ``loc`` (prefixing ``what`` to the message when given)."""
        try:
            yield
        except SceneFileError:
            raise
        except SynthgenError as e:
            reason = f"{what}: {e}" if what else str(e)
            raise SceneFileError(self.source, loc.line, loc.column, loc.path, reason) from e


# ---------------------------------------------------------------------------------------
# YAML loading with positions


class MarkedDict(dict):
    """dict from YAML that remembers 1-based (line, column) of itself, its keys and values."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.mark: Optional[Tuple[int, int]] = None
        self.key_marks: Dict[Any, Tuple[int, int]] = {}
        self.value_marks: Dict[Any, Tuple[int, int]] = {}


class MarkedList(list):
    """list from YAML that remembers 1-based (line, column) of itself and its items."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.mark: Optional[Tuple[int, int]] = None
        self.item_marks: List[Tuple[int, int]] = []


def _mark(m: yaml.Mark) -> Tuple[int, int]:
    return (m.line + 1, m.column + 1)


class _MarkedLoader(yaml.SafeLoader):
    """Safe YAML loader producing MarkedDict / MarkedList, rejecting duplicate keys."""

    def construct_marked_mapping(self, node: yaml.Node) -> MarkedDict:
        if not isinstance(node, yaml.MappingNode):
            raise yaml.constructor.ConstructorError(
                None, None, f"expected a mapping node, but found {node.id}", node.start_mark)
        seen: Dict[Any, yaml.Node] = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge" or not isinstance(key_node, yaml.ScalarNode):
                continue
            key = self.construct_object(key_node)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    "while constructing a mapping", node.start_mark,
                    f"found duplicate key {key!r} (first defined on line {seen[key].start_mark.line + 1})",
                    key_node.start_mark)
            seen[key] = key_node
        self.flatten_mapping(node)
        d = MarkedDict()
        d.mark = _mark(node.start_mark)
        for key_node, value_node in node.value:
            key = self.construct_object(key_node, deep=True)
            if not _hashable(key):
                raise yaml.constructor.ConstructorError(
                    "while constructing a mapping", node.start_mark, "found an unhashable key", key_node.start_mark)
            d[key] = self.construct_object(value_node, deep=True)
            d.key_marks[key] = _mark(key_node.start_mark)
            d.value_marks[key] = _mark(value_node.start_mark)
        return d

    def construct_marked_sequence(self, node: yaml.Node) -> MarkedList:
        if not isinstance(node, yaml.SequenceNode):
            raise yaml.constructor.ConstructorError(
                None, None, f"expected a sequence node, but found {node.id}", node.start_mark)
        out = MarkedList(self.construct_object(child, deep=True) for child in node.value)
        out.mark = _mark(node.start_mark)
        out.item_marks = [_mark(child.start_mark) for child in node.value]
        return out


_MarkedLoader.add_constructor("tag:yaml.org,2002:map", _MarkedLoader.construct_marked_mapping)
_MarkedLoader.add_constructor("tag:yaml.org,2002:seq", _MarkedLoader.construct_marked_sequence)
# YAML 1.1 (PyYAML) reads 1e3 and 1.0e3 as strings; accept them as floats like YAML 1.2.
_MarkedLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def read_yaml(path: str | os.PathLike, source: Optional[str] = None) -> Any:
    """Parses a YAML file safely into MarkedDict / MarkedList / scalars.

    Syntax errors, unknown tags and duplicate keys raise :class:`SceneFileError` with the
    line and column; ``source`` (default: ``path``) names the file in messages.
    """
    path = os.fspath(path)
    source = path if source is None else source
    try:
        with open(path, "r", encoding="utf-8") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError) as e:
        reason = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
        raise SceneFileError(source, None, None, "", f"cannot read scene file: {reason}") from e
    return parse_yaml(text, source)


def parse_yaml(text: str, source: str = "<string>") -> Any:
    """Parses YAML text like :func:`read_yaml`."""
    loader = _MarkedLoader(text)
    try:
        return loader.get_single_data()
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        reason = " ".join(str(x) for x in (e.context, e.problem) if x)
        if e.note:
            reason += f" ({e.note})"
        line, col = _mark(mark) if mark is not None else (None, None)
        raise SceneFileError(source, line, col, "", f"invalid YAML: {reason}") from None
    except yaml.YAMLError as e:
        raise SceneFileError(source, None, None, "", f"invalid YAML: {e}") from None
    finally:
        loader.dispose()


# ---------------------------------------------------------------------------------------
# Typed fields


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()
EMPTY: Any = type("_EmptyRecord", (), {"__repr__": lambda self: "EMPTY"})()  # record default: all defaults


def _show(value: Any) -> str:
    """Short description of a YAML value for error messages."""
    if value is None:
        return "null"
    if _is_bool(value):
        return f"{str(bool(value)).lower()} (boolean)"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return f"{value!r} (string)"
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)} item{'s' if len(value) != 1 else ''}"
    return type(value).__name__


def _is_bool(x: Any) -> bool:
    return isinstance(x, (bool, np.bool_))


def _seq(x: Any) -> Any:
    """numpy arrays (from scene dicts built in Python) are validated as lists."""
    return x.tolist() if isinstance(x, np.ndarray) else x


def _fmt_num(x: float) -> str:
    if isinstance(x, float) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


def _suggest(word: Any, candidates: Iterable[str]) -> str:
    if not isinstance(word, str):
        return ""
    m = difflib.get_close_matches(word, list(candidates), n=1, cutoff=0.6)
    return f" (did you mean '{m[0]}'?)" if m else ""


class Field:
    """Base of the schema fields: a default (``REQUIRED`` when the key must be given),
    a doc string, and ``validate(value, loc, ctx)`` returning the Python value."""

    type_name = "value"

    def __init__(self, default: Any = REQUIRED, doc: str = ""):
        self.default = default
        self.doc = doc

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        raise NotImplementedError

    def missing(self, loc: Loc, ctx: ValidationContext) -> Any:
        """Value used when the key is absent (a copy of the default)."""
        return copy.deepcopy(self.default)

    def describe(self) -> str:
        """Type and range as text, e.g. ``number in [0, 1]``."""
        return self.type_name


class Number(Field):
    """A finite number, optionally restricted to a range (``min``/``max`` inclusive
    unless ``min_open``/``max_open``)."""

    type_name = "number"

    def __init__(self, default: Any = REQUIRED, *, min: Optional[float] = None, max: Optional[float] = None,
                 min_open: bool = False, max_open: bool = False, doc: str = ""):
        super().__init__(default, doc)
        self.min, self.max, self.min_open, self.max_open = min, max, min_open, max_open

    def range_text(self) -> str:
        lo, hi = self.min, self.max
        if lo is not None and hi is not None:
            return f"{'(' if self.min_open else '['}{_fmt_num(lo)}, {_fmt_num(hi)}{')' if self.max_open else ']'}"
        if lo is not None:
            return f"{'>' if self.min_open else '>='} {_fmt_num(lo)}"
        if hi is not None:
            return f"{'<' if self.max_open else '<='} {_fmt_num(hi)}"
        return ""

    def describe(self) -> str:
        r = self.range_text()
        if not r:
            return self.type_name
        return f"{self.type_name} in {r}" if r[0] in "[(" else f"{self.type_name} {r}"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        return ctx.number(self, value, loc)

    def _convert(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if _is_bool(value) or not isinstance(value, numbers.Real):
            ctx.error(loc, f"expected a {self.describe()}, got {_show(value)}")
        v = float(value)
        if not math.isfinite(v):
            ctx.error(loc, f"expected a finite {self.describe()}, got {value!r}")
        return v

    def check(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        """Type and range check of one concrete value; returns it converted."""
        v = self._convert(value, loc, ctx)
        lo, hi = self.min, self.max
        bad = (lo is not None and (v < lo or (self.min_open and v == lo))) or \
              (hi is not None and (v > hi or (self.max_open and v == hi)))
        if bad:
            ctx.error(loc, f"value {_fmt_num(v)} is out of range; allowed: {self.describe()}")
        return v


class Integer(Number):
    """An integer (booleans and floats are rejected), optionally with a range."""

    type_name = "integer"

    def _convert(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if _is_bool(value) or not isinstance(value, numbers.Integral):
            ctx.error(loc, f"expected an {self.describe()}, got {_show(value)}")
        return int(value)


class Bool(Field):
    """true or false."""

    type_name = "boolean"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not _is_bool(value):
            ctx.error(loc, f"expected true or false, got {_show(value)}")
        return bool(value)


class String(Field):
    """A non-empty string."""

    type_name = "string"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not isinstance(value, str):
            ctx.error(loc, f"expected a string, got {_show(value)}")
        if not value:
            ctx.error(loc, "expected a non-empty string")
        return value


class Choice(String):
    """One of a fixed set of strings."""

    def __init__(self, choices: Sequence[str], default: Any = REQUIRED, doc: str = ""):
        super().__init__(default, doc)
        self.choices = list(choices)

    def describe(self) -> str:
        return "one of " + ", ".join(self.choices)

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not isinstance(value, str):
            ctx.error(loc, f"expected one of {', '.join(self.choices)}; got {_show(value)}")
        if value not in self.choices:
            ctx.error(loc, f"unknown value '{value}'{_suggest(value, self.choices)}; "
                           f"allowed values: {', '.join(self.choices)}")
        return value


class FilePath(String):
    """Path of an existing file; relative paths are resolved against the scene file's
    directory. Validates to an absolute path."""

    type_name = "file path"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        value = super().validate(value, loc, ctx)
        path = os.path.normpath(os.path.join(ctx.base_dir, os.path.expanduser(value)))
        if not os.path.isfile(path):
            how = "" if os.path.isabs(value) else f" (relative paths are resolved against {ctx.base_dir})"
            what = "is a directory" if os.path.isdir(path) else "not found"
            ctx.error(loc, f"file {what}: {path}{how}")
        return path


class Vector(Field):
    """A list of ``size`` numbers (each checked like ``Number(min, max, ...)``). With
    ``broadcast``, a single number stands for all components (e.g. a grey colour)."""

    def __init__(self, size: int, default: Any = REQUIRED, *, min: Optional[float] = None,
                 max: Optional[float] = None, min_open: bool = False, max_open: bool = False,
                 broadcast: bool = False, doc: str = ""):
        super().__init__(default, doc)
        self.size = size
        self.broadcast = broadcast
        self.element = Number(min=min, max=max, min_open=min_open, max_open=max_open)

    def describe(self) -> str:
        r = self.element.range_text()
        s = f"list of {self.size} numbers" + (f" (each {'in ' if r[0] in '[(' else ''}{r})" if r else "")
        return ("number or " + s) if self.broadcast else s

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        value = _seq(value)
        if isinstance(value, (list, tuple)):
            if len(value) != self.size:
                ctx.error(loc, f"expected a {self.describe()}, got {_show(value)}")
            return tuple(ctx.number(self.element, v, loc.index(i, value)) for i, v in enumerate(value))
        if self.broadcast:
            v = ctx.number(self.element, value, loc)
            return (v,) * self.size
        ctx.error(loc, f"expected a {self.describe()}, got {_show(value)}")


class Matrix4(Field):
    """A 4x4 affine matrix, row-major: four rows of four numbers (or 16 numbers); the
    last row must be (0, 0, 0, 1) and the 3x3 part invertible."""

    type_name = "4x4 matrix (4 rows of 4 numbers, last row [0, 0, 0, 1])"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        elem = Number()
        value = _seq(value)
        if isinstance(value, (list, tuple)) and len(value) == 16 and \
                not any(isinstance(v, (list, tuple)) for v in value):
            flat = [ctx.number(elem, v, loc.index(i, value)) for i, v in enumerate(value)]
            rows = [tuple(flat[4 * r: 4 * r + 4]) for r in range(4)]
        elif isinstance(value, (list, tuple)) and len(value) == 4:
            rows = []
            for r, row in enumerate(value):
                rloc = loc.index(r, value)
                if not isinstance(row, (list, tuple)) or len(row) != 4:
                    ctx.error(rloc, f"expected a row of 4 numbers, got {_show(row)}")
                rows.append(tuple(ctx.number(elem, v, rloc.index(c, row)) for c, v in enumerate(row)))
        else:
            ctx.error(loc, f"expected a {self.type_name}, got {_show(value)}")
        if all(isinstance(v, float) for row in rows for v in row):
            m = np.array(rows, dtype=np.float64)
            if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
                ctx.error(loc, f"last row must be [0, 0, 0, 1] (affine transforms only), got {list(rows[3])}")
            scale = np.abs(m[:3, :3]).max()
            if scale == 0.0 or abs(np.linalg.det(m[:3, :3])) <= 1e-12 * scale ** 3:
                ctx.error(loc, "matrix is singular (its 3x3 part has zero determinant)")
        return tuple(rows)


class TextureName(str):
    """A reference ``{texture: NAME}`` in a material parameter; ``loc`` is its position."""

    loc: Loc


class ColorOrTexture(Field):
    """A colour (number or list of 3, range-checked) or a texture reference
    ``{texture: NAME}``."""

    def __init__(self, default: Any = REQUIRED, *, min: Optional[float] = None, max: Optional[float] = None,
                 doc: str = ""):
        super().__init__(default, doc)
        self.color = Vector(3, min=min, max=max, broadcast=True)

    def describe(self) -> str:
        return self.color.describe() + ", or {texture: NAME}"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if isinstance(value, Mapping) and "texture" in value:
            rec = _TEXTURE_REF.validate(value, loc, ctx)
            name = TextureName(rec["texture"])
            name.loc = rec.locs["texture"]
            return name
        try:
            return self.color.validate(value, loc, ctx)
        except SceneFileError as e:
            if not isinstance(value, Mapping) or e.key_path != loc.path:
                raise
            keys = ", ".join(f"'{k}'" for k in value)
            ctx.error(loc, f"expected a {self.describe()}, got a mapping with key(s) {keys}"
                           f"{_suggest(next(iter(value), ''), ['texture'])}")


class MaterialName(str):
    """A reference to another material by name (e.g. the components of a "mix");
    ``loc`` is its position."""

    loc: Loc


class MaterialRef(String):
    """Name of a material under 'materials' (resolved to an id when the scene is built)."""

    type_name = "material name"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        value = super().validate(value, loc, ctx)
        name = MaterialName(value)
        name.loc = loc
        return name


class ScalarOrTexture(Field):
    """A number (range-checked) or a texture reference ``{texture: NAME}`` whose first
    channel is used."""

    def __init__(self, default: Any = REQUIRED, *, min: Optional[float] = None, max: Optional[float] = None,
                 doc: str = ""):
        super().__init__(default, doc)
        self.number = Number(min=min, max=max)

    def describe(self) -> str:
        return self.number.describe() + ", or {texture: NAME}"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if isinstance(value, Mapping) and "texture" in value:
            rec = _TEXTURE_REF.validate(value, loc, ctx)
            name = TextureName(rec["texture"])
            name.loc = rec.locs["texture"]
            return name
        return self.number.validate(value, loc, ctx)


class TextureRefField(Field):
    """A texture reference ``{texture: NAME}`` (no constant form)."""

    def __init__(self, default: Any = None, doc: str = ""):
        super().__init__(default, doc)

    def describe(self) -> str:
        return "{texture: NAME}"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not isinstance(value, Mapping):
            ctx.error(loc, f"expected {{texture: NAME}}, got {value!r}")
        rec = _TEXTURE_REF.validate(value, loc, ctx)
        name = TextureName(rec["texture"])
        name.loc = rec.locs["texture"]
        return name


class Validated(dict):
    """A validated record: a dict of every field (defaults filled in) that also keeps
    ``loc`` (its own location), ``locs`` (location of each given key's value) and
    ``given`` (the keys present in the input)."""

    def __init__(self, *args, loc: Optional[Loc] = None, **kwargs):
        super().__init__(*args, **kwargs)
        self.loc: Loc = loc or Loc()
        self.locs: Dict[str, Loc] = {}
        self.given: set = set()


class Record(Field):
    """A mapping with a fixed set of keys.

    ``fields``: key -> Field. ``tag``/``variants``: the value of key ``tag`` selects
    extra keys (e.g. ``type: sun`` allows ``irradiance``); a variant is a dict of fields.
    ``one_of``: groups of keys of which exactly one must be given; ``exclusive``: groups
    of keys that cannot be mixed; ``requires``: key -> keys that must accompany it.
    ``check(record, ctx)`` runs after the fields are valid. ``default=EMPTY`` validates
    an empty mapping when the key is absent (all defaults).
    """

    type_name = "mapping"

    def __init__(self, fields: Mapping[str, Field], *, default: Any = REQUIRED, doc: str = "",
                 tag: Optional[str] = None, variants: Optional[Mapping[str, Mapping[str, Field]]] = None,
                 one_of: Sequence[Sequence[str]] = (), exclusive: Sequence[Sequence[str]] = (),
                 requires: Optional[Mapping[str, Sequence[str]]] = None,
                 check: Optional[Callable[["Validated", ValidationContext], None]] = None):
        super().__init__(default, doc)
        self.fields = dict(fields)
        self.tag = tag
        self.variants = {k: dict(v) for k, v in (variants or {}).items()}
        self.one_of = [tuple(g) for g in one_of]
        self.exclusive = [tuple(g) for g in exclusive]
        self.requires = {k: tuple(v) for k, v in (requires or {}).items()}
        self.check = check

    def extend(self, fields: Optional[Mapping[str, Field]] = None, **kwargs) -> "Record":
        """A copy of this record with more (or replaced) fields; keyword arguments
        override the other constructor arguments."""
        args = dict(default=self.default, doc=self.doc, tag=self.tag, variants=self.variants,
                    one_of=self.one_of, exclusive=self.exclusive, requires=self.requires, check=self.check)
        args.update(kwargs)
        return Record({**self.fields, **(fields or {})}, **args)

    def missing(self, loc: Loc, ctx: ValidationContext) -> Any:
        if self.default is EMPTY:
            return self.validate({}, loc, ctx)
        return super().missing(loc, ctx)

    def describe(self) -> str:
        return "mapping with keys " + ", ".join(self.fields)

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not isinstance(value, Mapping):
            ctx.error(loc, f"expected a mapping (keys: {', '.join(self._all_keys())}), got {_show(value)}")
        for k in value:
            if not isinstance(k, str):
                ctx.error(loc.key(k, value), f"keys must be strings, got {_show(k)}")
        fields = dict(self.fields)
        variant = None
        if self.tag is not None and self.tag not in value and self.fields[self.tag].required \
                and not self._covered(self.tag):
            self._missing_key(self.tag, self.fields[self.tag], loc, ctx)
        if self.tag is not None and self.tag in value:
            variant = self.fields[self.tag].validate(value[self.tag], loc.value(self.tag, value), ctx)
            fields.update(self.variants.get(variant, {}))
        for k in value:
            if k not in fields:
                self._unknown_key(k, value, fields, variant, loc, ctx)
        for group in self.one_of:
            present = [k for k in group if k in value]
            if len(present) != 1:
                keys = " or ".join(f"'{k}'" for k in group)
                if not present:
                    ctx.error(loc, f"missing key: give exactly one of {keys}")
                ctx.error(loc.key(present[1], value),
                          f"'{present[0]}' and '{present[1]}' cannot be combined: give exactly one of {keys}")
        for i, ga in enumerate(self.exclusive):
            for gb in self.exclusive[i + 1:]:
                a = [k for k in ga if k in value]
                b = [k for k in gb if k in value]
                if a and b:
                    ctx.error(loc.key(b[0], value), f"'{b[0]}' cannot be combined with '{a[0]}'")
        for k, needs in self.requires.items():
            if k in value:
                for n in needs:
                    if n not in value:
                        ctx.error(loc.key(k, value), f"'{k}' requires '{n}' to be given as well")
        out = Validated(loc=loc)
        for k, f in fields.items():
            if k in value:
                vloc = loc.value(k, value)
                out[k] = f.validate(value[k], vloc, ctx)
                out.locs[k] = vloc
                out.given.add(k)
            elif f.required:
                if not self._covered(k):
                    self._missing_key(k, f, loc, ctx)
                out[k] = None
            else:
                out[k] = f.missing(loc.value(k, value), ctx)
        if self.check is not None:
            self.check(out, ctx)
        return out

    def _missing_key(self, k: str, f: Field, loc: Loc, ctx: ValidationContext) -> NoReturn:
        extra = f"; allowed values: {', '.join(f.choices)}" if isinstance(f, Choice) else ""
        ctx.error(loc, f"missing required key '{k}' ({f.doc or f.describe()}){extra}")

    def _covered(self, key: str) -> bool:
        """Required keys inside a one_of group are enforced by the group."""
        return any(key in g for g in self.one_of)

    def _all_keys(self) -> List[str]:
        keys = list(self.fields)
        for v in self.variants.values():
            keys += [k for k in v if k not in keys]
        return keys

    def _unknown_key(self, k: str, value: Mapping, fields: Mapping[str, Field], variant: Optional[str],
                     loc: Loc, ctx: ValidationContext) -> NoReturn:
        kloc = loc.key(k, value)
        allowed = ", ".join(fields)
        if self.tag is not None and variant is not None:
            owners = [name for name, v in self.variants.items() if k in v]
            if owners:
                ctx.error(kloc, f"key '{k}' is not allowed with {self.tag} '{variant}' (only with "
                                f"{', '.join(owners)}){_suggest(k, fields)}; allowed keys: {allowed}")
        if self.tag is not None and variant is None:
            allowed = ", ".join(self._all_keys())
            if any(k in v for v in self.variants.values()):
                ctx.error(kloc, f"key '{k}' needs '{self.tag}' to be given; allowed keys: {allowed}")
        ctx.error(kloc, f"unknown key '{k}'{_suggest(k, fields if variant else self._all_keys())}; "
                        f"allowed keys: {allowed}")


class MapOf(Field):
    """A mapping from user-chosen names to values of one field type."""

    type_name = "mapping of names"

    def __init__(self, value: Field, default: Any = REQUIRED, doc: str = ""):
        super().__init__(default, doc)
        self.value = value

    def describe(self) -> str:
        return f"mapping NAME -> ({self.value.describe()})"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if value is None:
            value = {}
        if not isinstance(value, Mapping):
            ctx.error(loc, f"expected a mapping of names, got {_show(value)}")
        out = Validated(loc=loc)
        for k, v in value.items():
            if not isinstance(k, str) or not k:
                ctx.error(loc.key(k, value), f"names must be non-empty strings, got {_show(k)}")
            vloc = loc.value(k, value)
            out[k] = self.value.validate(v, vloc, ctx)
            out.locs[k] = vloc
            out.given.add(k)
        return out


class ListOf(Field):
    """A list of values of one field type, with at least ``min_items`` items."""

    type_name = "list"

    def __init__(self, item: Field, default: Any = REQUIRED, *, min_items: int = 0, doc: str = ""):
        super().__init__(default, doc)
        self.item = item
        self.min_items = min_items

    def describe(self) -> str:
        return f"list of ({self.item.describe()})"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if value is None:
            value = []
        if not isinstance(value, (list, tuple)):
            ctx.error(loc, f"expected a list, got {_show(value)}")
        if len(value) < self.min_items:
            ctx.error(loc, f"expected at least {self.min_items} item{'s' if self.min_items != 1 else ''}, "
                           f"got {len(value)}")
        return [self.item.validate(v, loc.index(i, value), ctx) for i, v in enumerate(value)]


def map_values(tree: Any, fn: Callable[[Any], Any]) -> Any:
    """Rebuilds a validated tree, applying ``fn`` to every leaf (numbers, strings, ...).

    Validated records keep their locations, TextureName references are kept as they
    are; used e.g. to replace random-distribution placeholders by samples.
    """
    if isinstance(tree, Validated):
        out = Validated(((k, map_values(v, fn)) for k, v in tree.items()), loc=tree.loc)
        out.locs = dict(tree.locs)
        out.given = set(tree.given)
        return out
    if isinstance(tree, TextureName):
        return tree
    if isinstance(tree, list):
        return [map_values(v, fn) for v in tree]
    if isinstance(tree, tuple):
        return tuple(map_values(v, fn) for v in tree)
    return fn(tree)


# ---------------------------------------------------------------------------------------
# The scene schema

_ID_MAX = 65535
_TEXTURE_REF = Record({"texture": String(doc="name of a texture under 'textures'")})


def _color(default: Any, lo: Optional[float], hi: Optional[float], doc: str) -> Vector:
    return Vector(3, default, min=lo, max=hi, broadcast=True, doc=doc)


def _check_look_at(rec: Validated, ctx: ValidationContext) -> None:
    eye, target = rec["eye"], rec["target"]
    if all(isinstance(v, float) for v in eye + target) and eye == target:
        ctx.error(rec.locs["target"], "'eye' and 'target' coincide")


LOOK_AT = Record({
    "eye": Vector(3, doc="camera position"),
    "target": Vector(3, doc="point the camera looks at (image centre)"),
    "up": Vector(3, (0.0, 1.0, 0.0), doc="world up vector; image y points along -up"),
}, doc="camera pose from eye / target / up", check=_check_look_at)

CAMERA = Record({
    "width": Integer(min=1, max=65536, doc="image width in pixels"),
    "height": Integer(min=1, max=65536, doc="image height in pixels"),
    "fov_y": Number(min=0, max=180, min_open=True, max_open=True,
                    doc="vertical field of view in degrees (principal point at the image centre)"),
    "fx": Number(min=0, min_open=True, doc="focal length in pixels along x (OpenCV K)"),
    "fy": Number(None, min=0, min_open=True, doc="focal length in pixels along y (with fx)"),
    "cx": Number(None, doc="principal point x in pixels (default width / 2)"),
    "cy": Number(None, doc="principal point y in pixels (default height / 2)"),
    "look_at": LOOK_AT,
    "world_from_camera": Matrix4(doc="camera-to-world pose (OpenCV camera: x right, y down, z forward)"),
}, doc="pinhole camera (OpenCV convention)",
    one_of=[("fov_y", "fx"), ("look_at", "world_from_camera")],
    exclusive=[("fov_y",), ("fx", "fy", "cx", "cy")],
    requires={"fx": ("fy",), "fy": ("fx",), "cx": ("cy",), "cy": ("cx",)})

TEXTURE = Record({
    "type": Choice(["image", "constant"], doc="texture plugin"),
}, tag="type", variants={
    "image": {
        "file": FilePath(doc="image file read by OpenImageIO (relative to the scene file)"),
        "colorspace": Choice(["auto", "srgb", "linear"], "auto",
                             doc="how to decode the pixels (auto: 8-bit images are sRGB)"),
        "wrap": Choice(["repeat", "clamp", "mirror"], "repeat", doc="behaviour outside [0, 1] uv"),
        "scale": _color((1.0, 1.0, 1.0), None, None, "multiplies the texel values"),
        "uv_scale": Vector(2, (1.0, 1.0), broadcast=True, doc="uv scale S in uv' = R S uv + offset (non-zero)"),
        "uv_offset": Vector(2, (0.0, 0.0), broadcast=True, doc="uv offset, applied last"),
        "uv_rotation": Number(0.0, doc="counter-clockwise uv rotation in degrees, after scaling"),
    },
    "constant": {
        "value": _color((1.0, 1.0, 1.0), None, None, "the constant colour"),
    },
}, doc="texture")

MATERIAL = Record({
    "type": Choice(["diffuse", "emissive", "coated", "conductor", "dielectric", "mix", "principled"],
                   doc="material plugin"),
}, tag="type", variants={
    "diffuse": {
        "albedo": ColorOrTexture((0.5, 0.5, 0.5), min=0, max=1, doc="Lambertian reflectance"),
        "alpha": ScalarOrTexture(1.0, min=0, max=1, doc="coverage for cut-outs (texture: alpha channel, else first)"),
        "alpha_cutoff": Number(0.5, min=0, max=1, doc="hits with alpha below this are not surfaces"),
    },
    "emissive": {
        "radiance": _color((1.0, 1.0, 1.0), 0, None, "emitted radiance, W/(m^2 sr) per channel"),
        "strength": Number(1.0, min=0, doc="multiplies radiance"),
        "albedo": ColorOrTexture((0.0, 0.0, 0.0), min=0, max=1, doc="diffuse reflectance of the emitter"),
        "two_sided": Bool(False, doc="emit from both faces (default: the front face only)"),
    },
    "coated": {
        "albedo": ColorOrTexture((0.5, 0.5, 0.5), min=0, max=1, doc="Lambertian base reflectance"),
        "ior": Number(1.5, min=1, max=4, doc="index of refraction of the coat (1: no coat)"),
        "roughness": Number(0.0, min=0, max=1, doc="coat roughness (GGX alpha = roughness^2; 0: smooth)"),
        "specular": Number(1.0, min=0, max=1, doc="scales the coat reflection (the rest is absorbed)"),
    },
    "conductor": {
        "metal": Choice(["aluminium", "aluminum", "chrome", "chromium", "copper", "gold", "iron", "silver", "none"],
                        None, doc="measured metal preset (default aluminium unless eta/k are given; none: "
                                  "perfect mirror)"),
        "eta": _color(None, 0, None, "real part of the complex IOR per channel (with k, instead of metal)"),
        "k": _color(None, 0, None, "imaginary part (extinction) of the complex IOR per channel"),
        "roughness": Number(None, min=0, max=1, doc="GGX roughness (alpha = roughness^2; default 0.3; 0: mirror)"),
        "anisotropy": Number(None, min=-1, max=1, doc="stretches the highlight along the surface tangent"),
        "roughness_u": Number(None, min=0, max=1, doc="roughness along the tangent (instead of roughness/anisotropy)"),
        "roughness_v": Number(None, min=0, max=1, doc="roughness along the bitangent"),
        "specular_tint": ColorOrTexture(None, min=0, max=1, doc="multiplies the reflection"),
        "bump_map": TextureRefField(doc="height map (red channel)"),
        "bump_scale": Number(1.0, min=-100, max=100, doc="height in uv units"),
    },
    "dielectric": {
        "ior": Number(1.5, min=1, max=10, doc="index of refraction inside (must differ from exterior_ior "
                                             "unless thin)"),
        "exterior_ior": Number(1.0, min=1, max=10, doc="index of refraction outside"),
        "roughness": Number(0.0, min=0, max=1, doc="GGX roughness (0: smooth glass)"),
        "thin": Bool(False, doc="thin-walled (windows, car glass): no bending, slab reflectance"),
        "transmittance": ColorOrTexture(None, min=0, max=1, doc="tint of the transmitted light"),
    },
    "principled": {
        "base_color": ColorOrTexture((0.8, 0.8, 0.8), min=0, max=1, doc="base colour (F0 of metals)"),
        "metallic": ScalarOrTexture(0.0, min=0, max=1, doc="metalness (texture: red channel)"),
        "roughness": ScalarOrTexture(0.5, min=0, max=1, doc="GGX roughness, clamped to >= 0.03 (texture: red channel)"),
        "metallic_roughness": TextureRefField(doc="glTF packed texture: metallic = blue x metallic, "
                                                  "roughness = green x roughness"),
        "specular": Number(0.5, min=0, max=1, doc="dielectric F0 = 0.08 specular"),
        "clearcoat": Number(0.0, min=0, max=1, doc="clear coat strength"),
        "clearcoat_roughness": Number(0.03, min=0, max=1, doc="clear coat roughness"),
        "transmission": Number(0.0, min=0, max=1, doc="rough glass fraction, tinted by base_color"),
        "ior": Number(1.5, min=1.01, max=3, doc="index of refraction (transmission)"),
        "emission": ColorOrTexture((0.0, 0.0, 0.0), min=0, doc="emitted radiance (front face)"),
        "emission_strength": Number(1.0, min=0, max=1e6, doc="multiplies emission"),
        "normal_map": TextureRefField(doc="tangent-space normal map (glTF convention, +Y up; linear)"),
        "normal_scale": Number(1.0, min=-10, max=10, doc="scales the normal map's X and Y"),
        "bump_map": TextureRefField(doc="height map (red channel)"),
        "bump_scale": Number(1.0, min=-100, max=100, doc="height in uv units"),
        "alpha": ScalarOrTexture(1.0, min=0, max=1, doc="coverage (texture: alpha channel, else red)"),
        "alpha_factor": Number(1.0, min=0, max=1, doc="multiplies alpha"),
        "alpha_mode": Choice(["opaque", "mask", "blend"], "blend", doc="glTF alpha mode (blend: cut-out at 0.5)"),
        "alpha_cutoff": Number(0.5, min=0, max=1, doc="coverage threshold of the mask mode"),
    },
    "mix": {
        "material_a": MaterialRef(doc="material used where weight = 0"),
        "material_b": MaterialRef(doc="material used where weight = 1"),
        "weight": ScalarOrTexture(0.5, min=0, max=1, doc="fraction of material_b (a texture: its first channel)"),
        "stochastic": Bool(False, doc="where 0 < weight < 1, shade with one material chosen per point "
                                      "(probability = weight) instead of both: cheaper, a little noisier"),
    },
}, doc="material")


def _check_rotate(rec: Validated, ctx: ValidationContext) -> None:
    axis = rec.get("axis")
    if axis is not None and all(isinstance(v, float) for v in axis) and not any(axis):
        ctx.error(rec.locs["axis"], "rotation axis must be a non-zero vector")


ROTATE = Record({
    "axis": Vector(3, doc="rotation axis (normalised)"),
    "angle": Number(None, doc="rotation angle in degrees (right-handed about axis; with axis)"),
    "euler": Vector(3, doc="rotation angles in degrees about the world x, y, z axes"),
    "order": Choice(["xyz", "xzy", "yxz", "yzx", "zxy", "zyx"], "xyz",
                    doc="order in which the euler rotations are applied (xyz: R = Rz Ry Rx)"),
}, doc="rotation: {axis, angle} or {euler, order}",
    one_of=[("axis", "euler")], exclusive=[("axis", "angle"), ("euler", "order")],
    requires={"axis": ("angle",), "angle": ("axis",)}, check=_check_rotate)

MESH_FILE = Record({
    "file": FilePath(doc="OBJ (+MTL), PLY, glTF or GLB file (relative to the scene file)"),
}, doc="mesh loaded from a file")

_SIZE_DOC = "edge lengths"
OBJECT = Record({
    "name": String(None, doc="free name, reported in meta.json"),
    "mesh": MESH_FILE,
    "primitive": Choice(["sphere", "box", "plane"], doc="built-in procedural mesh"),
    "class_id": Integer(min=0, max=_ID_MAX, doc="semantic class label (0 is also the background)"),
    "instance_id": Integer(None, min=1, max=_ID_MAX, doc="instance label (default: instance handle + 1)"),
    "material": String(None, doc="name of a material under 'materials' (default: the mesh's own)"),
    "translate": Vector(3, (0.0, 0.0, 0.0), doc="translation"),
    "rotate": ROTATE.extend(default=None),
    "scale": Vector(3, (1.0, 1.0, 1.0), min=0, min_open=True, broadcast=True,
                    doc="scale factors (positive; use world_from_object to mirror)"),
    "world_from_object": Matrix4(None, doc="object-to-world matrix instead of translate/rotate/scale"),
}, tag="primitive", variants={
    "sphere": {
        "radius": Number(1.0, min=0, min_open=True, doc="sphere radius"),
        "segments": Integer(64, min=3, max=4096, doc="subdivisions around the y axis"),
        "rings": Integer(32, min=2, max=4096, doc="subdivisions from pole to pole"),
    },
    "box": {
        "size": Vector(3, (1.0, 1.0, 1.0), min=0, min_open=True, broadcast=True,
                       doc="edge lengths along x, y, z (centred at the origin)"),
    },
    "plane": {
        "size": Vector(2, (1.0, 1.0), min=0, min_open=True, broadcast=True,
                       doc="edge lengths along x and z (the y = 0 plane, normal +y)"),
    },
}, doc="an instance of a mesh file or primitive",
    one_of=[("mesh", "primitive")],
    exclusive=[("translate", "rotate", "scale"), ("world_from_object",)])
OBJECT.fields["rotate"].doc = "rotation {axis, angle} or {euler, order}, in degrees"

LIGHT = Record({
    "type": Choice(["sun", "environment", "point", "envmap", "sky", "spot"], doc="light plugin"),
    "name": String(None, doc="free name, reported in meta.json"),
}, tag="type", variants={
    "point": {
        "position": Vector(3, (0.0, 0.0, 0.0), doc="light position"),
        "intensity": _color((1.0, 1.0, 1.0), 0, None, "radiant intensity, W/sr per channel"),
        "strength": Number(1.0, min=0, doc="multiplies intensity"),
    },
    "sun": {
        "direction": Vector(3, (0.0, 0.0, 1.0), doc="direction from the scene towards the sun"),
        "irradiance": _color((1.0, 1.0, 1.0), 0, None, "W/m^2 per channel on a surface facing the sun"),
        "strength": Number(1.0, min=0, doc="multiplies irradiance"),
        "angular_diameter": Number(0.53, min=0, max=90, max_open=True,
                                   doc="apparent diameter in degrees (0: hard shadows)"),
    },
    "environment": {
        "radiance": _color((1.0, 1.0, 1.0), 0, None, "constant sky radiance per channel"),
        "strength": Number(1.0, min=0, doc="multiplies radiance"),
    },
    "envmap": {
        "file": FilePath(doc="equirectangular HDR image (EXR/HDR, linear), relative to the scene file"),
        "strength": Number(1.0, min=0, doc="multiplies the map"),
        "rotation": Number(0.0, doc="rotation in degrees about the map's up axis (right-handed)"),
        "up": Vector(3, (0.0, 1.0, 0.0), doc="world direction of the map's top row"),
        "visible": Bool(True, doc="whether camera rays see the map directly"),
    },
    "sky": {
        "elevation": Number(45.0, min=0, max=90, doc="sun elevation above the horizon, degrees"),
        "azimuth": Number(0.0, doc="sun compass bearing in degrees: 0 = -z, 90 = +x, 180 = +z"),
        "turbidity": Number(3.0, min=1.7, max=10, doc="atmospheric turbidity (Preetham 1999)"),
        "strength": Number(1.0, min=0, doc="multiplies sky and sun (radiance in luminance / 683 lm/W)"),
        "ground_albedo": _color((0.2, 0.2, 0.2), 0, 1, "reflectance of the ground below the horizon"),
        "sun": Bool(True, doc="add the 0.53 degree sun disc with Preetham's attenuated radiance"),
        "visible": Bool(True, doc="whether camera rays see the sky directly"),
    },
    "spot": {
        "position": Vector(3, (0.0, 0.0, 0.0), doc="light position"),
        "direction": Vector(3, (0.0, -1.0, 0.0), doc="cone axis"),
        "intensity": _color((1.0, 1.0, 1.0), 0, None, "radiant intensity on the axis, W/sr per channel"),
        "strength": Number(1.0, min=0, doc="multiplies intensity"),
        "cone_angle": Number(30.0, min=0, max=180, min_open=True, doc="half-angle where the light ends, degrees"),
        "falloff_start": Number(None, min=0, max=180,
                                doc="half-angle where the smooth falloff starts, degrees (default min(25, cone_angle))"),
    },
}, doc="light (area lights come from emissive materials)")

RENDER = Record({
    "spp": Integer(16, min=1, max=1 << 20, doc="samples per pixel"),
    "max_depth": Integer(8, min=1, max=1024, doc="maximum ray segments from the camera (1: emitters only)"),
    "rr_depth": Integer(5, min=0, max=1024, doc="path length at which Russian roulette starts"),
    "seed": Integer(0, min=0, max=(1 << 64) - 1, doc="random seed (images are deterministic per seed)"),
    "threads": Integer(0, min=0, max=4096, doc="worker threads (0: all cores)"),
    "tile_size": Integer(16, min=1, max=4096, doc="tile edge in pixels"),
    "texture_filtering": Bool(True, doc="filter textures over the ray footprint (ray cones)"),
}, default=EMPTY, doc="render settings (keyword arguments of Scene.render)")

SCENE_SCHEMA = Record({
    "version": Integer(1, min=1, max=1, doc="scene file format version"),
    "description": String(None, doc="free text"),
    "camera": CAMERA,
    "textures": MapOf(TEXTURE, {}, doc="named textures"),
    "materials": MapOf(MATERIAL, {}, doc="named materials"),
    "objects": ListOf(OBJECT, min_items=1, doc="instances of meshes and primitives"),
    "lights": ListOf(LIGHT, [], doc="lights"),
    "render": RENDER,
}, doc="a synthgen scene")


def format_schema(field: Field = SCENE_SCHEMA, indent: int = 0) -> str:
    """Human-readable description of a schema: every key with type, default and doc."""
    lines: List[str] = []
    pad = "  " * indent

    def default_text(rec: Record, k: str, f: Field) -> str:
        groups = [g for g in rec.one_of if k in g]
        if groups:
            return "exactly one of " + " / ".join(groups[0]) + " required"
        if f.required:
            return "required"
        if f.default is EMPTY or f.default is None:
            return "optional"
        d = f.default
        if isinstance(d, tuple) and d and all(x == d[0] for x in d) and \
                (isinstance(f, ColorOrTexture) or (isinstance(f, Vector) and f.broadcast)):
            d = d[0]
        return f"default {_fmt_default(d)}"

    def walk(rec: Record, ind: int, keys: Optional[Mapping[str, Field]] = None) -> None:
        p = "  " * ind
        for k, f in (keys or rec.fields).items():
            lines.append(f"{p}{k}: {f.describe() if not isinstance(f, (Record, MapOf, ListOf)) else f.type_name}"
                         f" ({default_text(rec, k, f)}) - {f.doc}")
            sub = f
            while hasattr(sub, "inner") or isinstance(sub, (MapOf, ListOf)):  # `inner`: wrappers such as
                if hasattr(sub, "inner"):                                     # scenario.Random
                    sub = sub.inner
                else:
                    sub = sub.value if isinstance(sub, MapOf) else sub.item
            if isinstance(sub, Record) and sub is not rec:
                walk(sub, ind + 1)
        if rec.variants and keys is None:
            for name, v in rec.variants.items():
                lines.append(f"{p}[{rec.tag}: {name}]")
                walk(rec, ind + 1, v)

    if isinstance(field, Record):
        walk(field, indent)
    else:
        lines.append(f"{pad}{field.describe()}")
    return "\n".join(lines)


def _fmt_default(d: Any) -> str:
    if isinstance(d, bool):
        return str(d).lower()
    if isinstance(d, float):
        return _fmt_num(d)
    if isinstance(d, tuple):
        return "[" + ", ".join(_fmt_default(x) for x in d) + "]"
    if isinstance(d, (dict, list)) and not d:
        return "{}" if isinstance(d, dict) else "[]"
    return str(d)


# ---------------------------------------------------------------------------------------
# Building


def _rotation_matrix(axis: Sequence[float], degrees: float) -> np.ndarray:
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    th = math.radians(degrees)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def world_from_object(obj: Mapping[str, Any]) -> np.ndarray:
    """The 4x4 (float64) object-to-world matrix of a validated object: its
    ``world_from_object``, or T * R * S from ``translate``, ``rotate``, ``scale``."""
    if obj.get("world_from_object") is not None:
        return np.array(obj["world_from_object"], dtype=np.float64)
    m = np.eye(4)
    R = np.eye(3)
    rot = obj.get("rotate")
    if rot:
        if rot.get("axis") is not None:
            R = _rotation_matrix(rot["axis"], rot["angle"])
        else:
            for ax, ang in zip(rot["order"], [rot["euler"]["xyz".index(c)] for c in rot["order"]]):
                R = _rotation_matrix(_AXES[ax], ang) @ R
    m[:3, :3] = R @ np.diag(np.asarray(obj["scale"], dtype=np.float64))
    m[:3, 3] = obj["translate"]
    return m


def _params(rec: Validated, skip: Iterable[str] = ("type", "name")) -> Dict[str, Any]:
    """Plugin parameters: only the keys given in the file (the core owns the defaults)."""
    out = {}
    for k in rec.given:
        if k in skip:
            continue
        v = rec[k]
        out[k] = list(v) if isinstance(v, tuple) else v
    return out


def _material_order(mats: Mapping[str, Validated], ctx: ValidationContext) -> List[str]:
    """Material names ordered so that every material comes after the materials it refers
    to (e.g. the components of a "mix"); a reference cycle is an error at its entry."""
    order: List[str] = []
    state: Dict[str, int] = {}  # 1: visiting, 2: done

    def visit(name: str, via: Optional[Loc]) -> None:
        if state.get(name) == 2:
            return
        if state.get(name) == 1:
            ctx.error(via or mats[name].loc, f"material '{name}' refers to itself through a reference cycle")
        state[name] = 1
        for v in mats[name].values():
            if isinstance(v, MaterialName) and str(v) in mats:
                visit(str(v), v.loc)
        state[name] = 2
        order.append(name)

    for n, mat in mats.items():  # unknown names first, with the full list of materials
        for v in mat.values():
            if isinstance(v, MaterialName) and str(v) not in mats:
                _lookup(ctx, {k: 0 for k in mats}, str(v), v.loc, "material", "materials")
    for n in mats:
        visit(n, None)
    return order


def _lookup(ctx: ValidationContext, table: Mapping[str, int], name: str, loc: Loc, what: str, section: str) -> int:
    if name not in table:
        defined = ", ".join(sorted(table)) if table else "none"
        ctx.error(loc, f"unknown {what} '{name}'{_suggest(name, table)}; {section} defined: {defined}")
    return table[name]


def _primitive_mesh(obj: Validated) -> Tuple[tuple, Dict[str, np.ndarray], np.ndarray]:
    """(cache key, unit mesh arrays, object_from_unit scale) of a primitive object: one
    unit mesh per kind (and tessellation) is shared by every instance, sized by scaling."""
    kind = obj["primitive"]
    if kind == "sphere":
        return ((kind, obj["segments"], obj["rings"]), primitives.uv_sphere(1.0, obj["segments"], obj["rings"]),
                np.array([obj["radius"]] * 3))
    if kind == "box":
        return (kind,), primitives.box((1.0, 1.0, 1.0)), np.array(obj["size"])
    sx, sz = obj["size"]
    return (kind,), primitives.plane(1.0, 1.0), np.array([sx, 1.0, sz])


def camera_from_spec(cam: Validated, ctx: ValidationContext) -> PinholeCamera:
    """PinholeCamera of a validated ``camera`` record."""
    with ctx.core(cam.locs.get("look_at", cam.loc)):
        if cam.get("look_at") is not None:
            la = cam["look_at"]
            wfc = PinholeCamera.look_at(list(la["eye"]), list(la["target"]), list(la["up"]))
        else:
            wfc = np.array(cam["world_from_camera"], dtype=np.float32)
    w, h = cam["width"], cam["height"]
    with ctx.core(cam.loc):
        if cam.get("fov_y") is not None:
            return PinholeCamera.from_fov(cam["fov_y"], w, h, wfc)
        cx = cam["cx"] if cam.get("cx") is not None else 0.5 * w
        cy = cam["cy"] if cam.get("cy") is not None else 0.5 * h
        return PinholeCamera(cam["fx"], cam["fy"], cx, cy, w, h, wfc)


def build_validated(spec: Validated, ctx: ValidationContext) -> Tuple[Scene, Dict[str, Any], Dict[str, Any]]:
    """Builds a Scene from a validated scene spec (see :func:`validate_scene`).

    Returns ``(scene, render_settings, meta)`` like :func:`load_scene`. Errors of the
    native core are re-raised as :class:`SceneFileError` at the offending entry.
    """
    scene = Scene()
    meta: Dict[str, Any] = {"source": ctx.source, "description": spec.get("description"),
                            "textures": {}, "materials": {}, "objects": [], "lights": []}

    textures: Dict[str, int] = meta["textures"]
    for name, tex in spec["textures"].items():
        params = _params(tex)
        if "file" in params:
            params["filename"] = params.pop("file")
        with ctx.core(tex.loc):
            textures[name] = scene.add_texture(tex["type"], params)

    materials: Dict[str, int] = meta["materials"]
    for name in _material_order(spec["materials"], ctx):
        mat = spec["materials"][name]
        params = _params(mat)
        for k, v in params.items():
            if isinstance(v, TextureName):
                params[k] = TextureRef(_lookup(ctx, textures, str(v), v.loc, "texture", "textures"))
            elif isinstance(v, MaterialName):
                params[k] = _lookup(ctx, materials, str(v), v.loc, "material", "materials")
        with ctx.core(mat.loc):
            materials[name] = scene.add_material(mat["type"], params)

    mesh_cache: Dict[Any, Dict[str, Any]] = {}
    for obj in spec["objects"]:
        info: Dict[str, Any] = {"name": obj.get("name")}
        if obj.get("mesh") is not None:
            path = obj["mesh"]["file"]
            key: tuple = ("file", path)
            if key not in mesh_cache:
                with ctx.core(obj.locs["mesh"]):
                    mesh_cache[key] = dict(scene.load_mesh_file(path))
            info["mesh"] = path
            instance_from_object = np.eye(4)
        else:
            key, arrays, size = _primitive_mesh(obj)
            if key not in mesh_cache:
                with ctx.core(obj.loc):
                    mesh_cache[key] = {"mesh_id": scene.add_mesh(**arrays, name=obj["primitive"])}
            info["primitive"] = obj["primitive"]
            instance_from_object = np.diag([*size, 1.0])
        mesh_id = mesh_cache[key]["mesh_id"]
        material_id = -1
        if obj.get("material") is not None:
            material_id = _lookup(ctx, materials, obj["material"], obj.locs["material"], "material", "materials")
        wfo = world_from_object(obj)
        with ctx.core(obj.locs.get("world_from_object", obj.loc)):
            handle = scene.add_instance(mesh_id, (wfo @ instance_from_object).astype(np.float32),
                                        class_id=obj["class_id"], instance_id=obj.get("instance_id"),
                                        material_id=material_id)
        info.update({
            "instance": handle,
            "instance_id": obj["instance_id"] if obj.get("instance_id") is not None else handle + 1,
            "class_id": obj["class_id"],
            "mesh_id": mesh_id,
            "material": obj.get("material"),
            "world_from_object": wfo.tolist(),  # of the primitive / mesh frame, before sizing
        })
        meta["objects"].append(info)

    for light in spec["lights"]:
        params = _params(light)
        if "file" in params:
            params["filename"] = params.pop("file")
        with ctx.core(light.loc):
            lid = scene.add_light(light["type"], params)
        meta["lights"].append({"name": light.get("name"), "type": light["type"], "id": lid})

    camera = camera_from_spec(spec["camera"], ctx)
    scene.set_camera(camera)
    settings = {k: spec["render"][k] for k in RENDER.fields}
    return scene, settings, meta


def validate_render_settings(settings: Mapping[str, Any], source: str = "<render settings>") -> Dict[str, Any]:
    """Checks render settings (e.g. after command-line overrides) against the ``render``
    section of the schema; returns a complete dict of ``Scene.render`` keyword arguments."""
    rec = RENDER.validate(dict(settings), Loc("render"), ValidationContext(source))
    return {k: rec[k] for k in RENDER.fields}


def validate_scene(data: Any, source_name: str = "<scene>", base_dir: Optional[str] = None,
                   context: Optional[ValidationContext] = None) -> Tuple[Validated, ValidationContext]:
    """Validates a scene description (a dict, e.g. from :func:`read_yaml`) against
    :data:`SCENE_SCHEMA`; returns ``(spec, context)``."""
    ctx = context or ValidationContext(source_name, base_dir)
    if data is None:
        ctx.error(Loc(), "the scene file is empty; expected a mapping with at least 'camera' and 'objects'")
    spec = SCENE_SCHEMA.validate(data, Loc.root(data), ctx)
    return spec, ctx


def build_scene(data: Mapping[str, Any], source_name: str = "<scene>", base_dir: Optional[str] = None,
                context: Optional[ValidationContext] = None) -> Tuple[Scene, Dict[str, Any], Dict[str, Any]]:
    """Validates a scene description (dict in the scene file format) and builds it.

    ``source_name`` names the description in error messages; relative file paths are
    resolved against ``base_dir`` (default: the current directory). Returns
    ``(scene, render_settings, meta)``: ``render_settings`` are keyword arguments of
    ``Scene.render``; ``meta`` lists the ids given to named textures and materials and,
    per object, its instance handle, labels, mesh id and world_from_object.
    """
    spec, ctx = validate_scene(data, source_name, base_dir, context)
    return build_validated(spec, ctx)


def load_scene(path: str | os.PathLike) -> Tuple[Scene, Dict[str, Any], Dict[str, Any]]:
    """Loads a YAML scene file: ``(scene, render_settings, meta)``.

    ``scene`` has its camera set; ``scene.render(**render_settings)`` renders it.
    Raises :class:`SceneFileError` (``FILE:LINE:COLUMN: key.path: reason``) on any
    problem in the file or in the files it references.
    """
    path = os.fspath(path)
    data = read_yaml(path)
    scene, settings, meta = build_scene(data, source_name=path, base_dir=os.path.dirname(os.path.abspath(path)))
    with open(path, "rb") as f:
        meta["source_sha256"] = hashlib.sha256(f.read()).hexdigest()
    return scene, settings, meta
