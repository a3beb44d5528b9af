"""Load, merge and validate scenario files into a frozen :class:`Scenario`.

Validation is driven by the dataclasses' type hints, so the schema module is the single place
that says what a scenario may contain. Every error names the file the value came from and the
field path inside it (``robots[0].control.wheelbase``).
"""

from __future__ import annotations

import dataclasses
import math
import re
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

import yaml

from harness import yamlio
from harness.errors import ScenarioError, SrrError, reason
from harness.scenario.schema import (
    BUILTIN_JOINTS,
    FORMAT_VERSION,
    CameraRecordSpec,
    ControlScoring,
    DiffDriveControl,
    ForkliftControl,
    GraphSpec,
    H264Spec,
    RobotSpec,
    SafetyScoring,
    Scenario,
    ScoringSpec,
    WorldSpec,
    gated_rate,
)

__all__ = ["RATE_TOLERANCE", "apply_overrides", "graph_name", "load_scenario", "parse_override",
           "rate_warnings", "resolve_names", "scenario_from_mapping", "scenario_to_mapping",
           "sensor_rates", "validate_dataclass"]

T = typing.TypeVar("T")

_CONTROL_BY_MODEL: dict[str, type] = {
    "forklift": ForkliftControl,
    "turtlebot3_waffle_pi": DiffDriveControl,
}


class _Origins:
    """Which file each top-level key, or each item of a list extended with ``key+``, came from
    (the scenario file or one of its includes)."""

    def __init__(self, default: str) -> None:
        self.default = default
        self.by_key: dict[str, str] = {}

    def file_for(self, path: str) -> str:
        head = path.split(".", 1)[0]
        return (self.by_key.get(head) or self.by_key.get(head.split("[", 1)[0])
                or self.default)

    def forget(self, key: str) -> None:
        """``key`` is defined anew: drop it and its items' origins."""
        for k in [k for k in self.by_key if k == key or k.startswith(f"{key}[")]:
            del self.by_key[k]


def _read_yaml(path: Path, shown: str, field: str = "") -> dict[str, Any]:
    try:
        if not path.exists():
            raise ScenarioError(shown, field, "file not found")
        if path.is_dir():
            raise ScenarioError(shown, field, "is a directory, not a scenario file")
        text = path.read_text(encoding="utf-8")
    except (OSError, ValueError) as err:  # a name too long, a NUL byte, no permission
        why = err.strerror if isinstance(err, OSError) and err.strerror else reason(err)
        raise ScenarioError(shown, field, f"cannot read: {why}") from err
    try:
        data = yamlio.load(text)
    except yamlio.DuplicateKeyError as err:
        raise ScenarioError(shown, err.field, f"set twice (lines {err.first_line} and "
                            f"{err.line}): remove one") from err
    except yaml.YAMLError as err:
        raise ScenarioError(shown, "", f"YAML syntax error at {yamlio.describe(err)}") from err
    if data is None:
        raise ScenarioError(shown, "", "file is empty")
    if not isinstance(data, dict):
        raise ScenarioError(shown, "", f"expected a mapping at the top level, got "
                            f"{type(data).__name__}")
    return data


def _expand_includes(path: Path, data: dict[str, Any], origins: _Origins) -> dict[str, Any]:
    """Merge top-level ``include:`` files in order; keys in the including file win.

    A key written ``key+`` (in the scenario file or a later include) extends what is there
    instead of replacing it: a list gets the new items appended (an item whose ``name`` is
    already there is refused), a mapping gets the new keys (a key already there is refused).
    """
    raw = data.pop("include", None)
    shown = str(path)
    if raw is None:
        includes: list[Any] = []
    else:
        includes = [raw] if isinstance(raw, str) else raw
        if not isinstance(includes, list) or not all(isinstance(i, str) for i in includes):
            raise ScenarioError(shown, "include", "expected a file name or a list of file names")
    merged: dict[str, Any] = {}
    for i, rel in enumerate(includes):
        field = "include" if isinstance(raw, str) else f"include[{i}]"
        if not rel or "\0" in rel:
            raise ScenarioError(shown, field, f"not a file name: {rel!r}")
        inc_path = (path.parent / rel).resolve()
        inc_shown = str(path.parent / rel)
        inc = _read_yaml(inc_path, inc_shown, field)
        if "include" in inc:
            raise ScenarioError(inc_shown, "include", "nested includes are not supported")
        inc.pop("format_version", None)
        for key, value in inc.items():
            if str(key).endswith("+"):
                _extend(merged, str(key), value, inc_shown, origins)
                continue
            if key in merged:
                raise ScenarioError(inc_shown, key, f"also defined in {origins.by_key[key]}")
            merged[key] = value
            origins.by_key[key] = inc_shown
    for key in data:
        if str(key).endswith("+") and str(key)[:-1] in data:
            raise ScenarioError(shown, str(key), f"both {str(key)[:-1]!r} and {key!r} are set: "
                                f"use {str(key)[:-1]!r} to replace the included value or "
                                f"{key!r} to extend it")
    for key, value in data.items():
        if str(key).endswith("+"):
            _extend(merged, str(key), value, shown, origins)
            continue
        merged[key] = value
        origins.forget(key)
    return merged


