"""Random fields: any value of a scenario may be a distribution.

:class:`Random` wraps a field: it accepts what the field accepts, or one of the
distribution mappings of :mod:`synthgen.schema.distributions` (``{uniform: [a, b]}``,
``normal``, ``loguniform``, ``int``, ``choice``, ``hsv``), whose bounds and options are
validated by the wrapped field (type and allowed range), so a typo or an out-of-range bound
is reported before anything renders. :func:`randomized` wraps every leaf of a record (the
scenario form of a plugin vocabulary).
"""
from __future__ import annotations

import copy
from typing import Any, Tuple

import numpy as np

from . import distributions as D
from .errors import Loc, ValidationContext, show_value, suggest
from .fields import REQUIRED, Field, Integer, ListOf, Number, Record, Vector

__all__ = ["Random", "R", "randomized"]


class Random(Field):
    """A value of field ``inner`` or a distribution over such values (bounds and options
    validated by ``inner``)."""

    _INNER = object()

    def __init__(self, inner: Field, doc: str = "", default: Any = _INNER):
        super().__init__(inner.default if default is Random._INNER else default, doc or inner.doc)
        self.inner = inner
        self._own_default = default is not Random._INNER

    @property
    def type_name(self) -> str:  # type: ignore[override]
        return self.inner.describe() + " (or a distribution)"

    def describe(self) -> str:
        return self.type_name

    def missing(self, loc: Loc, ctx: ValidationContext) -> Any:
        if self._own_default:
            return self.validate(copy.deepcopy(self.default), loc, ctx) if self.default is not None else None
        return self.inner.missing(loc, ctx)

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if isinstance(value, dict) and any(k in D.DIST_KEYS for k in value):
            return self._distribution(value, loc, ctx)
        if isinstance(value, dict) and not isinstance(self.inner, (Record, Random)) and \
                not getattr(self.inner, "randomizes", False):
            keys = [k for k in value if isinstance(k, str)]
            hint = suggest(keys[0], D.DIST_KEYS) if keys else ""
            ctx.error(loc, f"expected a {self.inner.describe()} or a distribution, got a mapping with key(s) "
                           f"{', '.join(map(str, value))}{hint}; distributions: {', '.join(D.DIST_KEYS)}")
        return self.inner.validate(value, loc, ctx)

    def _pair(self, args: Any, loc: Loc, ctx: ValidationContext, kind: str) -> Tuple[Any, Any]:
        if not isinstance(args, (list, tuple)) or len(args) != 2:
            ctx.error(loc, f"{kind} needs a list of two values [low, high], got {show_value(args)}")
        return (self.inner.validate(args[0], loc.index(0, args), ctx),
                self.inner.validate(args[1], loc.index(1, args), ctx))

    def _distribution(self, value: dict, loc: Loc, ctx: ValidationContext) -> D.Distribution:
        kinds = [k for k in value if k in D.DIST_KEYS]
        if len(kinds) > 1:
            ctx.error(loc.key(kinds[1], value), f"one distribution per value: '{kinds[0]}' and '{kinds[1]}' given")
        kind = kinds[0]
        allowed = (kind,) + D.DIST_EXTRA_KEYS.get(kind, ())
        for k in value:
            if k not in allowed:
                ctx.error(loc.key(k, value), f"unknown key '{k}' in a {kind} distribution{suggest(k, allowed)}; "
                                             f"allowed keys: {', '.join(allowed)}")
        args = value[kind]
        aloc = loc.value(kind, value)
        inner = self.inner
        if isinstance(inner, Vector) and inner.broadcast and kind in ("uniform", "normal", "loguniform") and \
                isinstance(args, (list, tuple)) and args and not any(isinstance(a, (list, tuple)) for a in args):
            # Scalar bounds on a vector that a number stands for (a grey colour, a cube's size):
            # one number is drawn and stands for every component (vector bounds draw each
            # component on its own).
            return D.Broadcast(Random(inner.element)._distribution(value, loc, ctx), inner.size)
        scalar = isinstance(inner, Number)
        if kind == "uniform":
            if isinstance(inner, Integer):
                ctx.error(aloc, "integer values take {int: [low, high]}, not uniform")
            if not (scalar or isinstance(inner, Vector)):
                ctx.error(aloc, f"uniform needs numbers or vectors; this key takes a {inner.describe()}")
            lo, hi = self._pair(args, aloc, ctx, kind)
            if np.any(np.asarray(lo) > np.asarray(hi)):
                ctx.error(aloc, f"uniform bounds must satisfy low <= high, got {list(np.atleast_1d(lo))} > "
                                f"{list(np.atleast_1d(hi))}")
            return D.Uniform(lo, hi)
        if kind == "loguniform":
            if not scalar or isinstance(inner, Integer):
                ctx.error(aloc, f"loguniform needs a real number; this key takes a {inner.describe()}")
            lo, hi = self._pair(args, aloc, ctx, kind)
            if not (0.0 < lo <= hi):
                ctx.error(aloc, f"loguniform bounds must satisfy 0 < low <= high, got [{lo}, {hi}]")
            return D.LogUniform(lo, hi)
        if kind == "int":
            if not isinstance(inner, Integer):
                ctx.error(aloc, f"int needs an integer value; this key takes a {inner.describe()}")
            lo, hi = self._pair(args, aloc, ctx, kind)
            if lo > hi:
                ctx.error(aloc, f"int bounds must satisfy low <= high, got [{lo}, {hi}]")
            return D.IntUniform(lo, hi)
        if kind == "normal":
            if not scalar or isinstance(inner, Integer):
                ctx.error(aloc, f"normal needs a real number; this key takes a {inner.describe()}")
            if not isinstance(args, (list, tuple)) or len(args) != 2:
                ctx.error(aloc, f"normal needs [mean, std], got {show_value(args)}")
            mean = inner.validate(args[0], aloc.index(0, args), ctx)
            std = Number(min=0.0, min_open=True).check(args[1], aloc.index(1, args), ctx)
            lo = inner.validate(value["min"], loc.value("min", value), ctx) if "min" in value else inner.min
            hi = inner.validate(value["max"], loc.value("max", value), ctx) if "max" in value else inner.max
            d = D.Normal(mean, std, lo, hi)
            if lo is not None and hi is not None and lo > hi:
                ctx.error(loc, f"normal truncation must satisfy min <= max, got [{lo}, {hi}]")
            if d.acceptance() < 1e-3:
                ctx.error(loc, f"normal {d.spec()} puts only {d.acceptance():.1e} of its mass inside "
                               f"[{lo}, {hi}] (allowed: {inner.describe()})")
            return d
        if kind == "choice":
            if not isinstance(args, (list, tuple)) or not args:
                ctx.error(aloc, f"choice needs a non-empty list of options, got {show_value(args)}")
            options = [self.validate(v, aloc.index(i, args), ctx) for i, v in enumerate(args)]
            weights = None
            if "weights" in value:
                w = value["weights"]
                wloc = loc.value("weights", value)
                if not isinstance(w, (list, tuple)) or len(w) != len(options):
                    ctx.error(wloc, f"weights must be a list of {len(options)} numbers (one per option)")
                weights = [Number(min=0.0).check(x, wloc.index(i, w), ctx) for i, x in enumerate(w)]
                if sum(weights) <= 0.0:
                    ctx.error(wloc, "weights must not all be 0")
            return D.Choice(options, weights, raw=list(args))
        if kind == "hsv":
            if not (isinstance(inner, Vector) and inner.size == 3):
                ctx.error(aloc, f"hsv jitter needs a colour; this key takes a {inner.describe()}")
            spec = Record({"color": Vector(3, REQUIRED, min=0.0, max=1.0, broadcast=True, doc="base colour"),
                           "h": Number(0.0, min=0.0, max=0.5, doc="hue jitter, fraction of the hue circle"),
                           "s": Number(0.0, min=0.0, max=1.0), "v": Number(0.0, min=0.0, max=1.0)})
            r = spec.validate(args, aloc, ctx)
            inner.validate(list(r["color"]), aloc, ctx)  # the base colour within the slot's range
            return D.HsvJitter(r["color"], r["h"], r["s"], r["v"])
        raise AssertionError(kind)


def R(inner: Field, doc: str = "", **kw: Any) -> Random:
    return Random(inner, doc, **kw)


def R(inner: Field, doc: str = "", **kw: Any) -> Random:
    """Shorthand: ``R(Number(...))`` is ``Random(Number(...))``."""
    return Random(inner, doc, **kw)


def randomized(rec: Record) -> Record:
    """A copy of a record (and its variants) in which every leaf field may be a
    distribution; nested records and lists keep their shape."""
    def wrap(f: Field) -> Field:
        if isinstance(f, (Record, ListOf, Random)) or getattr(f, "randomizes", False):
            return f
        return Random(f)

    variants = {name: Record({k: wrap(f) for k, f in v.fields.items()}, one_of=v.one_of, exclusive=v.exclusive,
                             requires=v.requires, aliases=v.aliases, check=v.check, doc=v.doc)
                for name, v in rec.variants.items()}
    fields = {k: (f if k == rec.tag else wrap(f)) for k, f in rec.fields.items()}
    return rec.extend(fields, variants=variants)
