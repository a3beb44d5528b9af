"""``OUT/index.html`` of ``srr suite``: one self-contained page for the whole suite, built from
its ``summary.json`` (format ``srr-suite/1``) alone.

From the top: the suite verdict with counts, wall time, executor and start time; one table of
groups, worst first, with each group's key regressions (or reasons), its flakiness and a link
to every repeat's ``report.html`` (or, for a run that left none, why and its log); per group a
collapsible table of metric statistics over the repeats; per sweep, each metric plotted
against the swept parameter with its bands and the places where the verdict changes; and,
with ``--history``, each group's metrics night by night.

Links are relative to the page (the summary's paths are relative to OUT already), so the
folder works after it is moved or downloaded as one CI artifact. No script, no request.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any
from urllib.parse import quote

from markupsafe import Markup

from harness import __version__
from harness.atomic import write_text_atomic
from harness.report.html import fmt_value
from harness.report.suite_plots import (
    SweepFigure,
    SweepPoint,
    XAxis,
    boundaries,
    fmt_x,
    sparkline,
    sweep_figure,
    verdict_strip,
)
from harness.report.templates import template
from harness.summary import recording_note

__all__ = ["SUITE_PAGE_NAME", "VERDICT_ORDER", "render_suite_page", "write_suite_page"]

SUITE_PAGE_NAME = "index.html"
#: Group verdicts, worst first (the order of the groups table).
VERDICT_ORDER = ("INVALID", "FLAKY", "MISMATCH", "REGRESSED", "FAIL", "INTERRUPTED",
                 "UNSCORED", "RECORDED", "PASS")
MAX_KEY = 3


def _rank(verdict: str) -> int:
    return VERDICT_ORDER.index(verdict) if verdict in VERDICT_ORDER else 0


def _verdict(v: Any) -> str:
    return str(v) if v in VERDICT_ORDER else "INVALID"


def _map(v: Any) -> Mapping[str, Any]:
    """``v`` when it is a mapping, else an empty one (hostile or partial summaries)."""
    return v if isinstance(v, Mapping) else {}


def _num(v: Any) -> float | None:
    ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    return float(v) if ok else None


def _href(path: Any, root: Path | None) -> str | None:
    """A link to a path relative to OUT, or None for anything that is not one (absolute,
    a URL, leaving the folder) and, with ``root`` (OUT), for a file that is not there."""
    if not isinstance(path, str) or not path or "\\" in path or ":" in path.split("/")[0]:
        return None
    p = PurePosixPath(path)
    if p.is_absolute() or ".." in p.parts:
        return None
    if root is not None and not (root / p).is_file():
        return None
    return quote(p.as_posix(), safe="/._-~")


def _params_text(params: Any) -> tuple[str, ...]:
    """``path=value`` per swept parameter."""
    return tuple(f"{k}={fmt_x(v)}" for k, v in _map(params).items())


def _metric_order(name: str, stat: Mapping[str, Any] | None = None) -> tuple[int, str, str]:
    """Safety first (the match rate before the rest), then by metric group and name."""
    group = str((stat or {}).get("group") or name.split(".", 1)[0])
    first = 0 if name == "safety.match_rate" else 1 if group == "safety" else 2
    return first, group, name


# --------------------------------------------------------------------------- view models


@dataclass(frozen=True)
class Banner:
    """The suite's verdict and what the reviewer needs to know about how it ran."""

    name: str
    verdict: str
    exit_code: Any
    counts: tuple[tuple[str, int], ...]
    meta: tuple[str, ...]
    interrupted: bool
    n_runs: int


@dataclass(frozen=True)
class RunCell:
    """One repeat in the groups table: its report (or why there is none) and its log."""

    id: str
    repeat: Any
    verdict: str
    report: str | None
    log: str | None
    problem: str | None


@dataclass(frozen=True)
class FlakyRepeat:
    label: str
    verdict: str
    digest: str


@dataclass(frozen=True)
class FlakyView:
    """Why repeats of a group disagree: the topics whose digests differ, the first
    divergence, and each repeat's verdict and digest."""

    topics: tuple[str, ...]
    first_divergence: str | None
    compared: tuple[str, ...]
    repeats: tuple[FlakyRepeat, ...]


@dataclass(frozen=True)
class StatRow:
    """One metric of one group over its repeats, formatted."""

    name: str
    mean: str
    ci: str
    range: str
    n: int
    baseline: str
    status: str
    band: str
    better: str


