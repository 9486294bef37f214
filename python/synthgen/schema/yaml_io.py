"""Safe YAML loading that remembers where every key and value is.

:func:`read_yaml` and :func:`parse_yaml` return :class:`MarkedDict` / :class:`MarkedList`
trees (dicts and lists that know the 1-based line and column of themselves, their keys and
their values), so validation errors can point into the file. Only safe YAML is accepted;
duplicate keys are errors; ``1e3`` reads as a number (YAML 1.2), not as a string.
"""
from __future__ import annotations

import os
import re
from typing import Any, Dict, List, Optional, Tuple

import yaml

from .errors import SceneFileError, _hashable
from .limits import MAX_YAML_DEPTH, MAX_YAML_VALUES, expanded_size

__all__ = ["MarkedDict", "MarkedList", "read_yaml", "read_text", "parse_yaml"]

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


def show(node: yaml.Node) -> str:
    """A node's value for a message (scalars as written, collections by kind)."""
    if isinstance(node, yaml.ScalarNode):
        v = str(node.value)
        return repr(v if len(v) <= 40 else v[:37] + "...")
    return "(a mapping)" if isinstance(node, yaml.MappingNode) else "(a list)"


def _mark(m: yaml.Mark) -> Tuple[int, int]:
    return (m.line + 1, m.column + 1)


class _MarkedLoader(yaml.SafeLoader):
    """Safe YAML loader producing MarkedDict / MarkedList, rejecting duplicate keys."""

    def construct_object(self, node: yaml.Node, deep: bool = False) -> Any:
        # PyYAML's scalar constructors raise plain ValueError for a tagged value they cannot
        # read (`!!float ior`, `!!int width`; found by fuzz_yaml): located here instead.
        try:
            return super().construct_object(node, deep=deep)
        except (yaml.YAMLError, MemoryError, RecursionError):
            raise
        except Exception as e:  # ValueError, KeyError (`!!bool maybe`), OverflowError, ...
            raise yaml.constructor.ConstructorError(
                None, None, f"cannot read {node.tag.rsplit(':', 1)[-1]} value {show(node)}: {e}",
                node.start_mark) from None

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


def _line_col(text: str, index: int) -> Tuple[int, int]:
    """1-based line and column of character `index` of `text`."""
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def read_text(path: str | os.PathLike, source: Optional[str] = None, what: str = "scene file") -> str:
    """A file's text, decoded as UTF-8; :class:`SceneFileError` naming the file (and, for
    bytes that are not UTF-8, their line and column) when it cannot be read."""
    path = os.fspath(path)
    source = path if source is None else source
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise SceneFileError(source, None, None, "", f"cannot read the {what}: {e.strerror or e}") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        good = data[:e.start].decode("utf-8")
        line, col = _line_col(good, len(good))
        raise SceneFileError(source, line, col, "", f"the {what} is not UTF-8 text (byte 0x{data[e.start]:02x} "
                                                    f"at offset {e.start}: {e.reason})") from None


def read_yaml(path: str | os.PathLike, source: Optional[str] = None) -> Any:
    """Parses a YAML file safely into MarkedDict / MarkedList / scalars.

    Syntax errors, unknown tags and duplicate keys raise :class:`SceneFileError` with the
    line and column; ``source`` (default: ``path``) names the file in messages.
    """
    path = os.fspath(path)
    source = path if source is None else source
    return parse_yaml(read_text(path, source), source)


def _check_depth(text: str, source: str) -> None:
    """Refuses documents nested deeper than MAX_YAML_DEPTH before they are composed (the
    event parser is iterative; the composer is not)."""
    depth = 0
    loader = yaml.SafeLoader(text)
    try:
        while loader.check_event():
            ev = loader.get_event()
            if isinstance(ev, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
                depth += 1
                if depth > MAX_YAML_DEPTH:
                    line, col = _mark(ev.start_mark)
                    raise SceneFileError(source, line, col, "", f"the document nests more than {MAX_YAML_DEPTH} "
                                                                f"levels of mappings and lists: refused")
            elif isinstance(ev, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                depth -= 1
    finally:
        loader.dispose()


def parse_yaml(text: str, source: str = "<string>") -> Any:
    """Parses YAML text like :func:`read_yaml`."""
    loader = None
    try:
        _check_depth(text, source)
        loader = _MarkedLoader(text)
        data = loader.get_single_data()
    except yaml.reader.ReaderError as e:
        line, col = _line_col(text, e.position) if isinstance(e.position, int) else (None, None)
        what = f"character U+{e.character:04X}" if isinstance(e.character, int) else "a character"
        raise SceneFileError(source, line, col, "", f"invalid YAML: {what} is not allowed in YAML text "
                                                    f"(control characters and the like)") from None
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
        if loader is not None:
            loader.dispose()
    n = expanded_size(data)
    if n > MAX_YAML_VALUES:
        raise SceneFileError(source, None, None, "", f"the document expands to more than {MAX_YAML_VALUES:,} values "
                                                     f"through its aliases (*name): refused (an alias bomb?)")
    return data
