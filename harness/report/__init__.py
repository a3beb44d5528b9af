"""Outputs for people and CI systems: the HTML report of a run, the suite page, JUnit XML.

* :func:`write_report` / :func:`render_report` (:mod:`harness.report.html`): one static
  ``report.html`` per run directory (``srr report RUN_DIR``), with the camera videos and
  clips beside it in ``video/`` (:mod:`harness.report.video`).
* :func:`write_suite_page` / :func:`render_suite_page` (:mod:`harness.report.suite_page`):
  ``OUT/index.html`` of ``srr suite`` from its ``summary.json`` — groups worst first with
  links to every repeat's report, statistics, sweep plots and night-to-night history.
* :mod:`harness.report.junit`: ``junit.xml``.

The HTML parts are imported on first use, so reading JUnit cases stays light.
"""

from __future__ import annotations

from typing import Any

__all__ = ["render_report", "render_suite_page", "write_report", "write_suite_page"]


def __getattr__(name: str) -> Any:
    if name in ("render_report", "write_report"):
        from harness.report import html

        return getattr(html, name)
    if name in ("render_suite_page", "write_suite_page"):
        from harness.report import suite_page

        return getattr(suite_page, name)
    raise AttributeError(f"module 'harness.report' has no attribute {name!r}")
