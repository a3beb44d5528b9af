"""``OUT/index.html`` of ``srr search``: one self-contained page built from the search's
``search.json`` (format ``srr-search/1``) alone.

From the top: whether the objective was violated, with the counts; the objective of every
trial against its trial number with the violation threshold and the best-so-far curve;
each parameter's importance; the counterexamples (parameters, value, scenario file, link to
the run's report); and every trial in a table. Links are relative to the page; no script,
no request.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import quote

from markupsafe import Markup

from harness import __version__
from harness.atomic import write_text_atomic
from harness.report.html import fmt_value
from harness.report.svg import Scale, Svg, nice_ticks, tick_label
from harness.report.templates import VERDICT_COLORS, template

__all__ = ["SEARCH_PAGE_NAME", "objective_figure", "render_search_page", "write_search_page"]

SEARCH_PAGE_NAME = "index.html"
WIDTH, HEIGHT = 720.0, 280.0
LEFT, RIGHT, TOP, BOTTOM = 60.0, 20.0, 18.0, 40.0
STATUS_COLORS = {"violated": VERDICT_COLORS["FAIL"], "holds": VERDICT_COLORS["PASS"],
                 "invalid": VERDICT_COLORS["INVALID"], "no-value": VERDICT_COLORS["UNSCORED"],
                 "killed": VERDICT_COLORS["INTERRUPTED"]}
#: The banner's colour class per search verdict.
_BANNER = {"VIOLATED": "FAIL", "HOLDS": "PASS", "INVALID": "INVALID",
           "INTERRUPTED": "INTERRUPTED"}


def _num(v: Any) -> float | None:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) \
        and math.isfinite(v) else None


def _href(path: Any) -> str | None:
    return quote(str(path)) if isinstance(path, str) and path else None


def objective_figure(trials: Sequence[Mapping[str, Any]], best: Sequence[Any],
                     threshold: float, metric: str) -> str:
    """Each trial's value (a dot coloured by its status; a tick on the axis for a trial
    without a value), the threshold as a dashed line and the best so far as a step line."""
    n = len(trials)
    values = [_num(t.get("value")) for t in trials]
    finite = [v for v in values if v is not None] + [threshold]
    lo, hi = min(finite), max(finite)
    pad = (hi - lo) * 0.08 or abs(hi) * 0.1 or 0.5
    lo, hi = lo - pad, hi + pad
    x = Scale(-0.5, max(n, 1) - 0.5, LEFT, WIDTH - RIGHT)
    y = Scale(lo, hi, HEIGHT - BOTTOM, TOP)
    svg = Svg(WIDTH, HEIGHT, label=f"{metric} per trial", class_="plot search-objective")
    ticks = nice_ticks(lo, hi, 6)
    for tv in ticks:
        svg.line(LEFT, y(tv), WIDTH - RIGHT, y(tv), stroke="#e5e7eb")
        svg.text(LEFT - 6, y(tv) + 4, tick_label(tv, ticks), text_anchor="end",
                 class_="tick")
    xticks = [int(v) for v in nice_ticks(0, max(n - 1, 1), 8) if float(v).is_integer()]
    for tv in xticks:
        svg.text(x(tv), HEIGHT - BOTTOM + 16, str(tv), text_anchor="middle", class_="tick")
    svg.text((LEFT + WIDTH - RIGHT) / 2, HEIGHT - 6, "trial", text_anchor="middle",
             class_="axis-label")
    svg.line(LEFT, y(threshold), WIDTH - RIGHT, y(threshold), stroke=VERDICT_COLORS["FAIL"],
             stroke_dasharray="6 4", class_="threshold", data_value=f"{threshold:g}",
             title=f"violation threshold {threshold:g}")
    xs: list[float] = []
    ys: list[float] = []
    for i, b in enumerate(best):
        bv = _num(b)
        if bv is None:
            continue
        if ys:
            xs.append(x(i))
            ys.append(ys[-1])
        xs.append(x(i))
        ys.append(y(bv))
    if xs:
        xs.append(x(n - 0.5))
        ys.append(ys[-1])
        svg.polyline(xs, ys, stroke="#2563eb", stroke_width=1.5, class_="best-so-far")
    for i, (t, v) in enumerate(zip(trials, values, strict=True)):
        status = str(t.get("status"))
        color = STATUS_COLORS.get(status, "#9ca3af")
        label = f"{t.get('id')}: {status}"
        if v is None:
            svg.rect(x(i) - 1.5, HEIGHT - BOTTOM - 8, 3, 8, fill=color, class_="trial novalue",
                     data_trial=str(t.get("number")), data_status=status, title=label)
        else:
            svg.circle(x(i), y(v), 4, fill=color, stroke="#fff", class_="trial",
                       data_trial=str(t.get("number")), data_status=status,
                       data_value=f"{v:g}", title=f"{label}, {metric} = {v:g}")
    return svg.render()


@dataclass(frozen=True)
class TrialRow:
    id: str
    number: int
    status: str
    value: str
    params: tuple[str, ...]
    verdict: str
    report: str | None
    log: str | None
    reason: str


@dataclass(frozen=True)
class Counterexample:
    id: str
    value: str
    params: tuple[str, ...]
    file: str | None
    report: str | None
    note: str | None
    suite: str | None


def _params(p: Any) -> tuple[str, ...]:
    if not isinstance(p, Mapping):
        return ()
    return tuple(f"{k} = {fmt_value(v) if _num(v) is not None else v}" for k, v in p.items())


def render_search_page(summary: Mapping[str, Any], *, root: Path | None = None) -> str:
    """The search page's HTML for a search summary (format ``srr-search/1``)."""
    trials = [t for t in summary.get("trials") or [] if isinstance(t, Mapping)]
    obj = summary.get("objective") if isinstance(summary.get("objective"), Mapping) else {}
    assert isinstance(obj, Mapping)
    metric = str(obj.get("metric", "?"))
    threshold = _num(obj.get("threshold")) or 0.0
    verdict = str(summary.get("verdict", "INVALID"))
    rows = [TrialRow(str(t.get("id")), int(t.get("number") or 0), str(t.get("status")),
                     "—" if _num(t.get("value")) is None else f"{t['value']:g}",
                     _params(t.get("params")), str(t.get("verdict") or ""),
                     _href(t.get("report")), _href(t.get("log")), str(t.get("reason") or ""))
            for t in trials]
    cex = [Counterexample(str(c.get("id")), f"{c.get('value'):g}"
                          if _num(c.get("value")) is not None else "—",
                          _params(c.get("params")), _href(c.get("file")),
                          _href(c.get("report")), c.get("note"), c.get("suite"))
           for c in summary.get("counterexamples") or [] if isinstance(c, Mapping)]
    imp = summary.get("importances") if isinstance(summary.get("importances"), Mapping) else {}
    assert isinstance(imp, Mapping)
    importances = sorted(((str(k), float(v)) for k, v in imp.items() if _num(v) is not None),
                         key=lambda kv: -kv[1])
    counts = summary.get("counts") if isinstance(summary.get("counts"), Mapping) else {}
    first = summary.get("first_violation")
    figure = Markup(objective_figure(trials, list(summary.get("best_so_far") or []),
                                     threshold, metric)) if trials else None
    meta = [f"scenario {summary.get('scenario')}",
            f"sampler {summary.get('sampler')} (seed {summary.get('seed')})",
            f"budget {summary.get('budget')}",
            f"{summary.get('executor')} × {summary.get('jobs')}",
            f"{summary.get('wall_s')} s (this call)"]
    toc = [("objective", "Objective"), ("importances", "Importances"),
           ("counterexamples", "Counterexamples"), ("trials", "Trials")]
    return template("search.html").render(
        verdict=_BANNER.get(verdict, "INVALID"), word=verdict,
        exit_code=summary.get("exit_code"), toc=toc, s=summary, metric=metric,
        violated=str(obj.get("violated", "below")), threshold=f"{threshold:g}",
        counts=counts, first_violation=first if isinstance(first, int) else None, meta=meta,
        figure=figure, rows=rows, cex=cex, importances=importances,
        space=[d for d in summary.get("space") or [] if isinstance(d, Mapping)],
        status_colors=STATUS_COLORS, srr_version=__version__)


def write_search_page(out_dir: Path, summary: Mapping[str, Any]) -> Path:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / SEARCH_PAGE_NAME
    write_text_atomic(path, render_search_page(summary, root=out))
    return path
