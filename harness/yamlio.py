"""The one way srr reads (and writes back) YAML: the YAML 1.2 core schema, no duplicate keys.

PyYAML's ``safe_load`` follows YAML 1.1: ``1e3`` (an exponent without a dot) is text,
``yes``/``no``/``on``/``off`` are booleans, ``012`` is octal, ``2024-01-02`` is a date, and a
key written twice silently keeps its last value. srr reads every YAML text (scenarios and their
includes, suite files, ``--set`` values, bag metadata) with :func:`load`, which resolves plain
scalars as YAML 1.2's core schema does:

* null: ``~``, ``null``, ``Null``, ``NULL`` and nothing;
* booleans: ``true``/``false`` (also ``True``, ``TRUE``, ``False``, ``FALSE``) only:
  ``yes``, ``no``, ``on`` and ``off`` are text;
* integers: ``12``, ``-3``, ``0o17``, ``0x1F`` (``012`` is twelve);
* floats: ``1.5``, ``1e3``, ``-1E-5``, ``.5``, ``.inf``, ``-.inf``, ``.nan``;
* everything else is text (dates too). Merge keys (``<<: *anchor``) still work.

A key written twice in one mapping is refused with :class:`DuplicateKeyError`, which names the
key's path, its line and the line of its first definition. Only the standard tags are accepted
(``!!str``, ``!!int``, ``!!float``, ``!!bool``, ``!!null``, ``!!seq``, ``!!map``); a value an
explicit tag cannot hold (``!!int abc``) is a :class:`yaml.constructor.ConstructorError`. Every
error raised is a :class:`yaml.YAMLError`; :func:`describe` turns one into a line.

:func:`dump` writes data that :func:`load` reads back the same (a string ``"1e3"`` is quoted).
"""

from __future__ import annotations

import math
import re
import sys
from typing import Any

import yaml
from yaml.constructor import ConstructorError
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

__all__ = ["DuplicateKeyError", "describe", "dump", "load"]

_BaseLoader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

#: The largest integer read: every number srr reads may become a float.
_MAX_INT = int(sys.float_info.max)

_NULL = "tag:yaml.org,2002:null"
_BOOL = "tag:yaml.org,2002:bool"
_INT = "tag:yaml.org,2002:int"
_FLOAT = "tag:yaml.org,2002:float"
_MERGE = "tag:yaml.org,2002:merge"

