"""Load, merge and validate scenario files into a frozen :class:`Scenario`.

Validation is driven by the dataclasses' type hints, so the schema module is the single place
that says what a scenario may contain. Every error names the file the value came from and the
field path inside it (``robots[0].control.wheelbase``).
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

import yaml

from harness.errors import ScenarioError
from harness.scenario.schema import (
    FORMAT_VERSION,
    DiffDriveControl,
    ForkliftControl,
    RobotSpec,
    Scenario,
)

__all__ = ["apply_overrides", "load_scenario", "parse_override", "scenario_from_mapping",
           "scenario_to_mapping", "validate_dataclass"]

T = typing.TypeVar("T")

_CONTROL_BY_MODEL: dict[str, type] = {
    "forklift": ForkliftControl,
    "turtlebot3_waffle_pi": DiffDriveControl,
}


class _Origins:
    """Which file each top-level key came from (scenario file or one of its includes)."""

    def __init__(self, default: str) -> None:
        self.default = default
        self.by_key: dict[str, str] = {}

    def file_for(self, path: str) -> str:
        top = path.split(".", 1)[0].split("[", 1)[0]
        return self.by_key.get(top, self.default)


def _read_yaml(path: Path, shown: str, field: str = "") -> dict[str, Any]:
    if not path.exists():
        raise ScenarioError(shown, field, "file not found")
    if path.is_dir():
        raise ScenarioError(shown, field, "is a directory, not a scenario file")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise ScenarioError(shown, field, f"cannot read: {err}") from err
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise ScenarioError(shown, "", f"YAML syntax error at {where}{problem}") from err
    if data is None:
        raise ScenarioError(shown, "", "file is empty")
    if not isinstance(data, dict):
        raise ScenarioError(shown, "", f"expected a mapping at the top level, got "
                            f"{type(data).__name__}")
    return data


def _expand_includes(path: Path, data: dict[str, Any], origins: _Origins) -> dict[str, Any]:
    """Merge top-level ``include:`` files; keys in the including file win."""
    raw = data.pop("include", None)
    if raw is None:
        return data
    includes = [raw] if isinstance(raw, str) else raw
    if not isinstance(includes, list) or not all(isinstance(i, str) for i in includes):
        raise ScenarioError(str(path), "include", "expected a file name or a list of file names")
    merged: dict[str, Any] = {}
    for i, rel in enumerate(includes):
        inc_path = (path.parent / rel).resolve()
        field = "include" if isinstance(raw, str) else f"include[{i}]"
        inc = _read_yaml(inc_path, str(path.parent / rel), field)
        if "include" in inc:
            raise ScenarioError(str(path.parent / rel), "include", "nested includes are not "
                                "supported")
        if "format_version" in inc:
            inc.pop("format_version")
        for key, value in inc.items():
            if key in merged:
                raise ScenarioError(str(path.parent / rel), key,
                                    f"also defined in {origins.by_key[key]}")
            merged[key] = value
            origins.by_key[key] = str(path.parent / rel)
    for key, value in data.items():
        merged[key] = value
        origins.by_key.pop(key, None)
    return merged


# ---------------------------------------------------------------------------------------------
# Overrides (--set key=value)


def parse_override(text: str) -> tuple[str, Any]:
    """``"robots.forklift.spawn.position=[1, 2, 0]"`` → (path, parsed YAML value)."""
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ScenarioError("--set", text, "expected KEY=VALUE")
    try:
        parsed = yaml.safe_load(value) if value.strip() else ""
    except yaml.YAMLError as err:
        raise ScenarioError("--set", key, f"value is not valid YAML: {value!r}") from err
    return key, parsed


def apply_overrides(data: dict[str, Any], overrides: Sequence[tuple[str, Any]]) -> None:
    """Apply dotted-path overrides in place. List items can be addressed by index or ``name``."""
    for key, value in overrides:
        parts = key.split(".")
        node: Any = data
        for depth, part in enumerate(parts):
            last = depth == len(parts) - 1
            where = ".".join(parts[: depth + 1])
            if isinstance(node, list):
                idx = _list_index(node, part)
                if idx is None:
                    raise ScenarioError("--set", where, "no list item with that index or name")
                if last:
                    node[idx] = value
                else:
                    node = node[idx]
            elif isinstance(node, dict):
                if last:
                    node[part] = value
                else:
                    if part not in node or node[part] is None:
                        node[part] = {}
                    node = node[part]
            else:
                raise ScenarioError("--set", where, "cannot set a field inside a "
                                    f"{type(node).__name__}")


def _list_index(items: list[Any], part: str) -> int | None:
    if part.lstrip("-").isdigit():
        idx = int(part)
        return idx if -len(items) <= idx < len(items) else None
    for i, item in enumerate(items):
        if isinstance(item, dict) and item.get("name") == part:
            return i
    return None


# ---------------------------------------------------------------------------------------------
# Validation


def _typename(tp: Any) -> str:
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
    if origin is dict:
        return "a mapping"
    if dataclasses.is_dataclass(tp):
        return "a mapping"
    return str(tp)


class _Validator:
    def __init__(self, origins: _Origins) -> None:
        self.origins = origins

    def fail(self, path: str, message: str) -> typing.NoReturn:
        raise ScenarioError(self.origins.file_for(path), path, message)

    def value(self, tp: Any, raw: Any, path: str, meta: Mapping[str, Any]) -> Any:
        origin = get_origin(tp)
        if origin in (Union, types.UnionType):
            options = [a for a in get_args(tp) if a is not type(None)]
            if raw is None:
                if type(None) in get_args(tp):
                    return None
                self.fail(path, f"expected {_typename(options[0])}, got null")
            if len(options) == 1:
                return self.value(options[0], raw, path, meta)
            return self.union(options, raw, path, meta)
        if raw is None:
            self.fail(path, f"expected {_typename(tp)}, got null")
        if dataclasses.is_dataclass(tp):
            return self.dataclass(tp, raw, path)
        if origin is Literal:
            if raw not in get_args(tp):
                self.fail(path, f"expected {_typename(tp)}, got {raw!r}")
            return raw
        if origin is tuple:
            return self.tuple(tp, raw, path, meta)
        if origin is dict:
            return self.mapping(tp, raw, path)
        if tp is Any:
            return raw
        if tp is bool:
            if not isinstance(raw, bool):
                self.fail(path, f"expected true or false, got {raw!r}")
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
            return raw
        raise TypeError(f"schema type {tp!r} at {path} is not supported by the loader")

    def check_range(self, raw: float, path: str, meta: Mapping[str, Any]) -> None:
        rng = meta.get("range")
        if not rng:
            return
        lo, hi, lo_open = rng
        if lo is not None and (raw <= lo if lo_open else raw < lo):
            self.fail(path, f"must be {'>' if lo_open else '>='} {lo:g}, got {raw!r}")
        if hi is not None and raw > hi:
            self.fail(path, f"must be <= {hi:g}, got {raw!r}")

    def union(self, options: list[Any], raw: Any, path: str, meta: Mapping[str, Any]) -> Any:
        errors: list[ScenarioError] = []
        for option in options:
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
        hints = get_type_hints(cls)
        fields = {f.name: f for f in dataclasses.fields(cls)}
        for key in raw:
            if key not in fields:
                close = _close(str(key), fields)
                hint = f" (did you mean '{close}'?)" if close else ""
                self.fail(_join(path, str(key)), f"unknown field{hint}")
        kwargs: dict[str, Any] = {}
        for name, f in fields.items():
            sub = _join(path, name)
            if name not in raw:
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                    self.fail(sub, "required field is missing")
                continue
            tp = hints[name]
            if cls is RobotSpec and name == "control":
                tp = _CONTROL_BY_MODEL.get(raw.get("model", ""), ForkliftControl) | None
            kwargs[name] = self.value(tp, raw[name], sub, f.metadata)
        return cls(**kwargs)


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def _close(key: str, fields: Mapping[str, Any]) -> str | None:
    import difflib

    found = difflib.get_close_matches(key, list(fields), n=1, cutoff=0.6)
    return found[0] if found else None


def _check_semantics(sc: Scenario, v: _Validator) -> None:
    """Cross-field rules the type hints cannot express."""
    if sc.format_version != FORMAT_VERSION:
        v.fail("format_version", f"unsupported version {sc.format_version} (this srr reads "
               f"{FORMAT_VERSION})")
    _check_name(v, "name", sc.name)
    names: set[str] = set()
    for i, robot in enumerate(sc.robots):
        if robot.name in names:
            v.fail(f"robots[{i}].name", f"duplicate robot name {robot.name!r}")
        names.add(robot.name)
        _check_name(v, f"robots[{i}].name", robot.name)
    cams: set[str] = set()
    for i, cam in enumerate(sc.cameras):
        if cam.name in cams:
            v.fail(f"cameras[{i}].name", f"duplicate camera name {cam.name!r}")
        cams.add(cam.name)
        _check_name(v, f"cameras[{i}].name", cam.name)
        w, h = cam.resolution
        if not (1 <= w <= 8192 and 1 <= h <= 8192):
            v.fail(f"cameras[{i}].resolution", f"must be within 1..8192, got {w}x{h}")
    for name, route in sc.routes.items():
        if len(route.waypoints) < 2:
            v.fail(f"routes.{name}.waypoints", "a route needs at least two waypoints")
    _check_workers_and_zones(sc, v)
    _check_topics(v, sc, "")
    suts: set[str] = set()
    for i, sut in enumerate(sc.systems_under_test):
        if sut.name in suts:
            v.fail(f"systems_under_test[{i}].name", f"duplicate name {sut.name!r}")
        suts.add(sut.name)
        module, sep, attr = sut.plugin.partition(":")
        if not sep or not module or not attr:
            v.fail(f"systems_under_test[{i}].plugin",
                   f"expected 'module:Class', got {sut.plugin!r}")


def _check_workers_and_zones(sc: Scenario, v: _Validator) -> None:
    """Workers: unique names, walkable routes, bodies taller than wide. Zones: a real polygon
    (three or more points, non-zero area) and a tripwire with two distinct ends."""
    seen: set[str] = set()
    for i, worker in enumerate(sc.workers):
        where = f"workers[{i}]"
        if worker.name:
            _check_name(v, f"{where}.name", worker.name)
        name = sc.worker_name(i)
        if name in seen:
            v.fail(f"{where}.name", f"duplicate worker name {name!r}")
        seen.add(name)
        if len(worker.route) < 2:
            v.fail(f"{where}.route", "a route needs at least two waypoints")
        for j in range(1, len(worker.route)):
            if worker.route[j] == worker.route[j - 1]:
                v.fail(f"{where}.route[{j}]", "repeats the previous waypoint")
        if worker.radius > worker.height / 3:
            v.fail(f"{where}.radius", f"must be at most height / 3 ({worker.height / 3:g}), "
                   f"got {worker.radius!r}")
    roi = sc.zones.loading_roi
    if roi:
        if len(roi) < 3:
            v.fail("zones.loading_roi", f"a polygon needs at least three points, got {len(roi)}")
        area2 = sum(x0 * y1 - x1 * y0
                    for (x0, y0), (x1, y1) in zip(roi, roi[1:] + roi[:1], strict=True))
        if abs(area2) < 1e-9:
            v.fail("zones.loading_roi", "the polygon has zero area")
    wire = sc.zones.trailer_tripwire
    if wire is not None and wire.a == wire.b:
        v.fail("zones.trailer_tripwire.b", f"must differ from a {list(wire.a)}")


def _check_topics(v: _Validator, obj: Any, path: str) -> None:
    """Every field whose name ends in ``topic`` must be a valid ROS 2 topic name."""
    from harness.bus.names import TopicNameError, validate_topic

    if isinstance(obj, tuple):
        for i, item in enumerate(obj):
            _check_topics(v, item, f"{path}[{i}]")
        return
    if not dataclasses.is_dataclass(obj):
        return
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        sub = _join(path, f.name)
        if f.name.endswith("topic") and isinstance(value, str):
            try:
                validate_topic(value)
            except TopicNameError as err:
                v.fail(sub, str(err))
        else:
            _check_topics(v, value, sub)


def _check_name(v: _Validator, path: str, name: str) -> None:
    if not name or not all(c.isalnum() or c == "_" for c in name) or name[0].isdigit():
        v.fail(path, f"must be letters, digits and '_' and not start with a digit, got {name!r}")


def validate_dataclass(cls: type[T], raw: Any, file: str, field: str) -> T:
    """Validate ``raw`` into the frozen dataclass ``cls`` with the scenario rules (used for
    plug-in parameters); errors name ``file`` and ``field``."""
    return typing.cast(T, _Validator(_Origins(file)).dataclass(cls, raw, field))


def scenario_from_mapping(data: Mapping[str, Any], file: str = "<scenario>",
                          origins: Mapping[str, str] | None = None) -> Scenario:
    """Validate an already-parsed mapping (includes expanded) into a :class:`Scenario`."""
    orig = _Origins(file)
    if origins:
        orig.by_key.update(origins)
    v = _Validator(orig)
    if "format_version" not in data:
        v.fail("format_version", f"required field is missing (use {FORMAT_VERSION})")
    sc = v.dataclass(Scenario, dict(data), "")
    _check_semantics(sc, v)
    return typing.cast(Scenario, sc)


def load_scenario(path: str | Path,
                  overrides: Sequence[tuple[str, Any]] = ()) -> Scenario:
    """Read ``path`` (with its includes), apply ``--set`` overrides and validate."""
    p = Path(path)
    shown = str(path)
    origins = _Origins(shown)
    data = _read_yaml(p, shown)
    data = _expand_includes(p, data, origins)
    if overrides:
        apply_overrides(data, overrides)
        for key, _ in overrides:
            origins.by_key.setdefault(key.split(".", 1)[0], shown)
    return scenario_from_mapping(data, shown, origins.by_key)


def scenario_to_mapping(sc: Scenario) -> dict[str, Any]:
    """The resolved scenario as plain YAML-able data (includes expanded, defaults filled)."""

    def plain(obj: Any) -> Any:
        if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            return {f.name: plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
        if isinstance(obj, tuple | list):
            return [plain(x) for x in obj]
        if isinstance(obj, dict):
            return {k: plain(v) for k, v in obj.items()}
        return obj

    out = plain(sc)
    assert isinstance(out, dict)
    return out
