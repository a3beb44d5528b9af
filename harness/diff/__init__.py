"""``srr diff``: two runs compared — recorded topics message by message, metrics side by side
— and the one-page HTML view of both.

* :func:`diff_runs` (:mod:`harness.diff.core`): the comparison, as a :class:`DiffResult`;
* :mod:`harness.diff.topics`: both bags read once, messages paired by index per topic;
* :mod:`harness.diff.fields`: two decoded messages walked field by field;
* :mod:`harness.diff.tolerance`: ``--tolerance TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]``;
* :mod:`harness.diff.metrics`: both runs' metrics through the baseline comparison engine;
* :func:`render_diff` / :func:`write_diff` (:mod:`harness.diff.html`): the page.
"""

from __future__ import annotations

from typing import Any

from harness.diff.core import diff_runs
from harness.diff.result import (
    DiffResult,
    Divergence,
    FieldDiff,
    MetricDelta,
    RunInfo,
    TopicDiff,
    Worst,
)
from harness.diff.tolerance import Tolerance, parse_tolerance

__all__ = [
    "DiffResult",
    "Divergence",
    "FieldDiff",
    "MetricDelta",
    "RunInfo",
    "Tolerance",
    "TopicDiff",
    "Worst",
    "diff_runs",
    "parse_tolerance",
    "render_diff",
    "write_diff",
]


def __getattr__(name: str) -> Any:
    if name in ("render_diff", "write_diff"):
        from harness.diff import html

        return getattr(html, name)
    raise AttributeError(f"module 'harness.diff' has no attribute {name!r}")
