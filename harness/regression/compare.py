"""Compare a run's metrics with a baseline: one engine, one strategy per metric direction.

Each metric gets a status:

* ``ok``        within tolerance of the baseline;
* ``regressed`` moved in its worse direction by more than the tolerance, or became undefined
  (e.g. time to goal when the goal is no longer reached);
* ``improved``  moved in its better direction by more than the tolerance;
* ``changed``   a metric without a better direction (``direction: none``) moved;
* ``new``       not in the baseline;
* ``missing``   in the baseline but not produced by this run (counts as a regression: a
  metric that silently disappears must not pass);
* ``not_compared`` the baseline was recorded with another configuration (verdict MISMATCH):
  both values are shown, neither judged (:meth:`Comparison.not_compared`).

The tolerance for a metric is the scenario's entry for its exact name, else the most specific
matching glob (``perception.*``), else the default for its unit.
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Literal

from harness.metrics.types import MetricResult
from harness.regression.store import Baseline, BaselineMetric
from harness.scenario.schema import ToleranceSpec

__all__ = ["DEFAULT_TOLERANCES", "Comparison", "MetricComparison", "compare", "tolerance_for"]

Status = Literal["ok", "regressed", "improved", "changed", "new", "missing", "not_compared"]

# Per unit: (absolute, relative). The larger of the two applies.
DEFAULT_TOLERANCES: dict[str, ToleranceSpec] = {
    "m": ToleranceSpec(abs=0.05, rel=0.05),
    "m/s": ToleranceSpec(abs=0.02, rel=0.05),
    "rad": ToleranceSpec(abs=0.02, rel=0.05),
    "rad/s": ToleranceSpec(abs=0.02, rel=0.05),
    "deg": ToleranceSpec(abs=1.0, rel=0.05),
    "s": ToleranceSpec(abs=0.1, rel=0.05),
    "%": ToleranceSpec(abs=1.0, rel=0.0),
    "ratio": ToleranceSpec(abs=0.01, rel=0.0),
    "count": ToleranceSpec(abs=0.0, rel=0.0),
    "bool": ToleranceSpec(abs=0.0, rel=0.0),
}
FALLBACK = ToleranceSpec(abs=1e-9, rel=0.05)


@dataclass(frozen=True)
class MetricComparison:
    name: str
    unit: str
    direction: str
    value: float | None
    baseline: float | None
    delta: float | None
    tolerance: float
    status: Status

    def describe(self) -> str:
        """One line a reviewer reads: what moved, from what, against which tolerance."""
        def fmt(v: float | None) -> str:
            return "undefined" if v is None else f"{v:.4g}"

        if self.status == "missing":
            return f"{self.name}: in the baseline ({fmt(self.baseline)} {self.unit}) but not " \
                   "produced by this run"
        if self.status == "new":
            return f"{self.name}: {fmt(self.value)} {self.unit} (not in the baseline)"
        if self.status == "not_compared":
            return (f"{self.name}: {fmt(self.value)} {self.unit}, baseline "
                    f"{fmt(self.baseline)} {self.unit} of another configuration — not compared")
        better = {"lower": "lower is better", "higher": "higher is better"}.get(
            self.direction, "no better direction")
        return (f"{self.name}: {fmt(self.value)} {self.unit} vs baseline {fmt(self.baseline)} "
                f"{self.unit} (delta {fmt(self.delta)}, tolerance ±{self.tolerance:.4g}, "
                f"{better}) — {self.status}")


@dataclass(frozen=True)
class Comparison:
    entries: tuple[MetricComparison, ...]

    @property
    def regressions(self) -> tuple[MetricComparison, ...]:
        return tuple(e for e in self.entries if e.status in ("regressed", "missing"))

    @property
    def regressed(self) -> bool:
        return bool(self.regressions)

    def not_compared(self) -> Comparison:
        """The same rows, judged by nothing: the baseline is of another configuration, so
        no metric regressed, improved or held against it (no delta either)."""
        return Comparison(tuple(replace(e, delta=None, status="not_compared")
                                for e in sorted(self.entries, key=lambda e: e.name)))

    def counts(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for e in self.entries:
            out[e.status] = out.get(e.status, 0) + 1
        return out


def tolerance_for(name: str, unit: str, tolerances: Mapping[str, ToleranceSpec]) -> ToleranceSpec:
    if name in tolerances:
        return tolerances[name]
    matches = [p for p in tolerances if fnmatch.fnmatchcase(name, p)]
    if matches:
        # The most specific pattern: the longest one without wildcards counted.
        best = max(matches, key=lambda p: len(p.replace("*", "").replace("?", "")))
        return tolerances[best]
    return DEFAULT_TOLERANCES.get(unit, FALLBACK)


def _allowed(tol: ToleranceSpec, baseline: float) -> float:
    return max(tol.abs or 0.0, (tol.rel or 0.0) * abs(baseline))


def _status(direction: str, value: float | None, base: float | None,
            allowed: float) -> tuple[Status, float | None]:
    if value is None and base is None:
        return "ok", None
    if value is None:
        return ("regressed" if direction != "none" else "changed"), None
    if base is None:
        return ("improved" if direction != "none" else "changed"), None
    delta = value - base
    if math.isnan(delta):
        return "regressed", delta
    if abs(delta) <= allowed + 1e-12:
        return "ok", delta
    if direction == "none":
        return "changed", delta
    worse = delta > 0 if direction == "lower" else delta < 0
    return ("regressed" if worse else "improved"), delta


def compare(metrics: Sequence[MetricResult], baseline: Baseline,
            tolerances: Mapping[str, ToleranceSpec]) -> Comparison:
    """Compare ``metrics`` with ``baseline``; entries are sorted regressions first."""
    entries: list[MetricComparison] = []
    seen: set[str] = set()
    for m in metrics:
        seen.add(m.name)
        base: BaselineMetric | None = baseline.metrics.get(m.name)
        tol = tolerance_for(m.name, m.unit, tolerances)
        if base is None:
            entries.append(MetricComparison(m.name, m.unit, m.direction, m.value, None, None,
                                            _allowed(tol, m.value or 0.0), "new"))
            continue
        allowed = _allowed(tol, base.value if base.value is not None else 0.0)
        status, delta = _status(m.direction, m.value, base.value, allowed)
        entries.append(MetricComparison(m.name, m.unit, m.direction, m.value, base.value,
                                        delta, allowed, status))
    for name, base in baseline.metrics.items():
        if name not in seen:
            tol = tolerance_for(name, base.unit, tolerances)
            entries.append(MetricComparison(name, base.unit, base.direction, None, base.value,
                                            None, _allowed(tol, base.value or 0.0), "missing"))
    order = {"regressed": 0, "missing": 1, "improved": 2, "changed": 3, "new": 4, "ok": 5}
    entries.sort(key=lambda e: (order[e.status], e.name))
    return Comparison(tuple(entries))
