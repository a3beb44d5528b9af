"""Metric values of two runs side by side, judged by the baseline comparison engine with run
A as the baseline (:func:`harness.regression.compare`): same tolerances, same statuses, same
order (regressed first)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal, cast

from harness.diff.result import MetricDelta
from harness.errors import SrrError
from harness.metrics.types import MetricResult
from harness.regression import Baseline, BaselineMetric, compare
from harness.scenario.schema import ToleranceSpec

__all__ = ["metric_deltas", "summary_metrics"]

_GROUPS = ("control", "perception", "safety", "health", "spec")
Group = Literal["control", "perception", "safety", "health", "spec"]


def summary_metrics(summary: Mapping[str, Any], source: Path) -> list[MetricResult]:
    """The ``metrics`` of a ``summary.json`` as typed results; :class:`SrrError` naming the
    file and the entry when one is malformed."""
    raw = summary.get("metrics", [])
    if not isinstance(raw, list):
        raise SrrError(f"{source}: metrics: expected a list, got {type(raw).__name__}")
    out = []
    for i, m in enumerate(raw):
        where = f"{source}: metrics[{i}]"
        if not isinstance(m, dict) or not isinstance(m.get("name"), str):
            raise SrrError(f"{where}.name: missing (not an srr metric)")
        v = m.get("value")
        if isinstance(v, bool) or not (v is None or isinstance(v, (int, float))):
            raise SrrError(f"{where}.value: expected a number or null, got {v!r}")
        direction = m.get("direction", "none")
        if direction not in ("lower", "higher", "none"):
            raise SrrError(f"{where}.direction: expected lower, higher or none, got "
                           f"{direction!r}")
        group = m.get("group") if m.get("group") in _GROUPS else m["name"].split(".")[0]
        out.append(MetricResult(m["name"], None if v is None else float(v),
                                str(m.get("unit", "")), direction,
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
