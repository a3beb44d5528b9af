"""Metrics: pure functions from recorded frames to typed results with units."""

from harness.metrics.types import Direction, HealthResult, MetricResult

__all__ = ["Direction", "HealthResult", "MetricResult"]
