"""JSON Schema (draft 2020-12) of a file, generated from the dataclass that
:mod:`harness.validation` reads it into: the same type hints, defaults and field metadata
(``range``, ``internal``, ``key``), so an editor checks a file by the rules ``srr validate``
applies (yaml-language-server, the VS Code YAML extension).

What the schema says and the validator checks alike: each value's type (an ``int`` is an
integer, ``int | float`` a number), ``Literal`` choices, ranges (``minimum``,
``exclusiveMinimum``, ``maximum``; a range open at 0 starts at :data:`~harness.validation.TINY`
as the validator's does), a field without a default is required, and a key no field has is
refused (``additionalProperties: false``) unless the file is read with ``unknown="ignore"``.
What it cannot say: that a number is finite, that a string holds no NUL character, that an
integer is not written ``2.0`` (JSON has one number type: a schema's integer takes it, srr
does not), and the cross-field rules a loader checks after the validator (``srr validate`` is
the full check).
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import inspect
import io
import json
import re
import sys
import tokenize
import types
from collections.abc import Mapping
from typing import Any, Literal, Union, get_args, get_origin

from harness.validation import TINY, layout

__all__ = ["DRAFT", "SchemaBuilder", "dumps", "field_comments", "json_schema", "plain"]

DRAFT = "https://json-schema.org/draft/2020-12/schema"

_MAPPINGS = (dict, Mapping)


def plain(value: Any) -> Any:
    """``value`` as JSON data: a dataclass as a mapping of its file keys, a tuple as a list
    (for a field's ``default``)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {key: plain(getattr(value, f.name)) for key, f in layout(type(value))[1].items()}
    if isinstance(value, tuple | list):
        return [plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    return value


#: A field's line in a class body: four spaces, its name, a colon.
_FIELD_LINE = re.compile(r"^    (\w+)\s*:")


def _unmark(text: str) -> str:
    """reST markup dropped: roles and double backquotes."""
    for markup in (":class:", ":mod:", ":func:", ":data:", ":meth:"):
        text = text.replace(markup, "")
    return text.replace("``", "`").replace("`~", "`")


@dataclasses.dataclass(frozen=True)
class _Source:
    """A module's source as :func:`field_comments` reads it."""

    lines: tuple[str, ...]
    comments: dict[int, str]  # line number (1-based) -> its comment's text
    alone: frozenset[int]  # the lines that hold only a comment
    classes: dict[str, tuple[int, int]]  # top-level class -> its first and last line


@functools.lru_cache(maxsize=32)
def _module_source(module: str) -> _Source | None:
    try:
        text = inspect.getsource(sys.modules[module])
        tree = ast.parse(text)
        tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (KeyError, OSError, TypeError, SyntaxError, tokenize.TokenError):
        return None
    lines = tuple(text.splitlines())
    comments: dict[int, str] = {}
    alone: set[int] = set()
    for tok in tokens:
        if tok.type == tokenize.COMMENT:
            row = tok.start[0]
            comments[row] = tok.string.lstrip("#").strip()
            if not lines[row - 1][:tok.start[1]].strip():
                alone.add(row)
    classes = {node.name: (node.lineno, node.end_lineno or node.lineno) for node in tree.body
               if isinstance(node, ast.ClassDef)}
    return _Source(lines, comments, frozenset(alone), classes)


def field_comments(cls: type) -> dict[str, str]:
    """The comments written with each field of ``cls`` (a class at the top level of its
    module) in its source: the comment lines right above the field and the one at the end of
    its line; empty where there is no source."""
    src = _module_source(cls.__module__)
    if src is None or cls.__name__ not in src.classes:
        return {}
    first, last = src.classes[cls.__name__]
    out: dict[str, str] = {}
    for row in range(first + 1, last + 1):
        m = _FIELD_LINE.match(src.lines[row - 1])
        if not m:
            continue
        above: list[str] = []
        r = row - 1
        while r in src.alone:
            above.insert(0, src.comments[r])
            r -= 1
        own = [src.comments[row]] if row in src.comments and row not in src.alone else []
        if above or own:
            out[m.group(1)] = " ".join(above + own)
    return out


def _description(cls: type) -> str | None:
    """A dataclass's own docstring (not the one dataclasses makes up from its signature),
    reST markup dropped."""
    doc = cls.__dict__.get("__doc__")
    if not doc:
        return None
    return _unmark(inspect.cleandoc(doc))


class SchemaBuilder:
    """Builds the schema of a dataclass, each nested dataclass once under ``$defs``.

    ``unknown``: as :class:`harness.validation.Validator`'s (``"refuse"``: no other keys)."""

    def __init__(self, *, unknown: Literal["refuse", "ignore"] = "refuse") -> None:
        self.unknown = unknown
        self.defs: dict[str, dict[str, Any]] = {}

    def ref(self, cls: type) -> dict[str, Any]:
        """``{"$ref": ...}`` to the definition of ``cls``, adding it when new."""
        name = cls.__name__
        if name not in self.defs:
            self.defs[name] = {}  # taken, for a dataclass that refers to itself
            self.defs[name] = self.object(cls)
        return {"$ref": f"#/$defs/{name}"}

    def object(self, cls: type) -> dict[str, Any]:
        """The schema of dataclass ``cls`` itself (not a reference to it)."""
        hints, fields = layout(cls)
        props: dict[str, Any] = {}
        required: list[str] = []
        notes = field_comments(cls)
        for key, f in fields.items():
            schema = self.value(hints[f.name], f.metadata)
            if f.name in notes:
                schema = {"description": _unmark(notes[f.name]), **schema}
            if f.default is not dataclasses.MISSING:
                schema = {**schema, "default": plain(f.default)}
            elif f.default_factory is not dataclasses.MISSING:
                schema = {**schema, "default": plain(f.default_factory())}
            else:
                required.append(key)
            props[key] = schema
        out: dict[str, Any] = {"type": "object"}
        desc = _description(cls)
        if desc:
            out["description"] = desc
        out["properties"] = props
        if required:
            out["required"] = required
        if self.unknown == "refuse":
            out["additionalProperties"] = False
        return out

    def value(self, tp: Any, meta: Mapping[str, Any]) -> dict[str, Any]:
        """The schema of a value of type ``tp`` (``meta``: its field's metadata)."""
        origin = get_origin(tp)
        if origin in (Union, types.UnionType):
            args = get_args(tp)
            options = [a for a in args if a is not type(None)]
            alts = ([{"type": "number", **_range(meta)}] if set(options) == {int, float}
                    else [self.value(o, meta) for o in options])
            if type(None) in args:
                alts.append({"type": "null"})
            return alts[0] if len(alts) == 1 else {"anyOf": alts}
        if dataclasses.is_dataclass(tp):
            return self.ref(tp)  # type: ignore[arg-type]
        if origin is Literal:
            return {"enum": list(get_args(tp))}
        if origin is tuple:
            args = get_args(tp)
            if len(args) == 2 and args[1] is Ellipsis:
                out: dict[str, Any] = {"type": "array", "items": self.value(args[0], meta)}
                if meta.get("polygon"):  # empty (none) or three points or more
                    out["anyOf"] = [{"maxItems": 0}, {"minItems": 3}]
                return out
            return {"type": "array", "prefixItems": [self.value(a, meta) for a in args],
                    "items": False, "minItems": len(args), "maxItems": len(args)}
        if origin in _MAPPINGS:
            return {"type": "object", "additionalProperties": self.value(get_args(tp)[1], {})}
        if tp is Any:
            return {}
        if tp is bool:
            return {"type": "boolean"}
        if tp is int:
            return {"type": "integer", **_range(meta)}
        if tp is float:
            return {"type": "number", **_range(meta)}
        if tp is str:
            return {"type": "string"}
        raise TypeError(f"type {tp!r} has no JSON Schema here")


def _range(meta: Mapping[str, Any]) -> dict[str, Any]:
    """The ``range`` metadata as JSON Schema keywords (see Validator.check_range)."""
    rng = meta.get("range")
    if not rng:
        return {}
    lo, hi, lo_open = rng
    out: dict[str, Any] = {}
    if lo is not None:
        if lo == 0 and lo_open:  # the validator's floor for a value that must be > 0
            out["minimum"] = TINY
        else:
            out["exclusiveMinimum" if lo_open else "minimum"] = lo
    if hi is not None:
        out["maximum"] = hi
    return out


def json_schema(cls: type, *, title: str, unknown: Literal["refuse", "ignore"] = "refuse",
                builder: SchemaBuilder | None = None) -> dict[str, Any]:
    """The whole schema document of the files read into dataclass ``cls``: its object at
    the top, the nested dataclasses under ``$defs``."""
    b = builder or SchemaBuilder(unknown=unknown)
    top = b.object(cls)
    return {"$schema": DRAFT, "title": title, **top, "$defs": dict(sorted(b.defs.items()))}


def dumps(doc: dict[str, Any]) -> str:
    """A schema document as text: indented JSON in its keys' order, with a final newline."""
    return json.dumps(doc, indent=2, ensure_ascii=False) + "\n"