@dataclass(frozen=True)
class GroupView:
    """A row of the groups table and its statistics table."""

    id: str
    anchor: str
    verdict: str
    params: tuple[str, ...]
    repeats: Any
    key: tuple[str, ...]
    more: int
    runs: tuple[RunCell, ...]
    flaky: FlakyView | None
    stats: tuple[StatRow, ...]
    other_bytes: str | None = None  # the first repeat's recording is not its baseline's


@dataclass(frozen=True)
class SweepView:
    """One sweep: its parameters, where the verdict changes, and a figure per metric."""

    name: str
    scenario: str
    x_param: str
    series_param: str
    n_points: int
    boundaries: tuple[str, ...]
    notes: tuple[str, ...]
    figures: tuple[SweepFigure, ...]


@dataclass(frozen=True)
class HistoryMetric:
    name: str
    svg: Markup
    tonight: str
    earlier: str  # min … max over the earlier nights
    note: str


@dataclass(frozen=True)
class HistoryGroup:
    """One group across nights: a verdict strip and a sparkline per metric."""

    id: str
    verdict: str
    open: bool
    note: str
    strip_label: str
    strip: Markup
    metrics: tuple[HistoryMetric, ...]


@dataclass(frozen=True)
class HistoryView:
    n_nights: int
    span: str
    warnings: tuple[str, ...]
    groups: tuple[HistoryGroup, ...]


# --------------------------------------------------------------------------- groups


def _excess(st: Mapping[str, Any]) -> float:
    """How many tolerances the mean moved from the baseline (inf: undefined or no
    tolerance)."""
    mean, base, tol = _num(st.get("mean")), _num(st.get("baseline")), _num(st.get("tolerance"))
    if mean is None or base is None or not tol:
        return math.inf
    return abs(mean - base) / tol


def _key_lines(g: Mapping[str, Any]) -> list[str]:
    """Regressed (or missing) metrics with mean vs baseline and delta, worst first; else the
    group's reasons."""
    stats = _map(g.get("stats"))
    bad = [(name, st) for name, st in stats.items()
           if isinstance(st, Mapping) and st.get("status") in ("regressed", "missing")]
    bad.sort(key=lambda e: -_excess(e[1]))
    lines = []
    for name, st in bad:
        unit = str(st.get("unit", ""))
        mean, base = _num(st.get("mean")), _num(st.get("baseline"))
        delta = "" if mean is None or base is None else \
            f", delta {fmt_value(mean - base, unit if unit != 'bool' else '', signed=True)}"
        tol = _num(st.get("tolerance"))
        tol_text = "" if tol is None else f", tolerance ±{tol:.3g}"
        n = st.get("n")
        lines.append(f"{name}: {fmt_value(mean, unit)} vs baseline {fmt_value(base, unit)} "
                     f"({st.get('status')}{delta}{tol_text}"
                     + (f"; mean of {n}" if isinstance(n, int) and n > 1 else "") + ")")
    return lines or [str(r) for r in g.get("reasons") or []]


def _run_cell(run_id: str, run: Mapping[str, Any] | None, root: Path | None) -> RunCell:
    if run is None:
        return RunCell(run_id, run_id.rsplit("#", 1)[-1], "INVALID", None, None,
                       "not in the summary's runs")
    problem = None
    reasons = [str(r) for r in run.get("reasons") or []]
    if run.get("crash"):
        problem = f"crashed: {run['crash']}"
    elif run.get("timed_out"):
        problem = next((r for r in reasons if "timed out" in r), "timed out")
    report = _href(run.get("report"), root)
    if problem is None and report is None:
        problem = (f"{run['report']} is missing from this folder" if run.get("report")
                   else reasons[0] if reasons else "no report was written")
    return RunCell(str(run.get("id", run_id)), run.get("repeat", "?"),
                   _verdict(run.get("verdict")), report, _href(run.get("log"), root), problem)


