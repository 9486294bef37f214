"""Errors with their place in a YAML file, and the context shared while validating.

Every problem in a scene file or scenario raises :class:`SceneFileError` (a
:class:`synthgen.SynthgenError`, hence a :class:`ValueError`) whose message reads
``FILE:LINE:COLUMN: key.path: reason``, e.g.::

    scene.yaml:12:5: objects[1].materal: unknown key 'materal' (did you mean
    'material'?); allowed keys: class_id, instance_id, material, ...

:class:`Loc` is the position of a value (key path, line, column); :class:`ValidationContext`
names the source, resolves relative paths, re-raises errors of the native core at the
entry that caused them, and is the extension point for random distributions
(:meth:`ValidationContext.number`).
"""
from __future__ import annotations

import contextlib
import difflib
import os
from collections.abc import Mapping
from typing import Any, Iterable, Iterator, NoReturn, Optional

import numpy as np

from .._core import SynthgenError

__all__ = ["SceneFileError", "Loc", "ValidationContext", "show_value", "suggest", "fmt_num", "is_bool", "as_seq"]

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


def show_value(value: Any) -> str:
    """Short description of a YAML value for error messages."""
    if value is None:
        return "null"
    if is_bool(value):
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


def is_bool(x: Any) -> bool:
    return isinstance(x, (bool, np.bool_))


def as_seq(x: Any) -> Any:
    """numpy arrays (from scene dicts built in Python) are validated as lists."""
    return x.tolist() if isinstance(x, np.ndarray) else x


def fmt_num(x: float) -> str:
    if isinstance(x, float) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


def suggest(word: Any, candidates: Iterable[str]) -> str:
    if not isinstance(word, str):
        return ""
    m = difflib.get_close_matches(word, list(candidates), n=1, cutoff=0.6)
    return f" (did you mean '{m[0]}'?)" if m else ""
