"""Typed schema fields: the tree that validates YAML into plain Python values.

The schema is a tree of small :class:`Field` objects (:class:`Number`, :class:`Integer`,
:class:`Bool`, :class:`String`, :class:`Choice`, :class:`Vector`, :class:`NumberList`,
:class:`Matrix4`, :class:`FilePath`, :class:`Record`, :class:`MapOf`, :class:`ListOf`,
:class:`ColorOrTexture`, :class:`ScalarOrTexture`, :class:`TextureRefField`,
:class:`MaterialRef`), each with a type, a default, a range and a doc string.
``field.validate(value, loc, ctx)`` returns plain Python values; records become
:class:`Validated` dicts that remember the YAML location of each key and which keys were
given.

Every numeric slot -- scalar fields and each component of vectors, colours and matrices --
is validated through one hook, :meth:`ValidationContext.number`, so a context can accept
more than plain numbers there. :func:`map_values` rebuilds a validated tree keeping its
locations (e.g. to replace random distributions by samples). The plugin records of scene
files and scenarios are not written here: :mod:`synthgen.schema.plugins` generates them
from the plugins' C++ declarations.
"""
from __future__ import annotations

import copy
import math
import numbers
import os
from collections.abc import Mapping, Sequence
from typing import Any, Callable, Dict, List, NoReturn, Optional, Tuple

import numpy as np

from .errors import Loc, SceneFileError, ValidationContext, as_seq, fmt_num, is_bool, show_value, suggest

__all__ = ["REQUIRED", "EMPTY", "Field", "Number", "Integer", "Bool", "String", "Choice", "FilePath", "Vector",
           "NumberList", "InputPath", "Matrix4", "TextureName", "ColorOrTexture", "MaterialName", "MaterialRef", "ScalarOrTexture",
           "TextureRefField", "Validated", "Record", "MapOf", "ListOf", "map_values", "TEXTURE_REF"]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()