def _flaky_view(g: Mapping[str, Any], runs: Sequence[RunCell]) -> FlakyView | None:
    d = g.get("flaky_detail")
    if not g.get("flaky") and not isinstance(d, Mapping):
        return None
    d = d if isinstance(d, Mapping) else {}
    verdicts = list(d.get("verdicts") or [r.verdict for r in runs])
    digests = list(d.get("digests") or [])
    repeats = []
    for i, v in enumerate(verdicts):
        label = f"#{runs[i].repeat}" if i < len(runs) else f"#{i + 1}"
        digest = digests[i] if i < len(digests) else None
        repeats.append(FlakyRepeat(label, _verdict(v), str(digest) if digest else "—"))
    first = d.get("first_divergence")
    return FlakyView(tuple(str(t) for t in d.get("differing_topics") or []),
                     str(first) if first else None,
                     tuple(str(c) for c in d.get("compared") or []), tuple(repeats))


def _fmt_stat(st: Mapping[str, Any]) -> tuple[str, str, str, str]:
    unit = str(st.get("unit", ""))
    mean, std = _num(st.get("mean")), _num(st.get("std"))
    mean_text = fmt_value(mean, unit) + ("" if std is None or mean is None
                                         else f" ± {std:.3g}")
    ci = st.get("ci95")
    ci_text = "—"
    if isinstance(ci, Sequence) and len(ci) == 2 and all(_num(c) is not None for c in ci):
        ci_text = f"{fmt_value(ci[0], unit)} … {fmt_value(ci[1], unit)}"
    lo, hi = _num(st.get("min")), _num(st.get("max"))
    range_text = "—" if lo is None else f"{fmt_value(lo, unit)} / {fmt_value(hi, unit)}"
    base, tol = _num(st.get("baseline")), _num(st.get("tolerance"))
    base_text = "—" if base is None else fmt_value(base, unit) + (
        "" if tol is None else f" ± {tol:.3g}")
    return mean_text, ci_text, range_text, base_text


def _stat_rows(stats: Any) -> tuple[StatRow, ...]:
    stats = _map(stats)
    rows = []
    for name in sorted(stats, key=lambda k: _metric_order(k, stats[k])):
        st = stats[name]
        if not isinstance(st, Mapping):
            continue
        mean, ci, rng, base = _fmt_stat(st)
        rows.append(StatRow(
            str(name), mean, ci, rng, int(st.get("n") or 0), base, str(st.get("status") or ""),
            str(st.get("band") or ""),
            {"lower": "lower is better", "higher": "higher is better"}.get(
                str(st.get("direction")), "")))
    return tuple(rows)


def _group_view(i: int, g: Mapping[str, Any], runs_by_id: Mapping[str, Mapping[str, Any]],
                root: Path | None) -> GroupView:
    gid = str(g.get("id", f"group {i + 1}"))
    run_ids = [str(r) for r in g.get("runs") or []]
    if not run_ids:
        run_ids = [rid for rid, r in runs_by_id.items() if r.get("group") == gid]
    cells = tuple(_run_cell(rid, runs_by_id.get(rid), root) for rid in run_ids)
    key = _key_lines(g)
    flaky = _flaky_view(g, cells)
    against = g.get("against_baseline")
    other = (recording_note({"baseline": against}) if flaky is None and isinstance(against, dict)
             and not against.get("digest_matches") else None)
    return GroupView(gid, f"g{i}", _verdict(g.get("verdict")), _params_text(g.get("params")),
                     g.get("repeats", len(cells)), tuple(key[:MAX_KEY]),
                     max(0, len(key) - MAX_KEY), cells, flaky, _stat_rows(g.get("stats")),
                     other)


def _banner(s: Mapping[str, Any], groups: Sequence[GroupView], n_runs: int) -> Banner:
    counts = _map(s.get("counts"))
    if not counts:
        counts = {v: sum(g.verdict == v for g in groups) for v in VERDICT_ORDER}
    shown = tuple((v, int(counts[v])) for v in VERDICT_ORDER
                  if isinstance(counts.get(v), int) and counts[v] > 0)
    meta = []
    wall = _num(s.get("wall_s"))
    if wall is not None:
        meta.append(f"wall time {wall:.1f} s")
    executor = s.get("executor")
    if executor:
        jobs = s.get("jobs")
        meta.append(f"executor {executor}" + (f", {jobs} jobs" if jobs is not None else "")
                    + (f" at {s['address']}" if s.get("address") else ""))
    if s.get("started_at"):
        meta.append(f"started {s['started_at']}")
    meta.append(f"{len(groups)} groups, {n_runs} runs")
    verdict = str(s.get("verdict") or (min((g.verdict for g in groups), key=_rank)
                                       if groups else "INVALID"))
    return Banner(str(s.get("name") or "srr suite"), _verdict(verdict),
                  s.get("exit_code", ""), shown or (("groups", 0),), tuple(meta),
                  bool(s.get("interrupted")), n_runs)


