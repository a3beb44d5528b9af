"""What a baseline must share with a run for their metrics to be comparable.

A baseline is only a yardstick for runs of the same *configuration*: the same simulated scene
(world, robots, cameras, workers, zones, routes, ground truth), the same duration, seed and
physics settings, and the same scoring definitions. What a regression test is meant to vary
is left out: the systems under test (a new version of a plug-in, changed parameters), the
scenario's name and description, which baseline it names, the tolerances and the health-gate
settings, how the bag is written (``recording``: chunking, fsync, the disk guard; a camera's
``record``, fixed or on a robot: raw or compressed images; ``output``: ROS 1 or ROS 2, bag or
MCAP, whose messages carry the same values), whether images render on a background thread
(``render.overlap``: the same bytes either way), live outputs (``ros2``, ``rtsp``), the
sweep a suite may expand the scenario into (``sweep``: each point is its own configuration)
and the ``specs`` (formulas judge the recording, they do not change it; each spec is its own
metric, compared by name: a spec added to a scenario is a ``new`` metric, not another
configuration).
:func:`comparable_config` is that part of a resolved scenario, as plain data (a run adds
``scene_files``, the digests of the model files its scene is built from);
:func:`config_differences` names what differs, field by field
(:func:`scenario_differences`: every field, for ``srr diff``). A baseline blessed before srr
gained a field has no value for it; :func:`with_defaults` gives it the field's default, so
adding a field with a default changes no verdict.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from harness.errors import SrrError
from harness.scenario import FORMAT_VERSION, scenario_from_mapping, scenario_to_mapping

__all__ = ["EXCLUDED", "LABELS", "comparable_config", "config_differences",
           "scenario_differences", "with_defaults"]

#: Top-level keys, and ``scoring`` sub-keys, that do not make two configurations different.
EXCLUDED = frozenset({"format_version", "name", "description", "baseline", "baselines",
                      "systems_under_test", "recording", "output", "sweep", "ros2",
                      "rtsp", "specs"})
EXCLUDED_SCORING = frozenset({"tolerances", "health"})
#: Keys of each ``cameras`` entry that do not make two configurations different.
EXCLUDED_CAMERA = frozenset({"record"})
#: ``render`` sub-keys that do not make two configurations different.
EXCLUDED_RENDER = frozenset({"overlap"})


def comparable_config(mapping: Mapping[str, Any]) -> dict[str, Any]:
    """The comparable part of a resolved scenario mapping
    (:func:`~harness.scenario.scenario_to_mapping`)."""
    out = {k: v for k, v in mapping.items() if k not in EXCLUDED}
    cameras = out.get("cameras")
    if isinstance(cameras, list):
        out["cameras"] = [{k: v for k, v in c.items() if k not in EXCLUDED_CAMERA}
                          if isinstance(c, Mapping) else c for c in cameras]
    robots = out.get("robots")
    if isinstance(robots, list):
        out["robots"] = [_without_camera_record(r) for r in robots]
    scoring = out.get("scoring")
    if isinstance(scoring, Mapping):
        out["scoring"] = {k: v for k, v in scoring.items() if k not in EXCLUDED_SCORING}
    render = out.get("render")
    if isinstance(render, Mapping):
        out["render"] = {k: v for k, v in render.items() if k not in EXCLUDED_RENDER}
    return out


def _without_camera_record(robot: Any) -> Any:
    """A robot entry without its camera's ``record`` (as it is when it has no camera)."""
    if not isinstance(robot, Mapping):
        return robot
    sensors = robot.get("sensors")
    if not isinstance(sensors, Mapping) or not isinstance(sensors.get("camera"), Mapping):
        return robot
    camera = {k: v for k, v in sensors["camera"].items() if k not in EXCLUDED_CAMERA}
    return {**robot, "sensors": {**sensors, "camera": camera}}


def with_defaults(config: Mapping[str, Any]) -> dict[str, Any]:
    """A stored comparable config with every field it lacks filled with its default (read
    through the scenario schema); as it is when it no longer validates."""
    files = config.get("scene_files")
    try:
        sc = scenario_from_mapping({**{k: v for k, v in config.items() if k != "scene_files"},
                                    "format_version": FORMAT_VERSION, "name": "baseline"},
                                   "<baseline config>")
    except SrrError:
        return dict(config)
    out = comparable_config(scenario_to_mapping(sc))
    if files is not None:
        out["scene_files"] = files
    return out


def _flat(value: Any, path: str, out: dict[str, Any]) -> None:
    if isinstance(value, Mapping) and value:
        for k in value:
            _flat(value[k], f"{path}.{k}" if path else str(k), out)
    elif isinstance(value, list | tuple) and value and any(
            isinstance(v, Mapping | list | tuple) for v in value):
        for i, v in enumerate(value):
            _flat(v, f"{path}[{i}]", out)
    else:
        out[path] = list(value) if isinstance(value, tuple) else value


def _show(value: Any) -> str:
    return "(absent)" if value is _ABSENT else repr(value) if isinstance(value, str) \
        else f"{value}"


_ABSENT = object()


def _emptied(key: str, one: Mapping[str, Any], other: Mapping[str, Any]) -> bool:
    """``key`` is an empty list or mapping on ``one`` side and holds items on the ``other``
    (flattened under it): the items' own lines say what was added or removed."""
    return (one.get(key, _ABSENT) in ([], {}) and key not in other
            and any(k.startswith((f"{key}[", f"{key}.")) for k in other))


def config_differences(baseline: Mapping[str, Any], run: Mapping[str, Any],
                       limit: int = 8) -> list[str]:
    """``field: baseline value → run value`` for every leaf that differs (sorted; at most
    ``limit`` lines, then a count of the rest)."""
    return _differences(comparable_config(baseline), comparable_config(run), limit)


#: Top-level keys that name or describe a scenario: no difference between two runs.
LABELS = frozenset({"format_version", "name", "description"})


def scenario_differences(a: Mapping[str, Any], b: Mapping[str, Any],
                         limit: int = 10) -> list[str]:
    """``field: A's value → B's value`` for every leaf of two resolved scenario mappings that
    differs, the systems under test, recording and scoring settings included (what
    ``srr diff`` shows as what changed between two runs; only :data:`LABELS` are left out).
    Sorted; at most ``limit`` lines, then a count of the rest."""
    return _differences({k: v for k, v in a.items() if k not in LABELS},
                        {k: v for k, v in b.items() if k not in LABELS}, limit)


def _differences(one: Mapping[str, Any], other: Mapping[str, Any], limit: int) -> list[str]:
    a: dict[str, Any] = {}
    b: dict[str, Any] = {}
    _flat(one, "", a)
    _flat(other, "", b)
    diffs = [f"{k}: {_show(a.get(k, _ABSENT))} → {_show(b.get(k, _ABSENT))}"
             for k in sorted(set(a) | set(b)) if a.get(k, _ABSENT) != b.get(k, _ABSENT)
             and not _emptied(k, a, b) and not _emptied(k, b, a)]
    if len(diffs) > limit:
        diffs = [*diffs[:limit], f"… and {len(diffs) - limit} more"]
    return diffs
