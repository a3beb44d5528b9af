"""Metrics: pure functions from recorded frames to typed results with units.

``control``, ``perception``, ``safety`` give :class:`MetricResult` lists; ``health`` gives
:class:`HealthResult` gates. Read a run with :func:`harness.frames.load_frames` first.
"""

from harness.metrics.control import control_metrics
from harness.metrics.health import OutputSpec, health_gates
from harness.metrics.perception import MotCounts, clear_mot, perception_metrics
from harness.metrics.safety import Tripwire, safety_metrics
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
]
