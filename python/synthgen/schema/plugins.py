"""Schema records generated from the plugins' own declarations.

Every material, texture, light, the camera and the render settings declare their parameters
once, in their C++ file (name, type, default, range, allowed values, aliases, combinations,
doc; ``synthgen._core.plugin_info``). This module turns those declarations into schema
fields, so the scene-file format, the scenario format (the same vocabulary with every leaf
allowed to be a distribution) and the generated docs cannot drift from the code:

- :func:`param_field` -- one declared parameter as a :class:`~synthgen.schema.fields.Field`;
- :func:`plugin_record` -- a ``type``-tagged record of a plugin kind (``material``, ...),
  one variant per plugin, with the plugins' combination rules;
- :func:`settings_record` -- the record of a single plugin's parameters (camera, render).

In the scenario form (``scenario=True``) parameters that refer to other library objects
(textures, materials) do not exist, colours and scalars that may be textures are plain
colours and scalars, and plugins that need such a reference (``mix``) are left out.
"""
from __future__ import annotations

import math
import struct

import functools
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

from .._core import plugin_info as _core_plugin_info, plugin_names as _core_plugin_names
from .errors import Loc, ValidationContext, show_value
from .fields import (REQUIRED, Bool, Choice, ColorOrTexture, Field, FilePath, Integer, Matrix4, MaterialRef, Number,
                     NumberList, Record, ScalarOrTexture, String, TextureRefField, Vector)

__all__ = ["plugin_info", "plugin_names", "param_field", "plugin_record", "refresh_runtime_plugins",
           "settings_record", "given_params", "realize", "REFERENCE_TYPES"]

#: Parameter types that refer to other library objects (in scenarios textures are written
#: inline, materials have no form).
REFERENCE_TYPES = ("texture", "material")


class TextureSpec(dict):
    """A validated (or sampled) inline texture of a scenario: ``{"texture": record}``, the
    record being ``{type: NAME, ...parameters}`` (created per frame, synthgen.frame)."""


_TEXTURE_RECORD: List[Any] = []


def scenario_texture_record() -> Record:
    """The scenario form of a texture: {type: NAME, ...its parameters, each may be a
    distribution or, for texture parameters, an inline texture} (built once, lazily: textures
    nest)."""
    if not _TEXTURE_RECORD:
        from .random import randomized

        _TEXTURE_RECORD.append(None)  # being built: nested fields look it up when validating
        _TEXTURE_RECORD[0] = randomized(plugin_record("texture", scenario=True, doc="a texture"))
    return _TEXTURE_RECORD[0]


class InlineTexture(Field):
    """Scenario form of a texture parameter: its constant form (a number or colour, or a
    distribution over them), or an inline texture ``{texture: {type: NAME, ...}}`` -- an
    image, noise, a checker, a gradient, ... whose parameters may be distributions too."""

    #: randomized() leaves this field as it is: it takes distributions itself.
    randomizes = True

    def __init__(self, constant: Optional[Field], default: Any = None, doc: str = ""):
        super().__init__(default, doc)
        self.constant = constant

    def describe(self) -> str:
        form = "{texture: {type: NAME, ...}}"
        return f"{self.constant.describe()}, or {form}" if self.constant is not None else form

    def missing(self, loc: Loc, ctx: ValidationContext) -> Any:
        if self.constant is not None:
            return self.constant.missing(loc, ctx)
        return super().missing(loc, ctx)

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        from .random import Random

        if isinstance(value, Mapping) and "texture" in value:
            extra = [k for k in value if k != "texture"]
            if extra:
                ctx.error(loc.key(extra[0], value), f"an inline texture is {{texture: {{...}}}} alone; unexpected key "
                                                    f"'{extra[0]}'")
            return TextureSpec(texture=scenario_texture_record().validate(value["texture"], loc.value("texture", value),
                                                                          ctx))
        if isinstance(value, Mapping) and "choice" in value:
            return Random(self)._distribution(value, loc, ctx)  # a choice among textures and constants
        if self.constant is None:
            ctx.error(loc, f"expected an inline texture {{texture: {{type: NAME, ...}}}}, got {show_value(value)}")
        return self.constant.validate(value, loc, ctx)


