"""The overall verdict of a run and its exit code.

Order of precedence: INVALID (a health gate tripped: the scores cannot be trusted, exit 3),
MISMATCH (the baseline was recorded with another configuration — duration, seed, physics,
scene or scoring — so its metrics are no yardstick; exit 1), REGRESSED (a metric moved past
its tolerance, exit 1), FAIL (an absolute criterion failed,
there is no baseline to compare with, or the baseline holds none of the run's metrics, exit 1),
UNSCORED (nothing was scored: the run was recorded but not judged, exit 1), PASS (exit 0).

PASS needs something compared that held: at least one metric compared with its baseline
value and none regressed. RECORDED (exit 0) is the verdict of a scenario that says it only
records (``scoring: {record_only: true}``) and whose health gates all held: nothing was
compared, on purpose, and the verdict says so instead of PASS.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from harness.metrics.types import NEAR_AT, HealthResult, MetricResult
from harness.regression.compare import Comparison

__all__ = ["EXIT_CODES", "GOAL_REACHED", "GOAL_REACHED_AT", "OK_VERDICTS", "Verdict",
           "absolute_failures", "decide"]

VerdictName = Literal["PASS", "RECORDED", "FAIL", "REGRESSED", "MISMATCH", "UNSCORED",
                      "INVALID"]
#: the exit status of each verdict (``srr run``'s, and a suite run's)
EXIT_CODES: dict[str, int] = {"PASS": 0, "RECORDED": 0, "FAIL": 1, "REGRESSED": 1,
                              "MISMATCH": 1, "UNSCORED": 1, "INVALID": 3}
#: the verdicts that exit 0: compared and held, or recorded on purpose with healthy gates
OK_VERDICTS = ("PASS", "RECORDED")
#: ``control.goal_reached`` or ``control.<robot>.goal_reached``.
GOAL_REACHED = re.compile(r"^control\.(?:[^.]+\.)?goal_reached$")
#: a goal-reached value below this fails the run (the metric is 1 reached, 0 not)
GOAL_REACHED_AT = 0.5


@dataclass(frozen=True)
class Verdict:
    name: VerdictName
    reasons: tuple[str, ...]

    @property
    def exit_code(self) -> int:
        return EXIT_CODES[self.name]


def absolute_failures(metrics: Sequence[MetricResult]) -> list[str]:
    """Criteria that fail a run whatever the baseline says: the safety match-rate band
    (FAIL below 80 %), a route goal that was not reached and a required spec that was
    violated or could not be evaluated (its metric's verdict FAIL)."""
    out = []
    for m in metrics:
        if m.group == "spec" and m.verdict == "FAIL":
            out.append(f"{m.name}: required spec " + (
                f"violated (robustness {m.value:.4g})" if m.value is not None else
                "not evaluated") + f" — {m.detail}")
        if m.name == "safety.match_rate" and m.value is not None and m.value < NEAR_AT:
            out.append(f"safety.match_rate {m.value:.1f} % is below {NEAR_AT:g} % (FAIL band)")
        if GOAL_REACHED.match(m.name) and m.value is not None and m.value < GOAL_REACHED_AT:
            out.append(f"{m.name}: the robot did not reach the end of its route")
    return out


def decide(health: Sequence[HealthResult], metrics: Sequence[MetricResult],
           comparison: Comparison | None, baseline_note: str | None,
           mismatch: Sequence[str] = (), *, record_only: bool = False,
           first_baseline: bool = False) -> Verdict:
    """``comparison`` is None when there is no baseline; ``baseline_note`` then says where
    one was looked for and how to bless one. ``mismatch``: the configuration fields in which
    the run differs from the baseline (:func:`~harness.regression.config.config_differences`);
    any makes the verdict MISMATCH, whatever the metrics say. ``record_only``: the scenario
    records on purpose (``scoring.record_only``): RECORDED when every health gate held.
    ``first_baseline``: the run is about to become its scenario's first baseline
    (``--update-baseline`` with none yet): RECORDED, ``baseline_note`` saying so, unless an
    absolute criterion failed."""
    tripped = [f"health {h.name}: {h.detail}" for h in health if not h.ok]
    if tripped:
        return Verdict("INVALID", tuple(tripped))
    if record_only:
        return Verdict("RECORDED", (
            f"recorded on purpose (scoring.record_only): nothing was scored or compared; "
            f"{len(health)} health gates held",))
    if mismatch:
        return Verdict("MISMATCH", (
            "not compared: the baseline was recorded with another configuration ("
            + "; ".join(mismatch) + "); bless a baseline for this configuration "
            "if the change is intended (srr baseline bless RUN_DIR; in a suite, "
            "--update-baselines)",
            *absolute_failures(metrics)))
    if comparison is not None and comparison.regressed:
        return Verdict("REGRESSED", tuple(e.describe() for e in comparison.regressions))
    failures = absolute_failures(metrics)
    if comparison is None and metrics:
        if first_baseline and not failures:
            return Verdict("RECORDED", (baseline_note or "no baseline to compare with",))
        failures.append(baseline_note or "no baseline to compare with")
    compared = [] if comparison is None else [
        e for e in comparison.entries if e.status in ("ok", "improved", "changed")]
    if comparison is not None and metrics and not compared:
        failures.append(f"the baseline holds none of this run's {len(metrics)} metrics, so "
                        "nothing was compared; bless a baseline from this configuration")
    if failures:
        return Verdict("FAIL", tuple(failures))
    if not metrics:
        return Verdict("UNSCORED", (
            "nothing was scored: the scenario has no scoring block (control, perception or "
            "safety), so the run was recorded but not compared with anything; a scenario "
            "that only records says so with scoring: {record_only: true}",))
    return Verdict("PASS", ())
