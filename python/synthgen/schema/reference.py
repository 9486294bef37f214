"""Reference text of a schema: every key with its type, default, range and meaning.

:func:`format_schema` prints a record tree (``synthgen schema``, the reference blocks of
``docs/scene_file.md`` and ``docs/scenarios.md``); since the plugin records are generated
from the C++ declarations (:mod:`synthgen.schema.plugins`), so is this text.
"""
from __future__ import annotations

from typing import Any, List, Mapping, Optional

from .errors import fmt_num
from .fields import EMPTY, ColorOrTexture, Field, ListOf, MapOf, Record, Vector

__all__ = ["format_schema"]


def format_schema(field: Field, indent: int = 0) -> str:
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
                walk(v, ind + 1, v.fields)

    if isinstance(field, Record):
        walk(field, indent)
    else:
        lines.append(f"{pad}{field.describe()}")
    return "\n".join(lines)


def _fmt_default(d: Any) -> str:
    if isinstance(d, bool):
        return str(d).lower()
    if isinstance(d, float):
        return fmt_num(d)
    if isinstance(d, tuple):
        return "[" + ", ".join(_fmt_default(x) for x in d) + "]"
    if isinstance(d, (dict, list)) and not d:
        return "{}" if isinstance(d, dict) else "[]"
    return str(d)