# --------------------------------------------------------------------------- sweeps


def _sweep_view(sw: Mapping[str, Any], groups: Mapping[str, Mapping[str, Any]],
                runs_by_id: Mapping[str, Mapping[str, Any]]) -> SweepView | None:
    params = [str(p) for p in sw.get("params") or []]
    if not params:
        return None
    x_param = params[0]
    rest = params[1:]
    notes = []
    members = []
    for gid in sw.get("groups") or []:
        g = groups.get(str(gid))
        if g is None:
            notes.append(f"{gid}: not in the summary's groups (not plotted)")
            continue
        if x_param not in _map(g.get("params")):
            notes.append(f"{gid}: has no value for {x_param} (not plotted)")
            continue
        members.append(g)
    if not members:
        return None

    def series(g: Mapping[str, Any]) -> str:
        gp = g["params"]
        if len(rest) == 1:
            return fmt_x(gp.get(rest[0], "?"))
        return ", ".join(f"{p}={fmt_x(gp.get(p, '?'))}" for p in rest)

    axis = XAxis([g["params"][x_param] for g in members])
    base = [SweepPoint(str(g["id"]), g["params"][x_param], series(g), _verdict(g.get("verdict")))
            for g in members]
    bounds = boundaries(base, axis)
    metrics: dict[str, Mapping[str, Any]] = {}
    for g in members:
        for name, st in _map(g.get("stats")).items():
            metrics.setdefault(str(name), _map(st))
        for rid in g.get("runs") or []:
            for name in _map(_map(runs_by_id.get(str(rid))).get("metrics")):
                metrics.setdefault(str(name), {})
    figures = []
    for name in sorted(metrics, key=lambda k: _metric_order(k, metrics[k])):
        unit = ""
        points = []
        for g, b in zip(members, base, strict=True):
            st = _map(_map(g.get("stats")).get(name))
            unit = unit or str(st.get("unit") or "")
            values = []
            for rid in g.get("runs") or []:
                run = _map(runs_by_id.get(str(rid)))
                v = _num(_map(run.get("metrics")).get(name))
                if v is not None:
                    values.append((int(run.get("repeat") or 0), v))
            points.append(SweepPoint(b.group, b.x, b.series, b.verdict, tuple(values),
                                     _num(st.get("mean")), _num(st.get("baseline")),
                                     _num(st.get("tolerance"))))
        if any(p.values or p.mean is not None for p in points):
            figures.append(sweep_figure(name, unit, points, axis, x_param=x_param,
                                        series_param=", ".join(rest), bounds=bounds))
    if not figures:
        notes.append("no group of this sweep produced metric values")
    return SweepView(str(sw.get("name", "")), str(sw.get("scenario", "")), x_param,
                     ", ".join(rest), len(members),
                     tuple(b.describe(x_param) for b in bounds), tuple(notes),
                     tuple(SweepFigure(f.metric, f.unit, Markup(f.svg), f.legend, f.note)
                           for f in figures))


# --------------------------------------------------------------------------- history


def _night_label(night: Any, i: int) -> str:
    if not isinstance(night, Mapping):
        return f"night {i + 1}"
    when = str(night.get("started_at") or f"night {i + 1}")
    return f"{when} ({night.get('verdict', '?')})"


def _missing_note(values: Sequence[float | None], labels: Sequence[str]) -> str:
    earlier = values[:-1]
    have = [v is not None for v in earlier]
    if not earlier:
        return ""
    if values[-1] is not None and not any(have):
        return "new tonight: no earlier night has a value"
    notes = []
    if values[-1] is None:
        notes.append("missing tonight")
    gaps = [labels[i].split(" ")[0] for i, h in enumerate(have) if not h]
    if gaps and any(have):
        shown = ", ".join(gaps[:3]) + (f" +{len(gaps) - 3} more" if len(gaps) > 3 else "")
        notes.append(f"missing on {len(gaps)} of {len(earlier)} earlier nights ({shown})")
    return "; ".join(notes)


