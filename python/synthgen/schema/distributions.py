"""Random distributions for scenario files, in one inline form for every kind of value.

Any scalar, vector, colour or choice in a scenario may be written as a constant or as a
mapping with one distribution key::

    {uniform: [0.2, 0.8]}                 # a number (on a colour or size: one number for every
                                          #   component, a grey); per component: [[0, 0, 0], [1, 1, 1]]
    {normal: [mean, std]}                 # truncated to the slot's allowed range, or to
    {normal: [0, 1], min: -2, max: 2}     #   explicit min / max (rejection sampling)
    {loguniform: [0.01, 1]}               # log-uniform between two positive bounds
    {int: [1, 5]}                         # integer, both ends included
    {choice: [a, b, c], weights: [1, 2, 1]}   # any values, even whole sub-trees
    {hsv: {color: [0.8, 0.1, 0.1], h: 0.05, s: 0.1, v: 0.2}}   # colour jitter in HSV

Bounds and options are validated like the constant they stand for (type and allowed range),
so a typo or an out-of-range bound is reported before anything renders.

Sampling is explicit: every distribution draws from the ``numpy.random.Generator`` passed to
:meth:`Distribution.sample`; there is no global random state. A frame's generators come from
:func:`frame_rng` (scenario seed, frame index, stream).
"""
from __future__ import annotations

import colorsys
import math
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

__all__ = ["Distribution", "Broadcast", "Uniform", "Normal", "LogUniform", "IntUniform", "Choice", "HsvJitter", "DIST_KEYS",
           "is_distribution_spec", "frame_rng"]

#: The keys that mark a mapping as a distribution.
DIST_KEYS = ("uniform", "normal", "loguniform", "int", "choice", "hsv")
#: Extra keys allowed next to each distribution key.
DIST_EXTRA_KEYS = {"normal": ("min", "max"), "choice": ("weights",)}


def is_distribution_spec(value: Any) -> bool:
    """True for a mapping whose keys are one distribution key plus its allowed extras."""
    if not isinstance(value, dict) or not value:
        return False
    keys = [k for k in value if k in DIST_KEYS]
    return len(keys) == 1


class Distribution:
    """Base class: ``sample(rng)`` draws one value; ``spec()`` is the JSON form for metadata."""

    kind = "distribution"

    def sample(self, rng: np.random.Generator) -> Any:
        raise NotImplementedError

    def spec(self) -> Dict[str, Any]:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.spec()})"


def _out(v: Any) -> Any:
    """numpy scalars and arrays -> plain Python floats / tuples."""
    a = np.asarray(v, dtype=np.float64)
    return float(a) if a.ndim == 0 else tuple(float(x) for x in a)


class Uniform(Distribution):
    """Uniform between ``lo`` and ``hi`` (numbers, or vectors component-wise)."""

    kind = "uniform"

    def __init__(self, lo: Any, hi: Any):
        self.lo, self.hi = lo, hi

    def sample(self, rng: np.random.Generator) -> Any:
        lo, hi = np.asarray(self.lo, np.float64), np.asarray(self.hi, np.float64)
        return _out(lo + (hi - lo) * rng.random(lo.shape))

    def spec(self) -> Dict[str, Any]:
        return {"uniform": [self.lo, self.hi]}


class Broadcast(Distribution):
    """One number drawn from ``inner`` standing for all ``size`` components of a vector (a
    grey colour from ``{uniform: [0.2, 0.8]}``)."""

    def __init__(self, inner: Distribution, size: int):
        self.inner, self.size = inner, int(size)
        self.kind = inner.kind

    def sample(self, rng: np.random.Generator) -> Any:
        return (float(self.inner.sample(rng)),) * self.size

    def spec(self) -> Dict[str, Any]:
        return self.inner.spec()


class Normal(Distribution):
    """Normal with ``mean`` and ``std``, truncated to [``lo``, ``hi``] by rejection."""

    kind = "normal"
    MAX_TRIES = 10000

    def __init__(self, mean: float, std: float, lo: Optional[float] = None, hi: Optional[float] = None):
        self.mean, self.std, self.lo, self.hi = float(mean), float(std), lo, hi

    def acceptance(self) -> float:
        """Probability mass of the truncation interval."""
        cdf = lambda x: 0.5 * (1.0 + math.erf((x - self.mean) / (self.std * math.sqrt(2.0))))  # noqa: E731
        a = 0.0 if self.lo is None else cdf(self.lo)
        b = 1.0 if self.hi is None else cdf(self.hi)
        return b - a

    def sample(self, rng: np.random.Generator) -> float:
        for _ in range(self.MAX_TRIES):
            x = self.mean + self.std * float(rng.standard_normal())
            if (self.lo is None or x >= self.lo) and (self.hi is None or x <= self.hi):
                return x
        raise ValueError(f"normal {self.spec()}: no sample inside the truncation after {self.MAX_TRIES} tries")

    def spec(self) -> Dict[str, Any]:
        d: Dict[str, Any] = {"normal": [self.mean, self.std]}
        if self.lo is not None:
            d["min"] = self.lo
        if self.hi is not None:
            d["max"] = self.hi
        return d


class LogUniform(Distribution):
    """exp(uniform(log lo, log hi)) for 0 < lo <= hi."""

    kind = "loguniform"

    def __init__(self, lo: float, hi: float):
        self.lo, self.hi = float(lo), float(hi)

    def sample(self, rng: np.random.Generator) -> float:
        a, b = math.log(self.lo), math.log(self.hi)
        return float(min(self.hi, max(self.lo, math.exp(a + (b - a) * float(rng.random())))))

    def spec(self) -> Dict[str, Any]:
        return {"loguniform": [self.lo, self.hi]}


