"""Outputs for people and CI systems: the HTML report of a run, the suite index, JUnit XML.

* :func:`write_report` / :func:`render_report` (:mod:`harness.report.html`): one
  self-contained ``report.html`` per run directory (``srr report RUN_DIR``).
* :func:`write_index` (:mod:`harness.report.index`): ``index.html`` linking the reports of
  several runs with their verdicts (``srr suite``).
* :mod:`harness.report.junit`: ``junit.xml``.

The HTML parts are imported on first use, so reading JUnit cases stays light.
"""

from __future__ import annotations

from typing import Any

__all__ = ["render_report", "write_index", "write_report"]


def __getattr__(name: str) -> Any:
    if name in ("render_report", "write_report"):
        from harness.report import html

        return getattr(html, name)
    if name == "write_index":
        from harness.report.index import write_index

        return write_index
    raise AttributeError(f"module 'harness.report' has no attribute {name!r}")
