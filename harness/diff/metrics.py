"""Metric values of two runs side by side, judged by the baseline comparison engine with run
A as the baseline (:func:`harness.regression.compare`): same tolerances, same statuses, same
order (regressed first)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal, cast

from harness.diff.result import MetricDelta
from harness.metrics.types import MetricResult
from harness.regression import Baseline, BaselineMetric, compare
from harness.scenario.schema import ToleranceSpec

__all__ = ["metric_deltas", "summary_metrics"]

_GROUPS = ("control", "perception", "safety", "health", "spec")
Group = Literal["control", "perception", "safety", "health", "spec"]


def summary_metrics(summary: Mapping[str, Any]) -> list[MetricResult]:
    """The ``metrics`` of a summary as typed results. The summary was checked where it was read
    (:func:`harness.summary.read_summary`, or :func:`harness.regression.load_baseline` for a
    baseline file): its entries have a name, a number or null, a unit and a direction."""
    out = []
    for m in summary.get("metrics", []):
        v = m.get("value")
        group = m.get("group") if m.get("group") in _GROUPS else m["name"].split(".")[0]
        out.append(MetricResult(m["name"], None if v is None else float(v),
                                str(m.get("unit", "")), m.get("direction", "none"),
                                cast(Group, group if group in _GROUPS else "health")))
    return out


def metric_deltas(a: list[MetricResult], b: list[MetricResult],
                  tolerances: Mapping[str, ToleranceSpec]) -> tuple[MetricDelta, ...]:
    """B's metrics compared with A's; ``delta = B − A``."""
    base = Baseline(scenario="", metrics={m.name: BaselineMetric(m.value, m.unit, m.direction)
                                          for m in a},
                    topics={}, digest="", seed=0, versions={}, blessed_by="", reason="",
                    blessed_at="", source_run="")
    return tuple(MetricDelta(e.name, e.unit, e.direction, e.baseline, e.value, e.delta,
                             e.tolerance, e.status)
                 for e in compare(b, base, tolerances).entries)