class IntUniform(Distribution):
    """A uniform integer in [lo, hi], both included."""

    kind = "int"

    def __init__(self, lo: int, hi: int):
        self.lo, self.hi = int(lo), int(hi)

    def sample(self, rng: np.random.Generator) -> int:
        return int(rng.integers(self.lo, self.hi + 1))

    def spec(self) -> Dict[str, Any]:
        return {"int": [self.lo, self.hi]}


class Choice(Distribution):
    """One of ``options`` (with ``weights``, default equal). Options may themselves hold
    distributions; the caller samples the chosen option further."""

    kind = "choice"

    def __init__(self, options: Sequence[Any], weights: Optional[Sequence[float]] = None, raw: Any = None):
        self.options = list(options)
        w = np.ones(len(self.options)) if weights is None else np.asarray(weights, np.float64)
        self.p = w / w.sum()
        self.weights = None if weights is None else [float(x) for x in weights]
        self.raw = raw if raw is not None else self.options

    def sample_index(self, rng: np.random.Generator) -> int:
        # NOTE: inverse-CDF on one uniform number, so the choice costs exactly one draw.
        u = float(rng.random())
        return int(min(np.searchsorted(np.cumsum(self.p), u, side="right"), len(self.options) - 1))

    def sample(self, rng: np.random.Generator) -> Any:
        return self.options[self.sample_index(rng)]

    def spec(self) -> Dict[str, Any]:
        d: Dict[str, Any] = {"choice": _plain(self.raw)}
        if self.weights is not None:
            d["weights"] = self.weights
        return d


class HsvJitter(Distribution):
    """A colour near ``color`` (linear RGB in [0, 1]): hue shifted uniformly by up to
    ±``h`` (fraction of the hue circle), saturation and value by up to ±``s`` and ±``v``
    (clamped to [0, 1])."""

    kind = "hsv"

    def __init__(self, color: Sequence[float], h: float = 0.0, s: float = 0.0, v: float = 0.0):
        self.color = tuple(float(c) for c in color)
        self.h, self.s, self.v = float(h), float(s), float(v)

    def sample(self, rng: np.random.Generator) -> tuple:
        hh, ss, vv = colorsys.rgb_to_hsv(*self.color)
        dh, ds, dv = (2.0 * rng.random(3) - 1.0) * np.array([self.h, self.s, self.v])
        hh = (hh + dh) % 1.0
        ss = min(1.0, max(0.0, ss + ds))
        vv = min(1.0, max(0.0, vv + dv))
        return tuple(float(min(1.0, max(0.0, c))) for c in colorsys.hsv_to_rgb(hh, ss, vv))

    def spec(self) -> Dict[str, Any]:
        return {"hsv": {"color": list(self.color), "h": self.h, "s": self.s, "v": self.v}}


def _plain(x: Any) -> Any:
    """A JSON-friendly copy of a (validated) value tree."""
    if isinstance(x, Distribution):
        return x.spec()
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    return x


def plain(x: Any) -> Any:
    """Public alias of the JSON conversion used for metadata."""
    return _plain(x)


def frame_rng(seed: int, frame: int, stream: int = 0) -> np.random.Generator:
    """The generator of frame ``frame``: a pure function of (scenario seed, frame index,
    stream) through numpy's SeedSequence (PCG64)."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([int(seed), int(frame), int(stream)])))


def sample_tree(tree: Any, rng: np.random.Generator, path: str = "", record: Optional[Dict[str, Any]] = None) -> Any:
    """A copy of ``tree`` (dicts, lists, tuples, leaves) with every :class:`Distribution`
    replaced by a sample, drawn in a fixed order (mapping insertion order, list order).
    ``record`` receives ``{key.path: sampled value}`` for every draw."""
    if isinstance(tree, Distribution):
        if isinstance(tree, Choice):
            i = tree.sample_index(rng)
            if record is not None:
                record[path] = {"choice": i}
            return sample_tree(tree.options[i], rng, path, record)
        v = tree.sample(rng)
        if record is not None:
            record[path] = v
        return v
    if isinstance(tree, dict):
        out = type(tree)() if type(tree) is dict else _clone_dict(tree)
        for k, v in tree.items():
            out[k] = sample_tree(v, rng, f"{path}.{k}" if path else str(k), record)
        return out
    if isinstance(tree, list):
        return [sample_tree(v, rng, f"{path}[{i}]", record) for i, v in enumerate(tree)]
    if isinstance(tree, tuple):
        return tuple(sample_tree(v, rng, f"{path}[{i}]", record) for i, v in enumerate(tree))
    return tree


def _clone_dict(d: dict) -> dict:
    """An empty dict of the same class keeping location attributes (Validated records)."""
    out = type(d).__new__(type(d))
    dict.__init__(out)
    for attr in ("loc", "locs", "given"):
        if hasattr(d, attr):
            setattr(out, attr, getattr(d, attr))
    return out


def has_distribution(tree: Any) -> bool:
    if isinstance(tree, Distribution):
        return True
    if isinstance(tree, dict):
        return any(has_distribution(v) for v in tree.values())
    if isinstance(tree, (list, tuple)):
        return any(has_distribution(v) for v in tree)
    return False


def as_list(x: Any) -> List[Any]:
    return list(x) if isinstance(x, (list, tuple)) else [x]
