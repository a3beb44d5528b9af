"""Metrics: pure functions from recorded frames to typed results with units.

``control``, ``perception``, ``safety`` and ``specs`` (STL formulas) give
:class:`MetricResult` lists; ``health`` gives :class:`HealthResult` gates. Read a run with
:func:`harness.frames.load_frames` first.
Names are imported from their submodules on first use (:mod:`harness._lazy`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.metrics.control import control_metrics
    from harness.metrics.health import OutputSpec, health_gates
    from harness.metrics.perception import MotCounts, clear_mot, perception_metrics
    from harness.metrics.safety import Tripwire, safety_metrics
    from harness.metrics.specs import spec_metric
    from harness.metrics.types import Direction, HealthResult, MetricResult

__all__ = [
    "Direction",
    "HealthResult",
    "MetricResult",
    "MotCounts",
    "OutputSpec",
    "Tripwire",
    "clear_mot",
    "control_metrics",
    "health_gates",
    "perception_metrics",
    "safety_metrics",
    "spec_metric",
]

_WHERE = {
    "control_metrics": "control",
    "OutputSpec": "health",
    "health_gates": "health",
    "MotCounts": "perception",
    "clear_mot": "perception",
    "perception_metrics": "perception",
    "Tripwire": "safety",
    "safety_metrics": "safety",
    "spec_metric": "specs",
    "Direction": "types",
    "HealthResult": "types",
    "MetricResult": "types",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
