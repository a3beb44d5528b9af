"""Baselines and regression comparison (named so it does not clash with ``baselines/``)."""

from harness.regression.compare import (
    DEFAULT_TOLERANCES,
    Comparison,
    MetricComparison,
    compare,
    tolerance_for,
)
from harness.regression.config import comparable_config, config_differences, with_defaults
from harness.regression.store import (
    Baseline,
    BaselineError,
    BaselineMetric,
    baseline_path,
    load_baseline,
    save_baseline,
)
from harness.regression.verdict import Verdict, absolute_failures, decide

__all__ = [
    "DEFAULT_TOLERANCES",
    "Baseline",
    "BaselineError",
    "BaselineMetric",
    "Comparison",
    "MetricComparison",
    "Verdict",
    "absolute_failures",
    "baseline_path",
    "comparable_config",
    "compare",
    "config_differences",
    "decide",
    "load_baseline",
    "save_baseline",
    "tolerance_for",
    "with_defaults",
]