@functools.lru_cache(maxsize=None)
def _info(kind: str, name: str) -> Dict[str, Any]:
    return _core_plugin_info(kind, name)


def plugin_info(kind: str, name: str) -> Dict[str, Any]:
    """The declaration of a plugin (see ``synthgen._core.plugin_info``)."""
    return _info(kind, name)


def plugin_names(kind: str) -> List[str]:
    """Names of the plugins of a kind, sorted."""
    return list(_core_plugin_names(kind))


def _short(x: Any) -> Any:
    """A float declared in C++ as a float32 (0.8f reads back as 0.800000011920929) as the
    shortest decimal with the same float32 value (0.8): what the declaration says."""
    if not isinstance(x, float) or not math.isfinite(x):
        return x
    f32 = struct.unpack("f", struct.pack("f", x))[0]
    if f32 != x:
        return x  # a double: kept
    for digits in range(1, 10):
        y = float(f"{x:.{digits}g}")
        if struct.unpack("f", struct.pack("f", y))[0] == f32:
            return y
    return x


def _default(p: Mapping[str, Any]) -> Any:
    if p["required"]:
        return REQUIRED
    if not p["has_default"]:
        return None
    d = p["default"]
    return tuple(_short(float(x)) for x in d) if isinstance(d, list) else _short(d)


def _doc(p: Mapping[str, Any]) -> str:
    doc = p["doc"]
    if p["default_doc"]:
        doc += f" (default: {p['default_doc']})"
    if p["aliases"]:
        doc += " (also spelled " + ", ".join(p["aliases"]) + ")"
    return doc


def param_field(p: Mapping[str, Any], scenario: bool = False) -> Optional[Field]:
    """The schema field of one declared parameter (None: no such field in the scenario
    form). Ranges, defaults and allowed values are the declaration's."""
    t = p["type"]
    default, doc = _default(p), _doc(p)
    rng = dict(min=p["min"], max=p["max"], min_open=p["min_open"], max_open=p["max_open"])
    if t in REFERENCE_TYPES:
        if scenario:
            return InlineTexture(None, default, doc=doc) if t == "texture" else None
        return TextureRefField(doc=doc) if t == "texture" else MaterialRef(default, doc=doc)
    if t == "bool":
        return Bool(default, doc=doc)
    if t == "int":
        return Integer(default, doc=doc, **rng)
    if t == "float_texture" and scenario:
        from .random import R

        return InlineTexture(R(Number(default, doc=doc, **rng)), default, doc=doc)
    if t == "color_texture" and scenario:
        from .random import R

        return InlineTexture(R(Vector(3, default, broadcast=True, doc=doc, **rng)), default, doc=doc)
    if t == "float":
        return Number(default, doc=doc, **rng)
    if t == "float_texture":
        return ScalarOrTexture(default, min=p["min"], max=p["max"], doc=doc)
    if t == "string":
        return Choice(p["choices"], default, doc=doc) if p["choices"] else String(default, doc=doc)
    if t == "path":
        return FilePath(default, doc=doc)
    if t in ("color", "vec3"):
        return Vector(3, default, broadcast=True, doc=doc, **rng)
    if t == "color_texture":
        return ColorOrTexture(default, min=p["min"], max=p["max"], doc=doc)
    if t == "vec2":
        return Vector(2, default, broadcast=True, doc=doc, **rng)
    if t == "floats":
        return NumberList(default, size=p["size"], min=p["min"], max=p["max"], doc=doc)
    if t == "matrix4":
        return Matrix4(default, doc=doc)
    raise AssertionError(f"parameter type {t!r} has no schema field")


def _usable(info: Mapping[str, Any], scenario: bool) -> bool:
    """A plugin has a scenario form unless it needs a material (a mix): textures are inline."""
    return not scenario or not any(p["required"] and p["type"] == "material" for p in info["params"])