def _extend(merged: dict[str, Any], key: str, value: Any, shown: str,
            origins: _Origins) -> None:
    """Apply ``key+: value`` to ``merged`` (see :func:`_expand_includes`)."""
    base = key[:-1]
    if base not in merged:  # nothing to extend yet: the value is the first definition
        merged[base] = value
        origins.by_key[base] = shown
        return
    old = merged[base]
    where = origins.file_for(base)
    if isinstance(old, list):
        if not isinstance(value, list):
            raise ScenarioError(shown, key, f"expected a list of items to append to {base!r}, "
                                f"got {value!r}")
        names = {item.get("name"): n for n, item in enumerate(old)
                 if isinstance(item, dict) and item.get("name")}
        for j, item in enumerate(value):
            name = item.get("name") if isinstance(item, dict) else None
            if name and name in names:
                first = origins.file_for(f"{base}[{names[name]}]")
                raise ScenarioError(shown, f"{key}[{j}].name",
                                    f"{base} already has an item named {name!r} (from {first}); "
                                    f"change it with --set {base}.{name}.FIELD=VALUE or replace "
                                    f"the whole list with {base!r}")
            if name:
                names[name] = len(old)
            origins.by_key.setdefault(base, where)
            origins.by_key[f"{base}[{len(old)}]"] = shown
            old.append(item)
        return
    if isinstance(old, dict):
        if not isinstance(value, dict):
            raise ScenarioError(shown, key, f"expected a mapping of entries to add to {base!r}, "
                                f"got {value!r}")
        for k, v in value.items():
            if k in old:
                raise ScenarioError(shown, f"{key}.{k}", f"{base} already has {k!r} (from "
                                    f"{where}); replace the whole mapping with {base!r}")
            old[k] = v
        return
    raise ScenarioError(shown, key, f"only a list or a mapping can be extended; {base!r} is "
                        f"{old!r}")


# ---------------------------------------------------------------------------------------------
# Overrides (--set key=value)


def parse_override(text: str) -> tuple[str, Any]:
    """``"robots.forklift.spawn.position=[1, 2, 0]"`` → (path, parsed YAML value)."""
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ScenarioError("--set", text, "expected KEY=VALUE")
    try:
        parsed = yamlio.load(value) if value.strip() else ""
    except yaml.YAMLError as err:
        raise ScenarioError("--set", key, f"value is not valid YAML ({yamlio.describe(err)}): "
                            f"{value!r}") from err
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


