"""Load a scenario file into a frozen :class:`~harness.scenario.schema.Scenario`: read it and
merge its includes (:mod:`harness.scenario.includes`), apply ``--set`` overrides
(:mod:`harness.scenario.overrides`), read the result into the schema's dataclasses
(:mod:`harness.validation`, driven by their type hints, so the schema module is the single place
that says what a scenario may contain), check the cross-field rules
(:mod:`harness.scenario.checks`) and fill in derived names (:mod:`harness.scenario.resolve`).
Every error names the file the value came from and the field path inside it
(``robots[0].control.wheelbase``).
"""

from __future__ import annotations

import dataclasses
import json
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from harness.errors import ScenarioError
from harness.scenario.checks import (
    RATE_TOLERANCE,
    check_semantics,
    degree_warnings,
    rate_warnings,
    robot_warnings,
    sensor_rates,
    tripwire_warnings,
    worker_warnings,
)
from harness.scenario.includes import Origins, expand_includes, read_yaml
from harness.scenario.origins import SET_FLAG
from harness.scenario.overrides import apply_overrides, parse_override, split_key
from harness.scenario.resolve import graph_name, resolve_names
from harness.scenario.schema import (
    FORMAT_VERSION,
    DiffDriveControl,
    ForkliftControl,
    RobotSpec,
    Scenario,
    ToleranceSpec,
)
from harness.validation import Validator, validate

__all__ = [
    "RATE_TOLERANCE",
    "apply_overrides",
    "degree_warnings",
    "graph_name",
    "load_scenario",
    "parse_override",
    "rate_warnings",
    "resolve_names",
    "robot_warnings",
    "scenario_from_mapping",
    "scenario_to_mapping",
    "sensor_rates",
    "tripwire_warnings",
    "validate_dataclass",
    "worker_warnings",
]

T = typing.TypeVar("T")

_CONTROL_BY_MODEL: dict[str, type] = {
    "forklift": ForkliftControl,
    "turtlebot3_waffle_pi": DiffDriveControl,
}


def _control_type(model: Any) -> type:
    """The ``control:`` block type a robot's ``model`` value calls for: by built-in name, or
    by a model file's ``drive`` (``swivel_drive``: the forklift's block)."""
    if isinstance(model, dict):
        return ForkliftControl if model.get("drive") == "swivel_drive" else DiffDriveControl
    return _CONTROL_BY_MODEL.get(model, ForkliftControl) if isinstance(model, str) \
        else ForkliftControl


_DRIVE_OF_CONTROL: dict[type, str] = {ForkliftControl: "swivel_drive",
                                       DiffDriveControl: "diff_drive"}


def _check_control_fields(data: Mapping[str, Any], v: Validator) -> None:
    """A robot's ``control:`` field that belongs with the other drive (``joint_names`` on a
    swivel-drive robot, ``wheelbase`` on a diff-drive one) is refused naming the robot's
    drive, not as an unknown field."""
    robots = data.get("robots")
    for i, robot in enumerate(robots if isinstance(robots, list) else ()):
        control = robot.get("control") if isinstance(robot, dict) else None
        if not isinstance(control, dict):
            continue
        model = robot.get("model")
        cls = _control_type(model)
        ours = [f.name for f in dataclasses.fields(cls)]
        other = next(c for c in _DRIVE_OF_CONTROL if c is not cls)
        theirs = {f.name for f in dataclasses.fields(other)} - set(ours)
        for key in control:
            if key in theirs:
                drive = _DRIVE_OF_CONTROL[cls]
                if isinstance(model, dict):
                    said = (f"robots[{i}].model.drive is {drive!r}"
                            + ("" if "drive" in model else " (the default)"))
                else:
                    said = f"robots[{i}].model is {model!r}, a {drive} robot"
                v.fail(f"robots[{i}].control.{key}",
                       f"belongs with drive {_DRIVE_OF_CONTROL[other]!r}, and {said}; a "
                       f"{drive} control block takes {', '.join(ours)}")


def _refine(cls: type, name: str, raw: Mapping[Any, Any], hinted: Any) -> Any:
    """A robot's ``control:`` is read as the block its ``model`` calls for."""
    if cls is RobotSpec and name == "control":
        return _control_type(raw.get("model")) | None
    return hinted


def validate_dataclass(cls: type[T], raw: Any, file: str | Callable[[str], str],
                       field: str) -> T:
    """Validate ``raw`` into the frozen dataclass ``cls`` with the scenario rules (used for
    plug-in parameters); errors name ``file`` (or the file it gives for a field path) and
    ``field``."""
    return validate(cls, raw, file, field, refine=_refine)


def scenario_from_mapping(data: Mapping[str, Any], file: str = "<scenario>",
                          origins: Mapping[str, str] | None = None) -> Scenario:
    """Validate an already-parsed mapping (includes expanded) into a :class:`Scenario`."""
    orig = Origins(file)
    if origins:
        orig.by_key.update(origins)
    v = Validator(orig.file_for, refine=_refine)
    if "format_version" not in data:
        v.fail("format_version", f"required field is missing (use {FORMAT_VERSION})")
    _check_control_fields(data, v)
    sc = v.dataclass(Scenario, dict(data), "")
    check_semantics(sc, v)
    sc = resolve_names(sc)
    return dataclasses.replace(sc, origins=dict(orig.by_key))


def load_scenario(path: str | Path,
                  overrides: Sequence[tuple[str, Any]] = ()) -> Scenario:
    """Read ``path`` (with its includes), apply ``--set`` overrides and validate."""
    p = Path(path)
    shown = str(path)
    origins = Origins(shown)
    data = read_yaml(p, shown)
    data = expand_includes(p, data, origins)
    if overrides:
        for key, _ in overrides:
            origins.by_key.setdefault(split_key(key)[0], shown)
        # a value a --set gave is the flag's to answer for, wherever it is found wrong
        origins.by_key.update(dict.fromkeys(apply_overrides(data, overrides), SET_FLAG))
    try:
        sc = scenario_from_mapping(data, shown, origins.by_key)
    except ScenarioError as err:
        hint = _quote_hint(err, overrides)
        if hint is None:
            raise
        raise ScenarioError(err.file, err.field, f"{err.message}; {hint}") from None
    return dataclasses.replace(sc, overrides=tuple(overrides)) if overrides else sc


def _quote_hint(err: ScenarioError, overrides: Sequence[tuple[str, Any]]) -> str | None:
    """For an error in ``scoring.tolerances`` that a ``--set`` split a metric name at its
    dots for (``scoring.tolerances.perception.position_error.p95.abs``): the spelling that keeps the
    name one key."""
    if err.file != SET_FLAG or not err.field.startswith("scoring.tolerances."):
        return None
    leaves = {f.name for f in dataclasses.fields(ToleranceSpec)}
    for key, value in overrides:
        parts = split_key(key)
        if parts[:2] != ["scoring", "tolerances"]:
            continue
        name, leaf = (parts[2:-1], f".{parts[-1]}") if parts[-1] in leaves \
            else (parts[2:], "")
        if len(name) > 1:
            spelt = f'scoring.tolerances."{".".join(name)}"{leaf}={json.dumps(value)}'
            return f"a metric name with dots is one key: quote it, --set '{spelt}'"
    return None


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
