"""Typed metric results: every metric says its unit and which direction is better."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

__all__ = ["NEAR_AT", "PASS_AT", "Direction", "HealthResult", "MetricResult"]

#: match-rate bands (%): PASS at or above PASS_AT, NEAR at or above NEAR_AT, FAIL below
#: (here, not in harness.metrics.safety, so that the verdict needs no pandas)
PASS_AT = 95.0
NEAR_AT = 80.0

Direction = Literal["lower", "higher", "none"]


@dataclass(frozen=True)
class MetricResult:
    """One scored value.

    ``name`` is dotted and stable (``safety.match_rate``, ``perception.mota``), it is the key
    in baselines. ``value`` is None when the metric is undefined for the run (e.g. no mute
    edge to measure a lag on); ``detail`` says why. ``windows`` lists time intervals
    (seconds of simulation time) that explain the value, for the report. ``verdict`` is set
    by metrics that carry their own pass bands (``safety.match_rate``: PASS / NEAR / FAIL).
    """

    name: str
    value: float | None
    unit: str
    direction: Direction
    group: Literal["control", "perception", "safety", "health", "spec"]
    detail: str = ""
    windows: tuple[tuple[float, float], ...] = field(default=())
    verdict: str | None = None


@dataclass(frozen=True)
class HealthResult:
    """A health gate: a tripped one makes the run INVALID (exit 3), not FAIL."""

    name: str
    ok: bool
    detail: str