def _history_view(h: Any, groups: Sequence[GroupView],
                  raw: Mapping[str, Mapping[str, Any]]) -> HistoryView | None:
    if not isinstance(h, Mapping):
        return None
    nights = list(h.get("nights") or [])
    n = len(nights)
    if n == 0:
        return None
    labels = [_night_label(x, i) for i, x in enumerate(nights)]
    series = _map(h.get("series"))
    per_group = _map(h.get("verdicts"))
    suite_verdicts = [x.get("verdict") if isinstance(x, Mapping) else None for x in nights]
    out = []
    for g in groups:
        s = _map(series.get(g.id))
        stats = _map(_map(raw.get(g.id)).get("stats"))
        rows = []
        all_new = bool(s) and n > 1
        for name in sorted(s, key=lambda k: _metric_order(k, stats.get(k))):
            vals = list(s[name]) if isinstance(s[name], Sequence) else []
            vals = ([None] * (n - len(vals)) + vals)[-n:]
            values = [_num(v) for v in vals]
            unit = str(_map(stats.get(name)).get("unit") or "")
            all_new = all_new and all(v is None for v in values[:-1])
            before = [v for v in values[:-1] if v is not None]
            earlier = "" if not before else fmt_value(min(before), unit) if min(
                before) == max(before) else \
                f"{fmt_value(min(before), unit)} … {fmt_value(max(before), unit)}"
            rows.append(HistoryMetric(
                str(name), Markup(sparkline(values, labels, metric=str(name), unit=unit,
                                            tonight_verdict=g.verdict)),
                fmt_value(values[-1], unit), earlier, _missing_note(values, labels)))
        gv = per_group.get(g.id)
        if isinstance(gv, Sequence) and not isinstance(gv, str) and len(gv) == n:
            strip = [str(v) if v else None for v in gv]
            strip_label = "group verdict per night"
        else:
            strip = [str(v) if v else None for v in suite_verdicts]
            strip_label = "suite verdict per night"
        note = ("new tonight: no earlier night ran this group" if all_new else
                "" if rows else "no metric history for this group")
        out.append(HistoryGroup(g.id, g.verdict, g.verdict not in ("PASS", "RECORDED"), note,
                                strip_label,
                                Markup(verdict_strip(strip, labels)), tuple(rows)))
    warnings = tuple(str(w) for w in h.get("warnings") or [])
    span = (f"{n} nights from {labels[0]} to tonight, {labels[-1]}; each sparkline's y range "
            "is that metric's own min … max over the nights; hollow marks at the bottom are "
            "nights without a value") if n > 1 else (
        "No earlier night was found: the history starts tonight.")
    return HistoryView(n, span, warnings, tuple(out))


# --------------------------------------------------------------------------- page


def render_suite_page(summary: Mapping[str, Any], *, root: Path | None = None) -> str:
    """The suite page's HTML for a suite summary (format ``srr-suite/1``). With ``root``
    (the suite's output folder), a report or log that is not there gets no link and the
    page says so."""
    raw_groups = [g for g in summary.get("groups") or [] if isinstance(g, Mapping)]
    runs_by_id = {str(r.get("id")): r for r in summary.get("runs") or []
                  if isinstance(r, Mapping)}
    views = [_group_view(i, g, runs_by_id, root) for i, g in enumerate(raw_groups)]
    views.sort(key=lambda v: _rank(v.verdict))  # stable: the runner's order within a verdict
    by_id = {str(g.get("id")): g for g in raw_groups}
    sweeps = [v for v in (_sweep_view(sw, by_id, runs_by_id)
                          for sw in summary.get("sweeps") or [] if isinstance(sw, Mapping))
              if v is not None]
    banner = _banner(summary, views, len(runs_by_id))
    history = _history_view(summary.get("history"), views, by_id)
    toc = [("groups", "Groups"), ("stats", "Metric statistics")]
    if sweeps:
        toc.append(("sweeps", "Sweeps"))
    if history:
        toc.append(("history", "History"))
    return template("suite.html").render(
        verdict=banner.verdict, exit_code=banner.exit_code, toc=toc, b=banner, groups=views,
        sweeps=sweeps, history=history, srr_version=__version__)


def write_suite_page(out_dir: Path, summary: Mapping[str, Any]) -> Path:
    """Write ``<out_dir>/index.html`` for the suite ``summary`` (whose paths are relative to
    ``out_dir``) and return its path."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / SUITE_PAGE_NAME
    write_text_atomic(path, render_suite_page(summary, root=out))
    return path
