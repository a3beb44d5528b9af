"""``srr diff``: two runs compared — recorded topics message by message, metrics side by side
— and the one-page HTML view of both.

* :func:`diff_runs` (:mod:`harness.diff.core`): the comparison, as a :class:`DiffResult`;
* :mod:`harness.diff.topics`: both bags read once, messages paired by index per topic;
* :mod:`harness.diff.fields`: two decoded messages walked field by field;
* :mod:`harness.diff.tolerance`: ``--tolerance TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]``;
* :mod:`harness.diff.metrics`: both runs' metrics through the baseline comparison engine;
* :func:`render_diff` / :func:`write_diff` (:mod:`harness.diff.html`): the page.

Names are imported from their submodules on first use (:mod:`harness._lazy`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.diff.core import diff_runs
    from harness.diff.html import render_diff, write_diff
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

_WHERE = {
    "diff_runs": "core",
    "DiffResult": "result",
    "Divergence": "result",
    "FieldDiff": "result",
    "MetricDelta": "result",
    "RunInfo": "result",
    "TopicDiff": "result",
    "Worst": "result",
    "Tolerance": "tolerance",
    "parse_tolerance": "tolerance",
    "render_diff": "html",
    "write_diff": "html",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
