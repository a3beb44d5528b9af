"""``--objective METRIC`` with ``--violated-below T`` or ``--violated-above T``: which metric
of a run's ``summary.json`` the search drives, and when a run *violates* it.

Any metric name a run's summary carries works (``safety.under_mute``,
``control.min_clearance``, ``spec.<name>.robustness``). A ``spec.*.robustness`` metric
(an STL specification's robustness: negative when the specification is violated) needs no
threshold: it is violated below 0. The optimizer minimises the metric for ``below``,
maximises it for ``above``; a run that crashed, timed out or is INVALID has no value and is
never a violation.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from harness.errors import SrrError

__all__ = ["Objective", "check_scored", "missing_metric", "parse_objective"]

#: Metric groups whose scoring block a scenario must have (checked before anything runs).
_GROUPS = ("control", "perception", "safety")


@dataclass(frozen=True)
class Objective:
    metric: str
    below: bool  # True: a value below the threshold is a violation
    threshold: float

    @property
    def direction(self) -> str:
        """optuna's direction: towards a violation."""
        return "minimize" if self.below else "maximize"

    def violated(self, value: float) -> bool:
        return value < self.threshold if self.below else value > self.threshold

    def margin(self, value: float) -> float:
        """How far ``value`` is from a violation (negative: violated by that much)."""
        return value - self.threshold if self.below else self.threshold - value

    def describe(self) -> str:
        return f"{self.metric} {'<' if self.below else '>'} {self.threshold:g}"

    def to_json(self) -> dict[str, Any]:
        return {"metric": self.metric, "violated": "below" if self.below else "above",
                "threshold": self.threshold, "direction": self.direction}


def parse_objective(metric: str, *, below: float | None, above: float | None) -> Objective:
    """Check ``--objective`` and its threshold; a bad one raises :class:`SrrError`."""
    metric = metric.strip()
    if not metric or any(c.isspace() for c in metric) or "." not in metric:
        raise SrrError(f"--objective {metric!r}: expected a metric name such as "
                       "safety.under_mute or spec.NAME.robustness")
    if below is not None and above is not None:
        raise SrrError("--violated-below, --violated-above: give one, not both")
    for flag, v in (("--violated-below", below), ("--violated-above", above)):
        if v is not None and not math.isfinite(v):
            raise SrrError(f"{flag}: expected a finite number, got {v!r}")
    if below is None and above is None:
        if metric.startswith("spec.") and metric.endswith(".robustness"):
            return Objective(metric, True, 0.0)
        raise SrrError(f"--objective {metric}: say when a run violates it, with "
                       "--violated-below VALUE or --violated-above VALUE")
    limit = below if below is not None else above
    assert limit is not None
    return Objective(metric, above is None, float(limit))


def check_scored(objective: Objective, scoring: Any, scenario_file: str) -> None:
    """A ``control``/``perception``/``safety`` metric needs that scoring block."""
    group = objective.metric.split(".", 1)[0]
    if group not in _GROUPS:
        return
    block = scoring.control_blocks if group == "control" else getattr(scoring, group)
    if not block:
        raise SrrError(f"--objective {objective.metric}: {scenario_file} scores no {group} "
                       f"(no scoring.{group} block), so no run would have this metric")


def missing_metric(objective: Objective, metrics: Mapping[str, Any]) -> str | None:
    """The one line to stop on when a trusted run's metrics lack the objective, else None."""
    if objective.metric in metrics:
        return None
    near: Sequence[str] = difflib.get_close_matches(objective.metric, list(metrics), n=3)
    hint = (f"; did you mean {', '.join(near)}?" if near else
            f"; it has {len(metrics)} metrics, e.g. {', '.join(sorted(metrics)[:3])}")
    return (f"--objective {objective.metric}: the runs' summary.json has no such metric"
            + hint)
