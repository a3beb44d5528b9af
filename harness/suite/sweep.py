"""Sweep declarations: ``--set`` paths with the values to run them at.

A scenario (or a suite entry) declares ::

    sweep:
      workers.0.speed: [0.6, 1.0, 1.4]            # values
      workers.0.start_delay: {from: 18, to: 24, step: 2}   # an inclusive range

Several parameters make a grid (every combination, in declaration order, the last parameter
varying fastest). Each point is one configuration: it is compared with its own baseline
(``<scenario>[path=value,...]``), never with the nominal scenario's.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from itertools import product
from typing import Any

from harness.errors import ScenarioError
from harness.validation import Validator, validate

__all__ = ["MAX_POINTS", "Point", "SweepParam", "SweepRange", "expand", "parse_sweep",
           "point_label", "varied_path"]

#: More points than this in one sweep is almost certainly a typo in a step.
MAX_POINTS = 1000

Scalar = bool | int | float | str


@dataclass(frozen=True)
class SweepParam:
    path: str
    values: tuple[Scalar, ...]


@dataclass(frozen=True)
class Point:
    """One sweep point: ``(path, value)`` pairs in declaration order."""

    params: tuple[tuple[str, Scalar], ...]

    @property
    def label(self) -> str:
        return point_label(self.params)

    def overrides(self) -> tuple[str, ...]:
        return tuple(f"{path}={_yaml_scalar(value)}" for path, value in self.params)


def _yaml_scalar(value: Scalar) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return "'" + value.replace("'", "''") + "'"
    return repr(value)


def _show(value: Scalar) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(value).lower() if isinstance(value, bool) else str(value)


def point_label(params: Sequence[tuple[str, Scalar]]) -> str:
    """``speed=1.4,seed=3`` (empty for the nominal point): each swept path by its shortest
    tail that names it alone among the point's paths and does not start with an index
    (``systems_under_test.safety_monitor.params.reaction_delay`` → ``reaction_delay``;
    ``workers.0.speed`` with ``workers.1.speed`` stay whole). The summary keeps full paths."""
    paths = [p for p, _ in params]
    return ",".join(f"{_short(p, paths)}={_show(v)}" for p, v in params)


def _short(path: str, paths: Sequence[str]) -> str:
    parts = path.split(".")
    for n in range(1, len(parts) + 1):
        tail = parts[-n:]
        if tail[0].isdigit():
            continue
        name = ".".join(tail)
        if sum(1 for q in paths if q == name or q.endswith("." + name)) == 1:
            return name
    return path


@dataclass(frozen=True)
class SweepRange:
    """``{from: A, to: B, step: C}``: the values A, A + C, ... up to B (inclusive)."""

    start: int | float = dataclasses.field(metadata={"key": "from"})
    to: int | float
    step: int | float


def _range(raw: Mapping[str, Any], file: str, field: str) -> tuple[Scalar, ...]:
    spec = validate(SweepRange, raw, file, field)
    lo, hi, step = spec.start, spec.to, spec.step
    if step <= 0:
        raise ScenarioError(file, f"{field}.step", f"must be > 0, got {step!r}")
    if hi < lo:
        raise ScenarioError(file, f"{field}.to", f"must be >= from ({lo!r}), got {hi!r}")
    try:
        span = (hi - lo) / step
    except OverflowError:  # integers too large for a float
        span = math.inf
    if not span < MAX_POINTS:  # also inf: from -1e308 to 1e308
        raise ScenarioError(file, f"{field}.step", f"gives too many values (at most "
                            f"{MAX_POINTS}): {lo!r} to {hi!r} in steps of {step!r}")
    n = math.floor(span + 1e-9) + 1
    if n > MAX_POINTS:
        raise ScenarioError(file, f"{field}.step", f"gives {n} values (at most {MAX_POINTS})")
    if all(isinstance(v, int) for v in (lo, hi, step)):
        return tuple(lo + i * step for i in range(n))
    # round away binary noise (0.1 + 2 * 0.2 = 0.5000000000000001) so labels read as written
    return tuple(round(lo + i * step, 12) for i in range(n))


def parse_sweep(raw: Any, file: str, field: str = "sweep") -> tuple[SweepParam, ...]:
    """Check a ``sweep:`` mapping; errors name ``file`` and ``field.<path>``."""
    if raw is None or raw == {}:
        return ()
    if not isinstance(raw, Mapping):
        raise ScenarioError(file, field, "expected a mapping of --set paths to values")
    params = []
    for path, spec in raw.items():
        where = f"{field}.{path}"
        if not isinstance(path, str) or not path or any(c.isspace() for c in path):
            raise ScenarioError(file, where, "expected a dotted --set path")
        if isinstance(spec, Mapping):
            values = _range(spec, file, where)
        elif isinstance(spec, list):
            if not spec:
                raise ScenarioError(file, where, "no values to sweep")
            values = Validator(file).value(tuple[Scalar, ...], spec, where, {})
            dup = next((v for i, v in enumerate(values) if v in values[:i]), None)
            if dup is not None:
                raise ScenarioError(file, where, f"value {dup!r} is listed twice")
        else:
            raise ScenarioError(file, where, "expected a list of values or {from, to, step}")
        params.append(SweepParam(path, values))
    total = math.prod(len(p.values) for p in params)
    if total > MAX_POINTS:
        raise ScenarioError(file, field, f"the grid has {total} points (at most {MAX_POINTS})")
    return tuple(params)


def expand(params: Sequence[SweepParam]) -> tuple[Point, ...]:
    """Every combination of the parameters' values (one nominal point when there are none)."""
    if not params:
        return (Point(()),)
    return tuple(Point(tuple(zip((p.path for p in params), combo, strict=True)))
                 for combo in product(*(p.values for p in params)))


def varied_path(path: str, varied: Iterable[str]) -> str | None:
    """The path of ``varied`` (a sweep's or a search's) that a fixed override of ``path``
    falls on (the same path, or a field inside it), None when none: each point's value
    would replace the override's."""
    return next((v for v in sorted(varied) if path == v or path.startswith(v + ".")), None)
