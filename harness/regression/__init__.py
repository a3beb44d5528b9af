"""Baselines and regression comparison (named so it does not clash with ``baselines/``).

Names are imported from their submodules on first use (:mod:`harness._lazy`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

# Imported now, not on first use: the function ``compare`` has the name of its submodule,
# which a lazy lookup would find first once anything imported ``harness.regression.compare``.
from harness.regression.compare import (
    DEFAULT_TOLERANCES,
    Comparison,
    MetricComparison,
    compare,
    tolerance_for,
)

if TYPE_CHECKING:
    from harness.regression.config import (
        comparable_config,
        config_differences,
        scenario_differences,
        with_defaults,
    )
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
    "scenario_differences",
    "tolerance_for",
    "with_defaults",
]

_WHERE = {
    "comparable_config": "config",
    "config_differences": "config",
    "scenario_differences": "config",
    "with_defaults": "config",
    "Baseline": "store",
    "BaselineError": "store",
    "BaselineMetric": "store",
    "baseline_path": "store",
    "load_baseline": "store",
    "save_baseline": "store",
    "Verdict": "verdict",
    "absolute_failures": "verdict",
    "decide": "verdict",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