EMPTY: Any = type("_EmptyRecord", (), {"__repr__": lambda self: "EMPTY"})()  # record default: all defaults



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
            return f"{'(' if self.min_open else '['}{fmt_num(lo)}, {fmt_num(hi)}{')' if self.max_open else ']'}"
        if lo is not None:
            return f"{'>' if self.min_open else '>='} {fmt_num(lo)}"
        if hi is not None:
            return f"{'<' if self.max_open else '<='} {fmt_num(hi)}"
        return ""

    def describe(self) -> str:
        r = self.range_text()
        if not r:
            return self.type_name
        return f"{self.type_name} in {r}" if r[0] in "[(" else f"{self.type_name} {r}"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        return ctx.number(self, value, loc)

    def _convert(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if is_bool(value) or not isinstance(value, numbers.Real):
            ctx.error(loc, f"expected a {self.describe()}, got {show_value(value)}")
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
            ctx.error(loc, f"value {fmt_num(v)} is out of range; allowed: {self.describe()}")
        return v


class Integer(Number):
    """An integer (booleans and floats are rejected), optionally with a range."""

    type_name = "integer"

    def _convert(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if is_bool(value) or not isinstance(value, numbers.Integral):
            ctx.error(loc, f"expected an {self.describe()}, got {show_value(value)}")
        return int(value)


class Bool(Field):
    """true or false."""

    type_name = "boolean"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not is_bool(value):
            ctx.error(loc, f"expected true or false, got {show_value(value)}")
        return bool(value)


class String(Field):
    """A non-empty string."""

    type_name = "string"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not isinstance(value, str):
            ctx.error(loc, f"expected a string, got {show_value(value)}")
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
        if isinstance(value, bool) and ("on" if value else "off") in self.choices:
            # YAML 1.1 reads a bare off / on (and no / yes) as a boolean.
            value = "on" if value else "off"
        if not isinstance(value, str):
            ctx.error(loc, f"expected one of {', '.join(self.choices)}; got {show_value(value)}")
        if value not in self.choices:
            ctx.error(loc, f"unknown value '{value}'{suggest(value, self.choices)}; "
                           f"allowed values: {', '.join(self.choices)}")
        return value


class InputPath(str):
    """An absolute path validated by :class:`FilePath`: a file the scene or scenario reads
    (so a run can record what its output depends on)."""


class FilePath(String):
    """Path of an existing file; relative paths are resolved against the scene file's
    directory. Validates to an absolute path (an :class:`InputPath`)."""

    type_name = "file path"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        value = super().validate(value, loc, ctx)
        path = os.path.normpath(os.path.join(ctx.base_dir, os.path.expanduser(value)))
        if not os.path.isfile(path):
            how = "" if os.path.isabs(value) else f" (relative paths are resolved against {ctx.base_dir})"
            what = "is a directory" if os.path.isdir(path) else "not found"
            ctx.error(loc, f"file {what}: {path}{how}")
        return InputPath(path)


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
        value = as_seq(value)
        if isinstance(value, (list, tuple)):
            if len(value) != self.size:
                ctx.error(loc, f"expected a {self.describe()}, got {show_value(value)}")
            return tuple(ctx.number(self.element, v, loc.index(i, value)) for i, v in enumerate(value))
        if self.broadcast:
            v = ctx.number(self.element, value, loc)
            return (v,) * self.size
        ctx.error(loc, f"expected a {self.describe()}, got {show_value(value)}")


class NumberList(Field):
    """A list of numbers (a single number is a list of one), each checked like
    ``Number(min, max)``; ``size`` > 0 asks for exactly that many."""

    def __init__(self, default: Any = REQUIRED, *, size: int = 0, min: Optional[float] = None,
                 max: Optional[float] = None, doc: str = ""):
        super().__init__(default, doc)
        self.size = size
        self.element = Number(min=min, max=max)

    def describe(self) -> str:
        r = self.element.range_text()
        n = f"{self.size} numbers" if self.size else "numbers"
        return f"list of {n}" + (f" (each {'in ' if r[0] in '[(' else ''}{r})" if r else "")

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        value = as_seq(value)
        if not isinstance(value, (list, tuple)):
            value = [value]
        if self.size and len(value) != self.size:
            ctx.error(loc, f"expected a {self.describe()}, got {show_value(value)}")
        return tuple(ctx.number(self.element, v, loc.index(i, value)) for i, v in enumerate(value))


class Matrix4(Field):
    """A 4x4 affine matrix, row-major: four rows of four numbers (or 16 numbers); the
    last row must be (0, 0, 0, 1) and the 3x3 part invertible."""

    type_name = "4x4 matrix (4 rows of 4 numbers, last row [0, 0, 0, 1])"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        elem = Number()
        value = as_seq(value)
        if isinstance(value, (list, tuple)) and len(value) == 16 and \
                not any(isinstance(v, (list, tuple)) for v in value):
            flat = [ctx.number(elem, v, loc.index(i, value)) for i, v in enumerate(value)]
            rows = [tuple(flat[4 * r: 4 * r + 4]) for r in range(4)]
        elif isinstance(value, (list, tuple)) and len(value) == 4:
            rows = []
            for r, row in enumerate(value):
                rloc = loc.index(r, value)
                if not isinstance(row, (list, tuple)) or len(row) != 4:
                    ctx.error(rloc, f"expected a row of 4 numbers, got {show_value(row)}")
                rows.append(tuple(ctx.number(elem, v, rloc.index(c, row)) for c, v in enumerate(row)))
        else:
            ctx.error(loc, f"expected a {self.type_name}, got {show_value(value)}")
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


def _texture_name(value: Mapping, loc: Loc, ctx: ValidationContext) -> TextureName:
    """The name of a texture reference ``{texture: NAME}`` (validated), with its position."""
    rec = TEXTURE_REF.validate(value, loc, ctx)
    name = TextureName(rec["texture"])
    name.loc = rec.locs["texture"]
    return name


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
            return _texture_name(value, loc, ctx)
        try:
            return self.color.validate(value, loc, ctx)
        except SceneFileError as e:
            if not isinstance(value, Mapping) or e.key_path != loc.path:
                raise
            keys = ", ".join(f"'{k}'" for k in value)
            ctx.error(loc, f"expected a {self.describe()}, got a mapping with key(s) {keys}"
                           f"{suggest(next(iter(value), ''), ['texture'])}")


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
            return _texture_name(value, loc, ctx)
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
        return _texture_name(value, loc, ctx)


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

    ``fields``: key -> Field. ``tag``/``variants``: the value of key ``tag`` selects extra
    keys (e.g. ``type: sun`` allows ``irradiance``); a variant is a dict of fields or a
    Record (whose own constraints then apply too). Constraints: ``one_of``: groups of keys
    of which exactly one must be given; ``exclusive``: pairs of key groups that cannot be
    mixed; ``requires``: key -> keys that must accompany it. ``aliases``: other spellings
    of a key (validated under the key's own name). ``check(record, ctx)`` runs after the
    fields are valid. ``default=EMPTY`` validates an empty mapping when the key is absent
    (all defaults).
    """

    type_name = "mapping"

    def __init__(self, fields: Mapping[str, Field], *, default: Any = REQUIRED, doc: str = "",
                 tag: Optional[str] = None, variants: Optional[Mapping[str, Any]] = None,
                 one_of: Sequence[Sequence[str]] = (),
                 exclusive: Sequence[Tuple[Sequence[str], Sequence[str]]] = (),
                 requires: Optional[Mapping[str, Sequence[str]]] = None,
                 aliases: Optional[Mapping[str, str]] = None,
                 check: Optional[Callable[["Validated", ValidationContext], None]] = None):
        super().__init__(default, doc)
        self.fields = dict(fields)
        self.tag = tag
        self.variants: Dict[str, Record] = {
            k: v if isinstance(v, Record) else Record(v) for k, v in (variants or {}).items()}
        self.one_of = [tuple(g) for g in one_of]
        self.exclusive = [(tuple(a), tuple(b)) for a, b in exclusive]
        self.requires = {k: tuple(v) for k, v in (requires or {}).items()}
        self.aliases = dict(aliases or {})
        self.check = check

    def extend(self, fields: Optional[Mapping[str, Field]] = None, **kwargs) -> "Record":
        """A copy of this record with more (or replaced) fields; keyword arguments
        override the other constructor arguments."""
        args = dict(default=self.default, doc=self.doc, tag=self.tag, variants=self.variants,
                    one_of=self.one_of, exclusive=self.exclusive, requires=self.requires, aliases=self.aliases,
                    check=self.check)
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
            ctx.error(loc, f"expected a mapping (keys: {', '.join(self._all_keys())}), got {show_value(value)}")
        for k in value:
            if not isinstance(k, str):
                ctx.error(loc.key(k, value), f"keys must be strings, got {show_value(k)}")
        fields = dict(self.fields)
        variant = None
        if self.tag is not None and self.tag not in value and self.fields[self.tag].required \
                and not self._covered(self.tag, self):
            self._missing_key(self.tag, self.fields[self.tag], loc, ctx)
        if self.tag is not None and self.tag in value:
            variant = self.fields[self.tag].validate(value[self.tag], loc.value(self.tag, value), ctx)
        elif self.tag is not None and not self.fields[self.tag].required and self.fields[self.tag].default is not None:
            variant = self.fields[self.tag].default  # a defaulted tag selects its variant (and its defaults)
        if variant is not None:
            vrec = self.variants.get(variant)
            if vrec is not None:
                fields.update(vrec.fields)
        rules = [self] + ([self.variants[variant]] if variant in self.variants else [])
        aliases = {a: k for r in rules for a, k in r.aliases.items()}
        # The given keys under their canonical names (aliases resolved).
        keys: Dict[str, Any] = {}
        for k in value:
            name = aliases.get(k, k)
            if name not in fields:
                self._unknown_key(k, value, fields, variant, loc, ctx)
            if name in keys:
                ctx.error(loc.key(k, value), f"'{keys[name]}' and '{k}' are the same key ({name}): give one")
            keys[name] = k
        for r in rules:
            r._check_groups(keys, value, loc, ctx)
        out = Validated(loc=loc)
        for k, f in fields.items():
            if k in keys:
                vloc = loc.value(keys[k], value)
                out[k] = f.validate(value[keys[k]], vloc, ctx)
                out.locs[k] = vloc
                out.given.add(k)
            elif f.required:
                if not any(self._covered(k, r) for r in rules):
                    self._missing_key(k, f, loc, ctx)
                out[k] = None
            else:
                out[k] = f.missing(loc.value(k, value), ctx)
        for r in rules:
            if r.check is not None:
                r.check(out, ctx)
        return out

    def _check_groups(self, keys: Mapping[str, Any], value: Mapping, loc: Loc, ctx: ValidationContext) -> None:
        """one_of, exclusive and requires of this record; ``keys``: canonical -> as given."""
        for group in self.one_of:
            present = [k for k in group if k in keys]
            if len(present) != 1:
                names = " or ".join(f"'{k}'" for k in group)
                if not present:
                    ctx.error(loc, f"missing key: give exactly one of {names}")
                ctx.error(loc.key(keys[present[1]], value),
                          f"'{present[0]}' and '{present[1]}' cannot be combined: give exactly one of {names}")
        for ga, gb in self.exclusive:
            a = [k for k in ga if k in keys]
            b = [k for k in gb if k in keys]
            if a and b:
                ctx.error(loc.key(keys[b[0]], value), f"'{b[0]}' cannot be combined with '{a[0]}'")
        for k, needs in self.requires.items():
            if k in keys:
                for n in needs:
                    if n not in keys:
                        ctx.error(loc.key(keys[k], value), f"'{k}' requires '{n}' to be given as well")

    def _missing_key(self, k: str, f: Field, loc: Loc, ctx: ValidationContext) -> NoReturn:
        extra = f"; allowed values: {', '.join(f.choices)}" if isinstance(f, Choice) else ""
        ctx.error(loc, f"missing required key '{k}' ({f.doc or f.describe()}){extra}")

    @staticmethod
    def _covered(key: str, rec: "Record") -> bool:
        """Required keys inside a one_of group are enforced by the group."""
        return any(key in g for g in rec.one_of)

    def _all_keys(self) -> List[str]:
        keys = list(self.fields)
        for v in self.variants.values():
            keys += [k for k in v.fields if k not in keys]
        return keys

    def _unknown_key(self, k: str, value: Mapping, fields: Mapping[str, Field], variant: Optional[str],
                     loc: Loc, ctx: ValidationContext) -> NoReturn:
        kloc = loc.key(k, value)
        allowed = ", ".join(fields)
        if self.tag is not None and variant is not None:
            owners = [name for name, v in self.variants.items() if k in v.fields or k in v.aliases]
            if owners:
                ctx.error(kloc, f"key '{k}' is not allowed with {self.tag} '{variant}' (only with "
                                f"{', '.join(owners)}){suggest(k, fields)}; allowed keys: {allowed}")
        if self.tag is not None and variant is None:
            allowed = ", ".join(self._all_keys())
            if any(k in v.fields for v in self.variants.values()):
                ctx.error(kloc, f"key '{k}' needs '{self.tag}' to be given; allowed keys: {allowed}")
        ctx.error(kloc, f"unknown key '{k}'{suggest(k, fields if variant else self._all_keys())}; "
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
            ctx.error(loc, f"expected a mapping of names, got {show_value(value)}")
        out = Validated(loc=loc)
        for k, v in value.items():
            if not isinstance(k, str) or not k:
                ctx.error(loc.key(k, value), f"names must be non-empty strings, got {show_value(k)}")
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
            ctx.error(loc, f"expected a list, got {show_value(value)}")
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


#: ``{texture: NAME}``: a reference to a named texture.
TEXTURE_REF = Record({"texture": String(doc="name of a texture under 'textures'")})