def _params_record(info: Mapping[str, Any], scenario: bool, keys: Optional[Sequence[str]] = None,
                   doc: str = "", default: Any = REQUIRED) -> Record:
    fields: Dict[str, Field] = {}
    aliases: Dict[str, str] = {}
    for p in info["params"]:
        if keys is not None and p["name"] not in keys:
            continue
        f = param_field(p, scenario)
        if f is None:
            continue
        fields[p["name"]] = f
        aliases.update({a: p["name"] for a in p["aliases"]})
    has = lambda ks: [k for k in ks if k in fields]  # noqa: E731
    exclusive = [(has(a), has(b)) for a, b in info["exclusive"] if has(a) and has(b)]
    requires = {k: has(o) for k, o in info["requires"] if k in fields and has(o)}
    one_of = [g for g in info["one_of"] if len(has(g)) == len(g)]
    return Record(fields, one_of=one_of, exclusive=exclusive, requires=requires, aliases=aliases,
                  doc=doc or info["doc"], default=default)


def plugin_record(kind: str, *, scenario: bool = False, names: Optional[Iterable[str]] = None,
                  fields: Optional[Mapping[str, Field]] = None, doc: str = "", default: Any = REQUIRED) -> Record:
    """A record ``{type: NAME, ...parameters of plugin NAME}`` over the plugins of ``kind``
    (all, or ``names``), plus the extra ``fields`` common to every variant (e.g. a
    light's ``name``)."""
    infos = [plugin_info(kind, n) for n in (names if names is not None else plugin_names(kind))]
    infos = [i for i in infos if _usable(i, scenario)]
    variants = {i["name"]: _params_record(i, scenario) for i in infos}
    base = {"type": Choice([i["name"] for i in infos], doc=f"{kind} plugin")}
    base.update(fields or {})
    rec = Record(base, tag="type", variants=variants, doc=doc or kind, default=default)
    if names is None:
        _RECORDS.append((rec, kind, scenario))
    return rec


#: The records of all plugins of a kind made by plugin_record: refresh_runtime_plugins() adds
#: the plugins that user extensions register later.
_RECORDS: List[Tuple[Record, str, bool]] = []


def refresh_runtime_plugins() -> None:
    """Makes the plugins registered at run time (user extensions' textures and shapes,
    synthgen.scene.extensions) known to the schemas: every record of a whole plugin kind
    gains (or renews) their variants, and the scenario texture form is rebuilt."""
    _info.cache_clear()
    for rec, kind, scenario in _RECORDS:
        choice = rec.fields["type"]
        for name in plugin_names(kind):
            info = plugin_info(kind, name)
            if name in rec.variants and not info["file"].endswith(".c"):
                continue  # built-in (run-time plugins are declared in their C file)
            if not _usable(info, scenario):
                continue
            rec.variants[name] = _params_record(info, scenario)
            if name not in choice.choices:
                choice.choices = sorted(choice.choices + [name])  # in plugin_names' order
    _TEXTURE_RECORD.clear()


def settings_record(kind: str, name: str, *, scenario: bool = False, keys: Optional[Sequence[str]] = None,
                    doc: str = "", default: Any = REQUIRED) -> Record:
    """The parameters of one plugin (all, or ``keys``) as a plain record."""
    return _params_record(plugin_info(kind, name), scenario, keys, doc, default)


def given_params(rec: Mapping[str, Any], skip: Sequence[str] = ("type", "name")) -> Dict[str, Any]:
    """The parameters given in a validated (or sampled) record, in declaration order, as
    values for the native core: tuples become lists, 4x4 matrices 16 numbers. Defaults are
    not repeated: the core owns them."""
    given = getattr(rec, "given", None)
    out: Dict[str, Any] = {}
    for k, v in rec.items():
        if k in skip or (given is not None and k not in given):
            continue
        if isinstance(v, tuple) and v and isinstance(v[0], tuple):
            v = [x for row in v for x in row]
        out[k] = list(v) if isinstance(v, tuple) else v
    return out


def realize(library: Any, params: Mapping[str, Any]) -> Dict[str, Any]:
    """Plugin parameters for the core, with every inline texture of a scenario
    (:class:`TextureSpec`, nested ones too) created in ``library`` and replaced by its
    :class:`TextureRef`."""
    from .._core import TextureRef

    out: Dict[str, Any] = {}
    for k, v in params.items():
        if isinstance(v, TextureSpec):
            rec = v["texture"]
            out[k] = TextureRef(library.add_texture(str(rec["type"]), realize(library, given_params(rec))))
        else:
            out[k] = v
    return out
