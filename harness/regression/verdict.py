"""The overall verdict of a run and its exit code.

Order of precedence: INVALID (a health gate tripped: the scores cannot be trusted, exit 3),
REGRESSED (a metric moved past its tolerance, exit 1), FAIL (an absolute criterion failed or
there is no baseline to compare with, exit 1), PASS (exit 0).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from harness.metrics.types import HealthResult, MetricResult
from harness.regression.compare import Comparison

__all__ = ["Verdict", "absolute_failures", "decide"]

VerdictName = Literal["PASS", "FAIL", "REGRESSED", "INVALID"]
EXIT_CODES: dict[str, int] = {"PASS": 0, "FAIL": 1, "REGRESSED": 1, "INVALID": 3}


@dataclass(frozen=True)
class Verdict:
    name: VerdictName
    exit_code: int
    reasons: tuple[str, ...]


def absolute_failures(metrics: Sequence[MetricResult]) -> list[str]:
    """Criteria that fail a run whatever the baseline says: the safety match-rate band
    (FAIL below 80 %) and a route goal that was not reached."""
    out = []
    for m in metrics:
        if m.name == "safety.match_rate" and m.value is not None and m.value < 80.0:
            out.append(f"safety.match_rate {m.value:.1f} % is below 80 % (FAIL band)")
        if m.name == "control.goal_reached" and m.value is not None and m.value < 0.5:
            out.append("control.goal_reached: the robot did not reach the end of its route")
    return out


def decide(health: Sequence[HealthResult], metrics: Sequence[MetricResult],
           comparison: Comparison | None, baseline_note: str | None) -> Verdict:
    """``comparison`` is None when there is no baseline; ``baseline_note`` then says where
    one was looked for and how to bless one."""
    tripped = [f"health {h.name}: {h.detail}" for h in health if not h.ok]
    if tripped:
        return Verdict("INVALID", 3, tuple(tripped))
    if comparison is not None and comparison.regressed:
        return Verdict("REGRESSED", 1, tuple(e.describe() for e in comparison.regressions))
    failures = absolute_failures(metrics)
    if comparison is None and metrics:
        failures.append(baseline_note or "no baseline to compare with")
    if failures:
        return Verdict("FAIL", 1, tuple(failures))
    return Verdict("PASS", 0, ())