#: The least value a field that must be > 0 takes: lengths, rates and times below it are
#: zero in practice (MuJoCo refuses geom sizes under 1e-15).
_TINY = 1e-9


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
                hint = " (YAML 1.2 booleans are true and false only)" if isinstance(
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
        raise TypeError(f"schema type {tp!r} at {path} is not supported by the loader")

    def check_range(self, raw: float, path: str, meta: Mapping[str, Any]) -> None:
        rng = meta.get("range")
        if not rng:
            return
        lo, hi, lo_open = rng
        if lo is not None and (raw <= lo if lo_open else raw < lo):
            self.fail(path, f"must be {'>' if lo_open else '>='} {lo:g}, got {raw!r}")
        if lo == 0 and lo_open and raw < _TINY:  # a size of 5e-324 m is 0 to MuJoCo
            self.fail(path, f"must be > 0 (at least {_TINY:g}), got {raw!r}")
        if hi is not None and raw > hi:
            self.fail(path, f"must be <= {hi:g}, got {raw!r}")

    def union(self, options: list[Any], raw: Any, path: str, meta: Mapping[str, Any]) -> Any:
        # Try the options shaped like the value first (a list for a list, a mapping for a
        # mapping), so the error reported is the one of the form the user meant.
        def fits(option: Any) -> bool:
            if isinstance(raw, list | tuple):
                return get_origin(option) is tuple
            if isinstance(raw, dict):
                return dataclasses.is_dataclass(option) or get_origin(option) is dict
            return True

        options = sorted(options, key=lambda o: not fits(o))
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
        fields = {f.name: f for f in dataclasses.fields(cls) if not f.metadata.get("internal")}
        for key in raw:
            if key not in fields:
                close = _close(str(key), fields)
                hint = f" (did you mean '{close}'?)" if close else ""
                if str(key).endswith("+") and str(key)[:-1] in fields:
                    hint = " (extending with '+' works for top-level keys only)"
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
                tp = _control_type(raw.get("model")) | None
            kwargs[name] = self.value(tp, raw[name], sub, f.metadata)
        return cls(**kwargs)


def _control_type(model: Any) -> type:
    """The ``control:`` block type a robot's ``model`` value calls for: by built-in name, or
    by a model file's ``drive`` (``swivel_drive``: the forklift's block)."""
    if isinstance(model, dict):
        return ForkliftControl if model.get("drive") == "swivel_drive" else DiffDriveControl
    return _CONTROL_BY_MODEL.get(model, ForkliftControl) if isinstance(model, str) \
        else ForkliftControl


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
    names: dict[str, int] = {}
    for i, robot in enumerate(sc.robots):
        if robot.name in names:
            j = names[robot.name]
            v.fail(f"robots[{i}].name", f"duplicate robot name {robot.name!r} (also robots[{j}], "
                   f"from {v.origins.file_for(f'robots[{j}]')})")
        names[robot.name] = i
        _check_name(v, f"robots[{i}].name", robot.name)
    for name, route in sc.routes.items():
        if len(route.waypoints) < 2:
            v.fail(f"routes.{name}.waypoints", "a route needs at least two waypoints")
    _check_workers_and_zones(sc, v)
    _check_names(v, sc, "")
    _check_world(sc, v)
    _check_robots(sc, v)
    _check_robot_cameras(sc, v)
    _check_cameras(sc, v)
    _check_suts(sc, v)
    _check_graphs(sc, v)
    _check_control_scoring(sc, v)
    _check_output(sc, v)
    _check_rates(sc, v)


#: How far (relative) the rate a sensor really gets may be from the rate it asks for before
#: the scenario is refused; closer, ``srr validate`` warns (:func:`rate_warnings`).
RATE_TOLERANCE = 0.10


def sensor_rates(sc: Scenario) -> list[tuple[str, float, float]]:
    """(field, rate asked for, rate it really gets) of every sensor a built-in graph
    publishes behind a simulation gate: a sensor publishes every ``gate_step``-th tick, so
    only ``tick_hz / n`` is possible (:func:`~harness.scenario.schema.gated_rate`)."""
    hz = sc.physics.tick_hz
    out: list[tuple[str, float, float]] = []
    for i, robot in enumerate(sc.robots):
        if not robot.enabled:
            continue
        s = robot.sensors
        for kind, spec in (("camera", s.camera), ("lidar", s.lidar), ("imu", s.imu)):
            if spec is not None and spec.enabled and spec.graph:
                out.append((f"robots[{i}].sensors.{kind}.fps", spec.fps,
                            gated_rate(hz, spec.fps)))
    for i, cam in enumerate(sc.cameras):
        if cam.enabled and cam.outputs:
            out.append((f"cameras[{i}].fps", cam.fps, gated_rate(hz, cam.fps)))
    if sc.rtsp.enabled and any(c.enabled and c.port is not None for c in sc.cameras):
        out.append(("rtsp.fps", sc.rtsp.fps, gated_rate(hz, sc.rtsp.fps)))
    return out


def _possible_rates(tick_hz: int) -> str:
    return ", ".join(f"{tick_hz / n:.4g}" for n in range(1, 6))


def _rate_message(sc: Scenario, asked: float, real: float) -> str:
    hz = sc.physics.tick_hz
    return (f"{asked:g} Hz cannot be given on the {hz} Hz tick (physics.tick_hz): a sensor "
            f"publishes every n-th tick, so it would publish at {real:.4g} Hz")


def _check_rates(sc: Scenario, v: _Validator) -> None:
    """Refuse a sensor rate the tick cannot give within :data:`RATE_TOLERANCE`."""
    for field, asked, real in sensor_rates(sc):
        if abs(real - asked) > RATE_TOLERANCE * asked:
            v.fail(field, f"{_rate_message(sc, asked, real)}; ask for tick_hz / n "
                   f"({_possible_rates(sc.physics.tick_hz)}, ... Hz) or change "
                   "physics.tick_hz")


def rate_warnings(sc: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """One warning per sensor whose real rate differs (by less than
    :data:`RATE_TOLERANCE`; more is refused) from the rate it asks for."""
    return tuple(f"{sc.file_for(field, source)}: {field}: {_rate_message(sc, asked, real)}"
                 for field, asked, real in sensor_rates(sc) if abs(real - asked) > 1e-9)


def _check_output(sc: Scenario, v: _Validator) -> None:
    """``output:`` values that cannot work together (what the graphs imply is checked once
    they are built: :mod:`harness.output`)."""
    out = sc.output
    if isinstance(out.ros, bool):  # YAML true == 1 to Literal[1, 2]
        v.fail("output.ros", f"expected one of 1, 2, got {out.ros!r}")
    if out.format == "bag" and out.ros == 2:
        v.fail("output.format", "bag is a ROS 1 bag; ROS 2 output is a rosbag2 directory "
               "(format: mcap)")
    ros1 = out.ros == 1 or out.format == "bag"
    if out.format == "bag" and sc.recording.compression == "zstd":
        v.fail("recording.compression", "a ROS 1 bag compresses its chunks with lz4 (or "
               "bz2), not zstd: use lz4 or none, or output.format: mcap")
    if ros1 and sc.ros2.enabled:
        v.fail("ros2.enabled", "the live ROS 2 bridge needs ROS 2 output, and this scenario "
               "records ROS 1 (output)")


_PROCEDURAL_FIELDS = ("size", "wall_height", "shelves", "dock")


def _check_world(sc: Scenario, v: _Validator) -> None:
    """A world file: exactly one of ``mjcf``/``urdf``; with ``mode: replace`` no procedural
    field set to anything but its default (it would be silently unused); a valid prim that no
    robot or camera lies in (or holds)."""
    from harness.scenario.prims import check_prim_path

    model = sc.world.model
    if model is None:
        return
    if (model.urdf is None) == (model.mjcf is None):
        v.fail("world.model", "set exactly one of 'urdf' and 'mjcf' (the path of the world's "
               "model file)")
    if not model.path.strip():
        v.fail(f"world.model.{model.kind}", "must not be empty")
    if model.mode == "replace":
        default = WorldSpec()
        for name in _PROCEDURAL_FIELDS:
            if getattr(sc.world, name) != getattr(default, name):
                v.fail(f"world.{name}", "is not used: world.model.mode is 'replace' (the model "
                       "file is the whole world); use mode: extend to build the procedural "
                       "warehouse around the file, or leave this field out")
    try:
        check_prim_path(model.prim)
    except SrrError as err:
        v.fail("world.model.prim", str(err))
    root = model.prim.rstrip("/")
    taken = [(f"robots[{i}].articulation_prim", r.prim) for i, r in enumerate(sc.robots)
             if r.enabled]
    taken += [(f"cameras[{i}].camera_prim", c.prim) for i, c in enumerate(sc.cameras)
              if c.enabled]
    for field, prim in taken:
        if prim == root or prim.startswith(root + "/") or root.startswith(prim + "/"):
            v.fail(field, f"{prim} overlaps {root}, where the world file's bodies are "
                   "(world.model.prim): move one of them")


def _check_robots(sc: Scenario, v: _Validator) -> None:
    """Namespaces and frame prefixes that ROS accepts; no two enabled robots on one prim (or
    one robot's prim inside another's)."""
    from harness.bus.names import (
        FrameIdError,
        TopicNameError,
        validate_frame_id,
        validate_namespace,
    )
    from harness.scenario.prims import check_prim_path

    for i, robot in enumerate(sc.robots):
        if robot.articulation_prim:
            try:
                check_prim_path(robot.prim)
            except SrrError as err:
                v.fail(f"robots[{i}].articulation_prim", str(err))
        model = robot.model_file
        if model is not None:
            if (model.urdf is None) == (model.mjcf is None):
                v.fail(f"robots[{i}].model", "set exactly one of 'urdf' and 'mjcf' (the "
                       "path of the robot's model file)")
            if not model.path.strip():
                v.fail(f"robots[{i}].model.{model.kind}", "must not be empty")
        else:
            _check_builtin_joints(v, f"robots[{i}].control", robot)
        if robot.namespace is not None:
            try:
                validate_namespace(robot.namespace)
            except TopicNameError as err:
                v.fail(f"robots[{i}].namespace", str(err))
        if robot.frame_prefix:
            try:
                validate_frame_id(robot.frame_prefix)
            except FrameIdError as err:
                v.fail(f"robots[{i}].frame_prefix", str(err).replace("frame id", "prefix"))
    enabled = [(i, r) for i, r in enumerate(sc.robots) if r.enabled]
    for n, (i, robot) in enumerate(enabled):
        for j, other in enabled[:n]:
            if robot.prim == other.prim:
                v.fail(f"robots[{i}].articulation_prim", f"{robot.prim} is also the prim of "
                       f"robots[{j}] ({other.name}): two robots cannot share one prim")
            for inner, outer, k in ((robot, other, j), (other, robot, i)):
                if inner.prim.startswith(outer.prim.rstrip("/") + "/"):
                    v.fail(f"robots[{i}].articulation_prim",
                           f"{inner.prim} lies inside {outer.prim}, the prim of robots[{k}] "
                           f"({outer.name})")


def _check_builtin_joints(v: _Validator, where: str, robot: RobotSpec) -> None:
    """A built-in model's ``control:`` names joints it has: the TurtleBot3's two wheel
    joints; the forklift's swivel and drive joints, distinct from each other and from its
    front wheels' joints."""
    control, fixed = robot.control, BUILTIN_JOINTS.get(str(robot.model), ())
    if isinstance(control, DiffDriveControl):
        unknown = [j for j in control.joint_names if j not in fixed]
        if unknown:
            v.fail(f"{where}.joint_names", f"{unknown} are not joints of {robot.model} "
                   f"(it has {list(fixed)})")
    elif isinstance(control, ForkliftControl):
        for sub, name in (("swivel_joint", control.swivel_joint),
                          ("drive_joint", control.drive_joint)):
            if name in fixed:
                v.fail(f"{where}.{sub}", f"{name!r} is a front wheel joint of the forklift; "
                       "name the swivel and drive joints otherwise")
        if control.swivel_joint == control.drive_joint:
            v.fail(f"{where}.drive_joint", f"{control.drive_joint!r} is also the swivel "
                   "joint: the two joints need distinct names")


def _check_cameras(sc: Scenario, v: _Validator) -> None:
    """Unique names and resolutions in range; no camera on another camera's or a robot's prim."""
    from harness.scenario.prims import check_prim_path

    cams: dict[str, int] = {}
    prims: dict[str, str] = {r.prim: f"robots[{i}] ({r.name})"
                             for i, r in enumerate(sc.robots) if r.enabled}
    for i, cam in enumerate(sc.cameras):
        if cam.name in cams:
            j = cams[cam.name]
            v.fail(f"cameras[{i}].name", f"duplicate camera name {cam.name!r} (also "
                   f"cameras[{j}], from {v.origins.file_for(f'cameras[{j}]')})")
        cams[cam.name] = i
        _check_name(v, f"cameras[{i}].name", cam.name)
        if cam.camera_prim:
            try:
                check_prim_path(cam.prim)
            except SrrError as err:
                v.fail(f"cameras[{i}].camera_prim", str(err))
        _check_resolution(v, f"cameras[{i}].resolution", cam.resolution)
        _check_record(v, f"cameras[{i}]", cam.record,
                      {s: f"{cam.name}_{s}" for s in ("rgb", "depth") if s in cam.outputs},
                      f"cameras[{i}].outputs has no '{{stream}}'", cam.resolution)
        if not cam.enabled:
            continue
        if cam.prim in prims:
            v.fail(f"cameras[{i}].camera_prim", f"{cam.prim} is already the prim of "
                   f"{prims[cam.prim]}")
        prims[cam.prim] = f"cameras[{i}] ({cam.name})"
    _check_rtsp(sc, v)


def _check_resolution(v: _Validator, path: str, resolution: tuple[int, int]) -> None:
    w, h = resolution
    if not (1 <= w <= 8192 and 1 <= h <= 8192):
        v.fail(path, f"must be within 1..8192, got {w}x{h}")


_MOUNT_PATH = re.compile(r"^(/[A-Za-z0-9._~-]+)+$")


def _check_record(v: _Validator, where: str, rec: CameraRecordSpec, raw: Mapping[str, str],
                  lacking: str, resolution: tuple[int, int]) -> None:
    """The ``record`` block of the camera at ``where`` (``raw``: the raw topic of each image
    stream it publishes; ``lacking``: why it does not publish a ``{stream}``): formats of
    streams the camera has, each once, one still format per topic, even sizes for h264."""
    _check_h264(v, f"{where}.record.h264", rec.h264)
    for stream, formats in (("rgb", rec.rgb), ("depth", rec.depth)):
        path = f"{where}.record.{stream}"
        for k, fmt in enumerate(formats):
            if fmt in formats[:k]:
                v.fail(f"{path}[{k}]", f"{fmt!r} is listed twice")
        if formats and formats != ("raw",) and stream not in raw:
            v.fail(path, f"records {', '.join(formats)} of the {stream} stream, but "
                   + lacking.format(stream=stream))
    if "jpeg" in rec.rgb and "png" in rec.rgb:
        v.fail(f"{where}.record.rgb", "jpeg and png both go to "
               f"{raw['rgb']}/compressed: choose one")
    w, h = resolution
    if "h264" in rec.rgb and (w % 2 or h % 2):
        v.fail(f"{where}.resolution", f"h264 ({where}.record.rgb) needs an even "
               f"width and height, got {w}x{h}")


def _check_robot_cameras(sc: Scenario, v: _Validator) -> None:
    """A robot camera's ``record`` block, as a fixed camera's; none without srr's graph."""
    for i, robot in enumerate(sc.robots):
        cam = robot.sensors.camera
        if cam is None:
            continue
        where = f"robots[{i}].sensors.camera"
        _check_resolution(v, f"{where}.resolution", cam.resolution)
        if not cam.graph and cam.record != CameraRecordSpec():
            v.fail(f"{where}.record", "has no effect with graph: false (the graphs: builder "
                   "that publishes the camera decides what it records)")
        raw = {"rgb": cam.topic} | ({"depth": cam.depth_topic} if cam.depth_topic else {})
        _check_record(v, where, cam.record, raw, f"{where}.depth_topic is not set",
                      cam.resolution)


#: Speed presets each h264 encoder knows.
H264_PRESETS = {
    "x264": ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow",
             "slower", "veryslow", "placebo"),
    "nvenc": ("p1", "p2", "p3", "p4", "p5", "p6", "p7"),
}


def _check_h264(v: _Validator, path: str, spec: H264Spec) -> None:
    if spec.preset is not None and spec.preset not in H264_PRESETS[spec.encoder]:
        v.fail(f"{path}.preset", f"{spec.encoder} has no preset {spec.preset!r} (presets: "
               f"{', '.join(H264_PRESETS[spec.encoder])})")


def _check_rtsp(sc: Scenario, v: _Validator) -> None:
    """``rtsp:`` and the cameras' ``port`` / ``mount_path``: valid mount paths, no two
    streams at one URL, h264-able sizes, at least one stream when enabled."""
    urls: dict[tuple[int, str], int] = {}
    streams = 0
    for i, cam in enumerate(sc.cameras):
        if cam.mount_path is not None and not _MOUNT_PATH.match(cam.mount_path):
            v.fail(f"cameras[{i}].mount_path", "must be '/' followed by letters, digits and "
                   f"'._~-' (segments separated by '/'), got {cam.mount_path!r}")
        if cam.port is None or not cam.enabled:
            continue
        streams += 1
        key = (cam.port, cam.mount)
        if key in urls:
            j = urls[key]
            v.fail(f"cameras[{i}].port", f"rtsp://{sc.rtsp.host}:{cam.port}{cam.mount} is "
                   f"also the stream of cameras[{j}] ({sc.cameras[j].name}): give each "
                   "camera its own port (or mount_path)")
        urls[key] = i
        w, h = cam.resolution
        if sc.rtsp.enabled and (w % 2 or h % 2):
            v.fail(f"cameras[{i}].resolution", f"an RTSP stream (h264, 4:2:0) needs an even "
                   f"width and height, got {w}x{h}")
    _check_h264(v, "rtsp.h264", sc.rtsp.h264)
    if not sc.rtsp.enabled:
        return
    if not sc.rtsp.host.strip():
        v.fail("rtsp.host", "must not be empty")
    if streams == 0:
        v.fail("rtsp.enabled", "no enabled camera has a port: give each camera to stream a "
               "port (and optionally a mount_path) in cameras")


def _check_suts(sc: Scenario, v: _Validator) -> None:
    """Unique names, ``module:Class`` plug-ins, a bound robot that exists, valid namespaces
    and remapping rules."""
    from harness.bus.names import TopicNameError, validate_namespace, validate_topic

    robots = [r.name for r in sc.robots if r.enabled]
    suts: set[str] = set()
    for i, sut in enumerate(sc.systems_under_test):
        where = f"systems_under_test[{i}]"
        if sut.name in suts:
            v.fail(f"{where}.name", f"duplicate name {sut.name!r}")
        suts.add(sut.name)
        module, sep, attr = sut.plugin.partition(":")
        if not sep or not module or not attr:
            v.fail(f"{where}.plugin", f"expected 'module:Class', got {sut.plugin!r}")
        if sut.robot and sut.robot not in robots and sut.enabled:
            if any(r.name == sut.robot for r in sc.robots):
                v.fail(f"{where}.robot", f"robot {sut.robot!r} is disabled; disable this "
                       "system under test too (enabled: false) or bind it to another robot")
            close = _close(sut.robot, dict.fromkeys(robots))
            hint = f"did you mean {close!r}? " if close else ""
            v.fail(f"{where}.robot", f"no enabled robot named {sut.robot!r} ({hint}robots: "
                   f"{', '.join(robots) or 'none'})")
        if sut.namespace is not None:
            try:
                validate_namespace(sut.namespace)
            except TopicNameError as err:
                v.fail(f"{where}.namespace", str(err))
        for src, dst in sut.remap.items():
            for name, sub in ((src, f"{where}.remap"), (dst, f"{where}.remap.{src}")):
                try:
                    validate_topic(name)
                except TopicNameError as err:
                    v.fail(sub, str(err))


def graph_name(spec: GraphSpec) -> str:
    """A ``graphs:`` entry's name: its own, else the builder function's name, else (for a
    function called ``build``) the module's last component."""
    if spec.name is not None:
        return spec.name
    module, _, func = spec.builder.partition(":")
    return func if func and func != "build" else module.rsplit(".", 1)[-1]


def _check_graphs(sc: Scenario, v: _Validator) -> None:
    """``module:function`` builders, unique names that make valid graph paths, and a robot
    that exists and is enabled (or, left out, a scene with exactly one enabled robot)."""
    robots = [r.name for r in sc.robots if r.enabled]
    names: dict[str, int] = {}
    for i, spec in enumerate(sc.graphs):
        where = f"graphs[{i}]"
        module, sep, func = spec.builder.partition(":")
        if not sep or not module or not func:
            v.fail(f"{where}.builder", f"expected 'module:function', got {spec.builder!r}")
        name = graph_name(spec)
        _check_name(v, f"{where}.name", name)
        if name in names:
            v.fail(f"{where}.name", f"duplicate graph name {name!r} (also graphs[{names[name]}]"
                   "); give one of them another name")
        names[name] = i
        if spec.robot and spec.enabled and spec.robot not in robots:
            close = _close(spec.robot, dict.fromkeys(robots))
            hint = f"did you mean {close!r}? " if close else ""
            v.fail(f"{where}.robot", f"no enabled robot named {spec.robot!r} ({hint}robots: "
                   f"{', '.join(robots) or 'none'})")


def _check_control_scoring(sc: Scenario, v: _Validator) -> None:
    """One control block per robot when ``scoring.control`` is a list; a block (or the
    safety block) that leaves ``robot`` out needs exactly one enabled robot to default to."""
    robots = [r.name for r in sc.robots if r.enabled]
    c = sc.scoring.control
    blocks: list[tuple[str, ControlScoring | SafetyScoring]] = \
        [] if c is None else [("scoring.control", c)] if not isinstance(c, tuple) else \
        [(f"scoring.control[{i}]", b) for i, b in enumerate(c)]
    if sc.scoring.safety is not None:
        blocks.append(("scoring.safety", sc.scoring.safety))
    for where, block in blocks:
        if block.enabled and not block.robot and len(robots) != 1:
            v.fail(f"{where}.robot", "required: the scene has "
                   f"{len(robots) or 'no'} enabled robots ({', '.join(robots) or 'none'}), "
                   "so there is no single robot to default to")
    if not isinstance(sc.scoring.control, tuple):
        return
    seen: dict[str, int] = {}
    for i, block in enumerate(sc.scoring.control):
        if block.robot in seen:
            v.fail(f"scoring.control[{i}].robot", f"robot {block.robot!r} is already scored by "
                   f"scoring.control[{seen[block.robot]}]")
        seen[block.robot] = i


def resolve_names(sc: Scenario) -> Scenario:
    """Fill in the robots' namespaces and frame prefixes and the systems under test's
    namespaces (see :class:`~harness.scenario.schema.RobotSpec`).

    With more than one enabled robot, a robot without ``namespace`` gets its name, and one
    without ``frame_prefix`` gets its namespace (or name) + ``/``, like robot_state_publisher's
    ``frame_prefix`` in ROS 2 multi-robot launches; with one robot both stay empty, so a
    single robot keeps the seeds' names. A prefix always ends in ``/``. A system under test
    bound to a robot takes the robot's namespace unless it sets its own.
    """
    multi = sum(r.enabled for r in sc.robots) > 1
    robots = []
    for r in sc.robots:
        ns = r.namespace if r.namespace is not None else (r.name if multi else "")
        if r.frame_prefix is not None:
            prefix = r.frame_prefix
        else:
            prefix = (ns.strip("/") or r.name) if multi else ""
        if prefix and not prefix.endswith("/"):
            prefix += "/"
        robots.append(dataclasses.replace(r, namespace=ns, frame_prefix=prefix))
    by_name = {r.name: r for r in robots}
    suts = []
    for sut in sc.systems_under_test:
        sut_ns = sut.namespace
        if sut_ns is None:
            sut_ns = by_name[sut.robot].ns if sut.robot in by_name else ""
        suts.append(dataclasses.replace(sut, namespace=sut_ns))
    enabled = [r.name for r in robots if r.enabled]
    only = enabled[0] if len(enabled) == 1 else ""
    graphs = tuple(dataclasses.replace(g, name=graph_name(g), robot=g.robot or only)
                   for g in sc.graphs)
    return dataclasses.replace(sc, robots=tuple(robots), systems_under_test=tuple(suts),
                               graphs=graphs, scoring=_default_scored_robot(sc.scoring, only))


def _default_scored_robot(scoring: ScoringSpec, only: str) -> ScoringSpec:
    """``scoring.control`` blocks and ``scoring.safety`` that leave ``robot`` out score the
    only enabled robot ``only``, as ``graphs:`` entries do."""
    def fill(block: ControlScoring) -> ControlScoring:
        return dataclasses.replace(block, robot=block.robot or only)

    c = scoring.control
    control = None if c is None else fill(c) if not isinstance(c, tuple) else \
        tuple(fill(b) for b in c)
    s = scoring.safety
    safety = None if s is None else dataclasses.replace(s, robot=s.robot or only)
    return dataclasses.replace(scoring, control=control, safety=safety)


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


def _name_rule(field: str) -> Callable[[str], None] | None:
    """The naming rule of a string field, by its name: ROS topic names for ``*topic``
    fields, tf2 frame ids for ``*_frame`` and ``frame_id`` fields."""
    from harness.bus.names import validate_frame_id, validate_topic

    if field.endswith("topic"):
        return validate_topic
    if field.endswith("_frame") or field == "frame_id":
        return validate_frame_id
    return None


def _check_names(v: _Validator, obj: Any, path: str) -> None:
    """Every topic field must be a valid ROS 2 topic name and every frame field a frame id
    tf2 accepts (see :func:`_name_rule`)."""
    from harness.bus.names import FrameIdError, TopicNameError, validate_topic

    if isinstance(obj, tuple):
        for i, item in enumerate(obj):
            _check_names(v, item, f"{path}[{i}]")
        return
    if not dataclasses.is_dataclass(obj):
        return
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        sub = _join(path, f.name)
        rule = _name_rule(f.name)
        if rule is not None and isinstance(value, str):
            try:
                rule(value)
            except (TopicNameError, FrameIdError) as err:
                v.fail(sub, str(err))
        elif f.name in _TOPIC_LISTS or f.name in _TOPIC_KEYED:
            names = value if f.name in _TOPIC_LISTS else tuple(value)
            for i, name in enumerate(names):
                try:
                    validate_topic(name)
                except TopicNameError as err:
                    v.fail(f"{sub}[{i}]" if f.name in _TOPIC_LISTS else f"{sub}.{name}",
                           str(err))
        else:
            _check_names(v, value, sub)


#: Fields that hold a list of topic names, and mappings keyed by topic names.
_TOPIC_LISTS = frozenset({"marker_topics"})
_TOPIC_KEYED = frozenset({"expected_rates", "sut_outputs"})

def _check_name(v: _Validator, path: str, name: str) -> None:
    if not name or not all(c.isascii() and (c.isalnum() or c == "_") for c in name) \
            or name[0].isdigit():  # names become prim paths and ROS names: ASCII only
        v.fail(path, f"must be letters, digits and '_' and not start with a digit (ASCII "
               f"only), got {name!r}")


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
    sc = resolve_names(sc)
    return dataclasses.replace(sc, origins=dict(orig.by_key))


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
            return {f.name: plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)
                    if not f.metadata.get("internal")}
        if isinstance(obj, tuple | list):
            return [plain(x) for x in obj]
        if isinstance(obj, dict):
            return {k: plain(v) for k, v in obj.items()}
        return obj

    out = plain(sc)
    assert isinstance(out, dict)
    return out
