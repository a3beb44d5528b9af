"""The page templates of every HTML page srr writes, and the environment that loads them.

The templates are the files in this folder (``harness/report/templates/``), shipped as
package data:

* ``page.html`` the frame every page extends: head and stylesheet, verdict banner, table of
  contents, footer;
* ``page.css`` the stylesheet of every page (its verdict colours are :data:`VERDICT_COLORS`),
  ``diff.css`` what the ``srr diff --html`` page adds to it;
* ``macros.html`` the pieces the pages share: notices, the map with its moments, series-plot
  panels and their legends, key-value lists and run cards, metric tables;
* ``cursor.js`` the time cursor of the report and diff pages (videos, plots and map on one
  simulation time), inlined by the ``cursor_data`` macro;
* ``report.html`` (a run's ``report.html``), ``diff.html`` (``srr diff --html``),
  ``suite.html`` (``srr suite``'s ``index.html``) and ``suitediff.html`` (``srr diff SUITE_A
  SUITE_B --html``).

Autoescaping is on: every value is text unless wrapped in ``Markup`` (the SVGs the report
builds itself).
"""

from __future__ import annotations

import functools

from jinja2 import Environment, PackageLoader, StrictUndefined, Template

__all__ = ["VERDICT_COLORS", "environment", "template"]

VERDICT_COLORS = {
    "PASS": "#15803d",
    "RECORDED": "#0f766e",
    "FAIL": "#b91c1c",
    "REGRESSED": "#c2410c",
    "INVALID": "#6d28d9",
    "INTERRUPTED": "#475569",
    "UNSCORED": "#a16207",
    "MISMATCH": "#0e7490",
    "FLAKY": "#be185d",
}


@functools.cache
def environment() -> Environment:
    """The one Jinja2 environment of the pages: templates read from this package (so an
    installed wheel finds them), autoescaped, undefined names an error."""
    env = Environment(loader=PackageLoader("harness.report", "templates"), autoescape=True,
                      undefined=StrictUndefined, trim_blocks=True, lstrip_blocks=True)
    env.globals["verdict_colors"] = VERDICT_COLORS
    return env


def template(name: str) -> Template:
    """The template ``name`` of this folder (``report.html``, ``diff.html``,
    ``suite.html``)."""
    return environment().get_template(name)
