"""``--space PATH=RANGE``: the dimensions a search samples, on the paths ``--set`` and sweeps
use (``workers.0.speed``, ``systems_under_test.safety_monitor.params.reaction_delay``).

RANGE is one of::

    LO..HI          continuous (floats), e.g. workers.0.speed=0.5..2.5
    LO..HI:log      continuous on a log scale (LO > 0)
    LO..HI:STEP     a step: integers when LO, HI and STEP are whole numbers (1..10:1),
                    else floats on that grid (0..2:0.5)
    [A, B, C]       categorical (YAML values: numbers, strings, true/false)

A trial's parameters become ``--set`` overrides through the sweep's own
:meth:`harness.suite.sweep.Point.overrides`, so a search point and a sweep point of the same
values run the same scenario.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import yaml

from harness import yamlio
from harness.errors import SrrError
from harness.suite.sweep import Scalar

__all__ = ["Dimension", "parse_dimension", "parse_space"]


@dataclass(frozen=True)
class Dimension:
    """One searched parameter. ``kind``: ``float``, ``int`` or ``categorical``."""

    path: str
    kind: str
    low: float = 0.0
    high: float = 0.0
    step: float | None = None
    log: bool = False
    choices: tuple[Scalar, ...] = ()

    def describe(self) -> str:
        if self.kind == "categorical":
            return "[" + ", ".join(str(c) for c in self.choices) + "]"
        tail = ":log" if self.log else f":{self.step:g}" if self.step is not None else ""
        return f"{self.low:g}..{self.high:g}{tail}"

    def to_json(self) -> dict[str, object]:
        return {"path": self.path, "kind": self.kind, "range": self.describe()}


def _bad(text: str, why: str) -> SrrError:
    return SrrError(f"--space {text}: {why}")


def _number(raw: str, text: str) -> float:
    try:
        value = float(raw)
    except ValueError:
        raise _bad(text, f"{raw.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise _bad(text, f"{raw.strip()!r} is not a finite number")
    return value


def _whole(raw: str) -> bool:
    return raw.strip().lstrip("+-").isdigit()


def parse_dimension(text: str) -> Dimension:
    """One ``PATH=RANGE``; a bad one raises :class:`SrrError` naming ``--space`` and it."""
    path, sep, spec = text.partition("=")
    path, spec = path.strip(), spec.strip()
    if not sep or not path or any(c.isspace() for c in path) or path.startswith(".") \
            or path.endswith(".") or ".." in path:
        raise _bad(text, "expected PATH=RANGE with a dotted --set path, e.g. "
                   "workers.0.speed=0.5..2.5")
    if spec.startswith("["):
        try:
            values = yamlio.load(spec)
        except yaml.YAMLError as err:
            raise _bad(text, f"the list is not valid YAML ({yamlio.describe(err)})") from None
        if not isinstance(values, list) or not values:
            raise _bad(text, "expected a non-empty list of values, e.g. [0.5, 1.0]")
        if not all(isinstance(v, bool | int | float | str) for v in values):
            raise _bad(text, "the choices must be numbers, strings or true/false")
        if len(set(map(repr, values))) != len(values):
            raise _bad(text, "a choice is listed twice")
        return Dimension(path, "categorical", choices=tuple(values))
    lo_raw, dots, rest = spec.partition("..")
    if not dots:
        raise _bad(text, "expected LO..HI, LO..HI:STEP, LO..HI:log or [A, B, ...]")
    hi_raw, colon, tail = rest.partition(":")
    lo, hi = _number(lo_raw, text), _number(hi_raw, text)
    if not hi > lo:
        raise _bad(text, f"HI ({hi:g}) must be greater than LO ({lo:g})")
    if not colon:
        return Dimension(path, "float", lo, hi)
    if tail.strip() == "log":
        if lo <= 0:
            raise _bad(text, "a log range needs LO > 0")
        return Dimension(path, "float", lo, hi, log=True)
    step = _number(tail, text)
    if step <= 0 or step > hi - lo:
        raise _bad(text, f"STEP must be > 0 and at most HI - LO, got {step:g}")
    steps = (hi - lo) / step
    if abs(steps - round(steps)) > 1e-9 * max(1.0, steps):
        last = lo + math.floor(steps + 1e-9) * step
        raise _bad(text, f"HI - LO ({hi - lo:g}) is not a whole number of steps of {step:g}: "
                         f"the grid would stop at {last:g} and never try {hi:g}; make HI "
                         f"{last:g} or {last + step:g}, or take a step that divides {hi - lo:g}")
    kind = "int" if all(_whole(r) for r in (lo_raw, hi_raw, tail)) else "float"
    return Dimension(path, kind, lo, hi, step)


def parse_space(texts: Sequence[str]) -> tuple[Dimension, ...]:
    """Every ``--space``; at least one, each path once."""
    if not texts:
        raise SrrError("--space: give at least one PATH=RANGE to search")
    dims = tuple(parse_dimension(t) for t in texts)
    seen: set[str] = set()
    for d in dims:
        if d.path in seen:
            raise SrrError(f"--space {d.path}: the path is given twice")
        seen.add(d.path)
    return dims