# (tag, pattern, first characters); ints before floats, as "12" matches both.
_RESOLVERS: list[tuple[str, re.Pattern[str], str]] = [
    (_NULL, re.compile(r"^(?:~|null|Null|NULL|)$"), "~nN"),
    (_BOOL, re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), "tTfF"),
    (_INT, re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"), "-+0123456789"),
    (_FLOAT, re.compile(r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
                        r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"), "-+.0123456789"),
    (_MERGE, re.compile(r"^(?:<<)$"), "<"),
]


def _add_resolvers(cls: Any) -> None:
    cls.yaml_implicit_resolvers = {}
    for tag, pattern, first in _RESOLVERS:
        cls.add_implicit_resolver(tag, pattern, [*first] + ([""] if tag == _NULL else []))


class DuplicateKeyError(ConstructorError):  # type: ignore[misc]
    """A mapping has the same key twice. ``field``: the key's dotted path (``robots[0].name``),
    ``key`` the key, ``line`` where it is repeated, ``first_line`` where it was first set
    (1-based)."""

    def __init__(self, field: str, key: Any, node: Node, first: Node) -> None:
        self.field = field
        self.key = key
        self.line = node.start_mark.line + 1
        self.first_line = first.start_mark.line + 1
        super().__init__(None, None, f"duplicate key {key!r} (first set on line "
                         f"{self.first_line})", node.start_mark)


class _Loader(_BaseLoader):  # type: ignore[misc]
    yaml_constructors: dict[Any, Any] = {}

    def _scalar(self, node: Node) -> str:
        return str(self.construct_scalar(node))

    def _bad(self, node: Node, what: str) -> ConstructorError:
        return ConstructorError(None, None, f"{self._scalar(node)!r} is not {what}",
                                node.start_mark)

    def construct_null(self, node: Node) -> None:
        if not _RESOLVERS[0][1].match(self._scalar(node)):
            raise self._bad(node, "null")

    def construct_bool(self, node: Node) -> bool:
        text = self._scalar(node)
        if not _RESOLVERS[1][1].match(text):
            raise self._bad(node, "true or false")
        return text.lower() == "true"

    def construct_int(self, node: Node) -> int:
        text = self._scalar(node)
        if not _RESOLVERS[2][1].match(text):
            raise self._bad(node, "an integer")
        try:
            if text.startswith(("0o", "0x")):
                value = int(text[2:], 8 if text[1] == "o" else 16)
            else:
                value = int(text, 10)
        except ValueError:  # more digits than Python converts (sys.get_int_max_str_digits)
            raise self._bad(node, "an integer srr can hold (too many digits)") from None
        if abs(value) > _MAX_INT:
            raise self._bad(node, "an integer srr can hold (beyond ±1.8e308, the largest "
                            "number)")
        return value

    def construct_float(self, node: Node) -> float:
        text = self._scalar(node)
        if not _RESOLVERS[3][1].match(text):
            raise self._bad(node, "a number")
        low = text.lower()
        if low.endswith(".inf"):
            return -math.inf if low.startswith("-") else math.inf
        if low == ".nan":
            return math.nan
        return float(text)

    def construct_unknown(self, node: Node) -> Any:
        raise ConstructorError(None, None, f"the tag {node.tag} is not supported (srr reads "
                               "plain YAML: mappings, lists, strings, numbers, true/false, "
                               "null)", node.start_mark)


_add_resolvers(_Loader)
for _tag, _make in ((_NULL, _Loader.construct_null), (_BOOL, _Loader.construct_bool),
                    (_INT, _Loader.construct_int), (_FLOAT, _Loader.construct_float),
                    ("tag:yaml.org,2002:str", yaml.SafeLoader.construct_yaml_str),
                    ("tag:yaml.org,2002:seq", yaml.SafeLoader.construct_yaml_seq),
                    ("tag:yaml.org,2002:map", yaml.SafeLoader.construct_yaml_map),
                    (None, _Loader.construct_unknown)):
    _Loader.add_constructor(_tag, _make)


class _Dumper(yaml.SafeDumper):  # type: ignore[misc]
    """Quotes a string exactly when :func:`load` would read it as something else."""


_add_resolvers(_Dumper)


def _check_duplicates(loader: _Loader, node: Node, path: str, seen: set[int]) -> None:
    """Refuse a key set twice in any mapping under ``node`` (merged keys may be overridden)."""
    if id(node) in seen:
        return
    seen.add(id(node))
    if isinstance(node, SequenceNode):
        for i, item in enumerate(node.value):
            _check_duplicates(loader, item, f"{path}[{i}]", seen)
    elif isinstance(node, MappingNode):
        first: dict[Any, Node] = {}
        for key_node, value_node in node.value:
            if key_node.tag == _MERGE:
                continue
            key: Any = None
            sub = path
            if isinstance(key_node, ScalarNode):
                key = loader.construct_object(key_node, deep=True)
                sub = f"{path}.{key}" if path else str(key)
                try:
                    if key in first:
                        raise DuplicateKeyError(sub, key, key_node, first[key])
                    first[key] = key_node
                except TypeError:  # an unhashable key: the constructor refuses it
                    pass
            _check_duplicates(loader, value_node, sub, seen)


def load(text: str) -> Any:
    """Parse one YAML document the YAML 1.2 way, refusing duplicate keys (see the module)."""
    loader = _Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_duplicates(loader, node, "", set())
        return loader.construct_document(node)
    finally:
        loader.dispose()


def dump(data: Any, **kwargs: Any) -> str:
    """``yaml.safe_dump`` whose output :func:`load` reads back as ``data``."""
    return str(yaml.dump(data, Dumper=_Dumper, **kwargs))


def describe(err: yaml.YAMLError) -> str:
    """One line for a YAML error: ``line 3, column 5: found duplicate key 'x' ...``."""
    mark = getattr(err, "problem_mark", None)
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
    problem = getattr(err, "problem", None)
    if not problem:
        problem = next((ln.strip() for ln in str(err).splitlines() if ln.strip()),
                       type(err).__name__)
    return f"{where}{' '.join(str(problem).split())}"
