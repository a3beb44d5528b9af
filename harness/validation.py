"""Reading parsed data (YAML or JSON) into typed frozen dataclasses, checked against their type
hints: the one validator of every file srr reads (scenario files and their plug-in parameters,
suite files, sweep declarations, a run's ``summary.json``, baseline files).

A dataclass says what a file may hold: its fields' type hints (``int``, ``float``, ``bool``,
``str``, ``Literal``, ``tuple[...]``, ``dict[str, ...]`` or ``Mapping[str, ...]``,
``X | None``, nested dataclasses, ``Any``), their defaults (a field without one is required)
and their metadata (``range``: ``(lo, hi, lo_open)``; ``internal``: not read from the file;
``key``: the key the file spells it with, where that is no Python name, such as ``from``).
Every error is one :class:`~harness.errors.ScenarioError` line naming the file and the field
path inside it (``robots[0].control.wheelbase``), long values cut
(:func:`harness.errors.shorten`).

This module knows no file format; callers parse the text and give the data.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import types
import typing
import weakref
from collections.abc import Callable, Iterable, Mapping
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

from harness.errors import ScenarioError

__all__ = ["TINY", "Layout", "Refine", "Validator", "close_match", "join", "layout", "typename",
           "validate"]

T = typing.TypeVar("T")

#: ``refine(cls, name, raw, hinted)``: the type to read field ``name`` of dataclass ``cls``
#: as, given the raw mapping it is read from (a field whose type depends on a sibling's
#: value); return ``hinted`` to keep the type hint.
Refine = Callable[[type, str, Mapping[Any, Any], Any], Any]

_MISSING = "required field is missing"

#: Type hints read as a mapping (into a dict).
_MAPPINGS = (dict, Mapping)

def typename(tp: Any) -> str:
    origin = get_origin(tp)
    if tp is float:
        return "a number"
    if tp is int:
        return "an integer"
    if tp is bool:
        return "true or false"
    if tp is str:
        return "a string"
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in get_args(tp))
    if origin is tuple:
        return "a list"
    if origin in _MAPPINGS:
        return "a mapping"
    if dataclasses.is_dataclass(tp):
        return "a mapping"
    return str(tp)


#: The least value a field that must be > 0 takes: lengths, rates and times below it are
#: zero in practice (MuJoCo refuses geom sizes under 1e-15).
TINY = 1e-9


class Validator:
    """Reads raw values into the types of a dataclass's hints.

    ``file``: the file named in errors, or a function giving it for a field path (a scenario's
    keys come from several files); ``refine``: see :data:`Refine`; ``unknown``: ``"refuse"``
    a key no field has, or ``"ignore"`` it (files that later versions may extend);
    ``missing``: the message for a required top-level field that is not there (a nested one
    says "required field is missing"); ``yaml``: the data was read from YAML (a ``yes`` for a
    boolean is then explained)."""

    def __init__(self, file: str | Callable[[str], str], *, refine: Refine | None = None,
                 unknown: Literal["refuse", "ignore"] = "refuse",
                 missing: str = _MISSING, yaml: bool = True) -> None:
        self.file_for: Callable[[str], str] = (
            (lambda _path: file) if isinstance(file, str) else file)
        self.refine = refine
        self.unknown = unknown
        self.missing = missing
        self.yaml = yaml

    def fail(self, path: str, message: str) -> typing.NoReturn:
        raise ScenarioError(self.file_for(path), path, message)

    def value(self, tp: Any, raw: Any, path: str, meta: Mapping[str, Any]) -> Any:
        origin = get_origin(tp)
        if origin in (Union, types.UnionType):
            options = [a for a in get_args(tp) if a is not type(None)]
            if raw is None:
                if type(None) in get_args(tp):
                    return None
                self.fail(path, f"expected {_alternatives(options)}, got null")
            if len(options) == 1:
                return self.value(options[0], raw, path, meta)
            return self.union(options, raw, path, meta)
        if raw is None:
            self.fail(path, f"expected {typename(tp)}, got null")
        if dataclasses.is_dataclass(tp):
            return self.dataclass(tp, raw, path)
        if origin is Literal:
            if raw not in get_args(tp):
                self.fail(path, f"expected {typename(tp)}, got {raw!r}")
            return raw
        if origin is tuple:
            return self.tuple(tp, raw, path, meta)
        if origin in _MAPPINGS:
            return self.mapping(tp, raw, path)
        if tp is Any:
            return raw
        if tp is bool:
            if not isinstance(raw, bool):
                hint = " (YAML 1.2 booleans are true and false only)" if self.yaml and isinstance(
                    raw, str) and raw.lower() in ("yes", "no", "on", "off", "y", "n") else ""
                self.fail(path, f"expected true or false, got {raw!r}{hint}")
            return raw
        if tp is int:
            if isinstance(raw, bool) or not isinstance(raw, int):
                self.fail(path, f"expected an integer, got {raw!r}")
            self.check_range(raw, path, meta)
            return raw
        if tp is float:
            if isinstance(raw, bool) or not isinstance(raw, int | float):
                self.fail(path, f"expected a number, got {raw!r}")
            if not math.isfinite(raw):
                self.fail(path, f"expected a finite number, got {raw!r}")
            self.check_range(raw, path, meta)
            return float(raw)
        if tp is str:
            if not isinstance(raw, str):
                self.fail(path, f"expected a string, got {raw!r}")
            if "\0" in raw:  # C libraries (MuJoCo) and file systems end a name there
                self.fail(path, f"contains a NUL character: {raw!r}")
            return raw
        raise TypeError(f"type {tp!r} at {path} is not supported by the validator")

    def check_range(self, raw: float, path: str, meta: Mapping[str, Any]) -> None:
        rng = meta.get("range")
        if not rng:
            return
        lo, hi, lo_open = rng
        if lo is not None and (raw <= lo if lo_open else raw < lo):
            self.fail(path, f"must be {'>' if lo_open else '>='} {lo:g}, got {raw!r}")
        if lo == 0 and lo_open and raw < TINY:  # a size of 5e-324 m is 0 to MuJoCo
            self.fail(path, f"must be > 0 (at least {TINY:g}), got {raw!r}")
        if hi is not None and raw > hi:
            self.fail(path, f"must be <= {hi:g}, got {raw!r}")

    def union(self, options: list[Any], raw: Any, path: str, meta: Mapping[str, Any]) -> Any:
        if set(options) == {int, float}:  # a number; an integer stays one
            whole = isinstance(raw, int) and not isinstance(raw, bool)
            return self.value(int if whole else float, raw, path, meta)
        if not any(_rank(o, raw) == 0 for o in options):  # none of the value's type
            self.fail(path, f"expected {_alternatives(options)}, got {raw!r}")
        # Try the options of the value's type first (a list for a list, a mapping for a
        # mapping, a number for a number), so the error reported is the one of the form the
        # user meant.
        errors: list[ScenarioError] = []
        for option in sorted(options, key=lambda o: _rank(o, raw)):
            try:
                return self.value(option, raw, path, meta)
            except ScenarioError as err:
                errors.append(err)
        raise errors[0]

    def tuple(self, tp: Any, raw: Any, path: str, meta: Mapping[str, Any]) -> tuple[Any, ...]:
        if not isinstance(raw, list | tuple):
            self.fail(path, f"expected a list, got {raw!r}")
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(self.value(args[0], item, f"{path}[{i}]", meta)
                         for i, item in enumerate(raw))
        if len(raw) != len(args):
            self.fail(path, f"expected a list of {len(args)} values, got {len(raw)}")
        return tuple(self.value(a, item, f"{path}[{i}]", meta)
                     for i, (a, item) in enumerate(zip(args, raw, strict=True)))

    def mapping(self, tp: Any, raw: Any, path: str) -> dict[str, Any]:
        if not isinstance(raw, dict):
            self.fail(path, f"expected a mapping, got {raw!r}")
        _key_tp, val_tp = get_args(tp)
        out: dict[str, Any] = {}
        for k, v in raw.items():
            if not isinstance(k, str):
                self.fail(path, f"keys must be strings, got {k!r}")
            out[k] = self.value(val_tp, v, f"{path}.{k}", {})
        return out

    def dataclass(self, cls: Any, raw: Any, path: str) -> Any:
        if not isinstance(raw, dict):
            self.fail(path or "(top level)", f"expected a mapping, got {raw!r}")
        hints, fields = layout(cls)
        if self.unknown == "refuse":
            for key in raw:
                if key not in fields:
                    close = close_match(str(key), fields)
                    hint = f" (did you mean '{close}'?)" if close else \
                        f" (expected {', '.join(fields)})" if len(fields) <= _LISTED else ""
                    if str(key).endswith("+") and str(key)[:-1] in fields:
                        hint = " (extending with '+' works for top-level keys only)"
                    self.fail(join(path, str(key)), f"unknown field{hint}")
        kwargs: dict[str, Any] = {}
        for key, f in fields.items():
            sub = join(path, key)
            if key not in raw:
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                    self.fail(sub, self.missing if not path else _MISSING)
                continue
            tp = hints[f.name]
            if self.refine is not None:
                tp = self.refine(cls, f.name, raw, tp)
            kwargs[f.name] = self.value(tp, raw[key], sub, f.metadata)
        return cls(**kwargs)


#: A dataclass's type hints (by field name) and the fields a file may hold, by the key the
#: file spells them with.
Layout = tuple[dict[str, Any], dict[str, dataclasses.Field[Any]]]
#: Each dataclass's :func:`layout`, for as long as the class lives (a plug-in's module is
#: dropped between the runs of a suite's host; its classes go with it).
_LAYOUTS: weakref.WeakKeyDictionary[type, Layout] = weakref.WeakKeyDictionary()


def layout(cls: type) -> Layout:
    """The type hints of dataclass ``cls`` and the fields a file may hold, in declaration
    order, by the key the file spells them with (metadata ``key``: a name Python cannot
    take; fields marked ``internal`` left out): what the validator reads and the schema and
    reference pages describe. Worked out once a class: resolving string annotations compiles
    each one, which every scenario load paid again for every block it read (a quarter of
    checking a suite)."""
    found = _LAYOUTS.get(cls)
    if found is None:
        fields = {f.metadata.get("key", f.name): f for f in dataclasses.fields(cls)
                  if not f.metadata.get("internal")}
        found = _LAYOUTS[cls] = (get_type_hints(cls), fields)
    return found


#: An unknown key in a dataclass of at most this many fields is answered with all of them.
_LISTED = 6


def _rank(option: Any, raw: Any) -> int:
    """How well ``raw`` fits the type ``option``: 0 of its type (a list for a list, a mapping
    for a mapping, a number for a number, a string for one of string literals), 1 another
    scalar for a scalar, 2 another form."""
    container = get_origin(option) is tuple or get_origin(option) in _MAPPINGS \
        or dataclasses.is_dataclass(option)
    if option is Any:
        return 0
    if isinstance(raw, list | tuple):
        return 0 if get_origin(option) is tuple else 2
    if isinstance(raw, dict):
        return 0 if container and get_origin(option) is not tuple else 2
    if container:
        return 2
    if get_origin(option) is Literal:
        return 0 if any(type(a) is type(raw) for a in get_args(option)) else 1
    if isinstance(raw, bool):
        return 0 if option is bool else 1
    if isinstance(raw, int | float):
        return 0 if option is float or (option is int and isinstance(raw, int)) else 1
    return 0 if option is str and isinstance(raw, str) else 1


def _alternatives(options: list[Any]) -> str:
    """``options`` in words: ``a string, a number or a mapping`` (an integer is a number)."""
    names = [typename(o) for o in options if not (o is int and float in options)]
    names = list(dict.fromkeys(names))
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"


def join(path: str, name: str) -> str:
    """The field path ``name`` inside ``path`` (``a.b``; ``b`` at the top level)."""
    return f"{path}.{name}" if path else name


def close_match(key: str, names: Iterable[str]) -> str | None:
    """The name in ``names`` (a mapping's keys, or any names) that ``key`` is most likely a
    typo of, if any."""
    found = difflib.get_close_matches(key, list(names), n=1, cutoff=0.6)
    return found[0] if found else None


def validate(cls: type[T], raw: Any, file: str | Callable[[str], str], field: str = "", *,
             refine: Refine | None = None, unknown: Literal["refuse", "ignore"] = "refuse",
             missing: str = _MISSING, yaml: bool = True) -> T:
    """``raw`` read into the dataclass ``cls`` (see :class:`Validator`); errors name ``file``
    and ``field`` (the path of ``raw`` inside the file, empty at the top level)."""
    v = Validator(file, refine=refine, unknown=unknown, missing=missing, yaml=yaml)
    return typing.cast(T, v.dataclass(cls, raw, field))
