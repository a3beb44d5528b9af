"""The suite page's figures as inline SVG.

* :func:`sweep_figure`: one metric against a swept parameter — a dot per repeat coloured by
  its group's verdict, a line through the group means (one per value of a second swept
  parameter), the metric's own bands (``safety.match_rate`` PASS/NEAR/FAIL, a goal-reached
  threshold) or else each point's ``baseline ± tolerance``, and a marker wherever the verdict
  changes along x (:func:`boundaries`).
* :func:`sparkline` and :func:`verdict_strip`: a metric and a verdict across nights, on one
  shared x layout so a strip lines up with the sparklines under it.

Like the run report's plots, everything is plain SVG text built with :mod:`harness.report.svg`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

from harness.metrics.safety import NEAR_AT, PASS_AT
from harness.regression.verdict import GOAL_REACHED, GOAL_REACHED_AT
from harness.report.html import fmt_value
from harness.report.svg import Scale, Svg, nice_ticks, tick_label
from harness.report.templates import VERDICT_COLORS

__all__ = [
    "SPARK_WIDTH",
    "Band",
    "Boundary",
    "Scalar",
    "SweepFigure",
    "SweepPoint",
    "XAxis",
    "boundaries",
    "fixed_bands",
    "fmt_x",
    "sparkline",
    "sweep_figure",
    "verdict_color",
    "verdict_strip",
]

Scalar = str | int | float | bool

WIDTH, HEIGHT = 600.0, 250.0
LEFT, RIGHT, TOP, BOTTOM = 56.0, 74.0, 22.0, 42.0
SERIES_COLORS = ("#374151", "#2563eb", "#db2777", "#0d9488", "#7c3aed", "#ea580c")
SERIES_DASH = (None, "6 3", "2 3", "8 3 2 3")
TOL_COLOR = "#64748b"
UNKNOWN_COLOR = "#9ca3af"
BAND_COLORS = {"PASS": "#16a34a", "NEAR": "#f59e0b", "FAIL": "#dc2626"}
SPARK_WIDTH, SPARK_HEIGHT, STRIP_HEIGHT = 280.0, 40.0, 14.0
MAX_X_TICKS = 10  # up to this many sweep values, each gets its own tick


def verdict_color(verdict: str | None) -> str:
    """The report's colour of a verdict (grey for none or an unknown one)."""
    return VERDICT_COLORS.get(verdict or "", UNKNOWN_COLOR)


def fmt_x(v: Scalar) -> str:
    """A swept value as the page writes it: ``1.4``, ``true``, ``fast``."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def _finite(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


@dataclass(frozen=True)
class SweepPoint:
    """One sweep point (a group) as one metric's plot sees it: its x value, the series it
    belongs to (the other swept values, ``""`` for one series), its verdict, the metric's
    value per repeat that produced one, their mean, and its baseline and tolerance."""

    group: str
    x: Scalar
    series: str
    verdict: str
    values: tuple[tuple[int, float], ...] = ()  # (repeat, value)
    mean: float | None = None
    baseline: float | None = None
    tolerance: float | None = None


class XAxis:
    """The swept parameter's axis. Numbers are placed by value; anything else (strings,
    booleans, or a mix) at equal spacing in the order first seen, labelled."""

    def __init__(self, values: Sequence[Scalar], r0: float = LEFT,
                 r1: float = WIDTH - RIGHT) -> None:
        distinct: dict[str, Scalar] = {}
        for v in values:
            distinct.setdefault(fmt_x(v), v)
        self.numeric = bool(distinct) and all(_finite(v) for v in distinct.values())
        if self.numeric:
            order = sorted(distinct.values(), key=float)
            lo, hi = float(order[0]), float(order[-1])
            pad = (hi - lo) * 0.06 if hi > lo else 0.5
            self.scale = Scale(lo - pad, hi + pad, r0, r1)
            if len(order) <= MAX_X_TICKS:
                self.ticks = [(self.scale(float(v)), fmt_x(v)) for v in order]
            else:
                nice = nice_ticks(lo, hi, 8)
                self.ticks = [(self.scale(t), tick_label(t, nice)) for t in nice]
            self._index: dict[str, float] = {k: float(v) for k, v in distinct.items()}
        else:
            order = list(distinct.values())
            self.scale = Scale(-0.5, max(len(order), 1) - 0.5, r0, r1)
            self._index = {fmt_x(v): float(i) for i, v in enumerate(order)}
            self.ticks = [(self.scale(i), fmt_x(v)) for i, v in enumerate(order)]
        self.order = order

    def key(self, v: Scalar) -> float:
        """Where ``v`` sorts along the axis (its value, or its place in first-seen order)."""
        return self._index.get(fmt_x(v), math.nan)

    def __call__(self, v: Scalar) -> float:
        return self.scale(self.key(v))


@dataclass(frozen=True)
class Band:
    """A horizontal band of a metric's own verdict: ``lo`` ≤ value < ``hi`` (None:
    unbounded)."""

    verdict: str  # PASS | NEAR | FAIL
    lo: float | None
    hi: float | None

    def label(self, short: bool = False) -> str:
        if self.lo is not None:
            return f"{self.verdict} ≥ {self.lo:g}"
        return f"{self.verdict} {'<' if short else 'below'} {self.hi:g}"


def fixed_bands(metric: str) -> tuple[Band, ...] | None:
    """The bands a metric is judged by whatever the baseline says, or None: the safety match
    rate (PASS ≥ 95 %, NEAR ≥ 80 %, FAIL below) and a route's goal reached (≥ 0.5)."""
    if metric == "safety.match_rate":
        return (Band("PASS", PASS_AT, None), Band("NEAR", NEAR_AT, PASS_AT),
                Band("FAIL", None, NEAR_AT))
    if GOAL_REACHED.match(metric):
        return Band("PASS", GOAL_REACHED_AT, None), Band("FAIL", None, GOAL_REACHED_AT)
    return None


@dataclass(frozen=True)
class Boundary:
    """Where the verdict changes between two neighbouring sweep points of one series."""

    series: str
    left: Scalar
    right: Scalar
    before: str
    after: str

    def describe(self, param: str) -> str:
        where = f" (with {self.series})" if self.series else ""
        return (f"{self.before} → {self.after}: boundary between {param} = {fmt_x(self.left)} "
                f"and {fmt_x(self.right)}{where}")


def _series_order(points: Sequence[SweepPoint]) -> list[str]:
    return list(dict.fromkeys(p.series for p in points))


def _along(points: Sequence[SweepPoint], series: str, axis: XAxis) -> list[SweepPoint]:
    return sorted((p for p in points if p.series == series), key=lambda p: axis.key(p.x))


def boundaries(points: Sequence[SweepPoint], axis: XAxis) -> list[Boundary]:
    """Every place, per series and in x order, where a point's verdict differs from the
    previous point's."""
    out = []
    for s in _series_order(points):
        row = _along(points, s, axis)
        for a, b in itertools.pairwise(row):
            if a.verdict != b.verdict:
                out.append(Boundary(s, a.x, b.x, a.verdict, b.verdict))
    return out


@dataclass(frozen=True)
class SweepFigure:
    """One metric's plot: caption parts, legend (label, colour, style), SVG text, a note."""

    metric: str
    unit: str
    svg: str
    legend: tuple[tuple[str, str, str], ...]
    note: str


def _y_domain(metric: str, values: Sequence[float],
              bands: tuple[Band, ...] | None) -> tuple[float, float]:
    vals = list(values)
    if metric == "safety.match_rate":
        vals += [NEAR_AT, 100.0]
    elif bands is not None:
        vals += [0.0, 1.0]
    if not vals:
        return 0.0, 1.0
    lo, hi = min(vals), max(vals)
    if hi - lo < 1e-12:
        pad = abs(lo) * 0.1 or 0.5
        lo, hi = lo - pad, hi + pad
    return lo, hi


def _tol_runs(row: Sequence[SweepPoint]) -> list[list[SweepPoint]]:
    """Runs of neighbouring points that have a baseline (the band breaks where one has
    none)."""
    runs: list[list[SweepPoint]] = [[]]
    for p in row:
        if p.baseline is not None and _finite(p.baseline):
            runs[-1].append(p)
        elif runs[-1]:
            runs.append([])
    return [r for r in runs if r]


def sweep_figure(metric: str, unit: str, points: Sequence[SweepPoint], axis: XAxis, *,
                 x_param: str, series_param: str = "",
                 bounds: Sequence[Boundary] = ()) -> SweepFigure:
    """The plot of ``metric`` over the sweep's ``points`` (see the module docstring)."""
    top, bottom = TOP, HEIGHT - BOTTOM
    bands = fixed_bands(metric)
    values = [v for p in points for _, v in p.values if _finite(v)]
    values += [p.mean for p in points if p.mean is not None and _finite(p.mean)]
    if bands is None:
        for p in points:
            if p.baseline is not None and _finite(p.baseline):
                tol = p.tolerance if p.tolerance is not None and _finite(p.tolerance) else 0.0
                values += [p.baseline - tol, p.baseline + tol]
    lo, hi = _y_domain(metric, values, bands)
    ticks = nice_ticks(lo, hi, 5)
    d0, d1 = min([lo, *ticks[:1]]), max([hi, *ticks[-1:]])
    pad = (d1 - d0) * 0.04
    y = Scale(d0 - pad, d1 + pad, bottom, top)
    svg = Svg(WIDTH, HEIGHT, label=f"{metric} against {x_param}", class_="plot sweep")
    legend: list[tuple[str, str, str]] = []
    note = ""
    # the metric's own bands, or each point's baseline ± tolerance
    if bands is not None:
        for b in bands:
            b_lo = y.d0 if b.lo is None else max(b.lo, y.d0)
            b_hi = y.d1 if b.hi is None else min(b.hi, y.d1)
            if b_hi <= b_lo:
                continue
            svg.rect(LEFT, y(b_hi), WIDTH - RIGHT - LEFT, y(b_lo) - y(b_hi),
                     class_=f"band band-{b.verdict}", data_verdict=b.verdict,
                     data_lo="" if b.lo is None else f"{b.lo:g}",
                     data_hi="" if b.hi is None else f"{b.hi:g}", title=b.label())
            svg.text(WIDTH - RIGHT + 5, (y(b_hi) + y(b_lo)) / 2 + 4, b.label(short=True),
                     class_="band-label")
            legend.append((b.label(), BAND_COLORS[b.verdict], "fill"))
        for edge in sorted({e for b in bands for e in (b.lo, b.hi) if e is not None}):
            svg.line(LEFT, y(edge), WIDTH - RIGHT, y(edge), class_="threshold",
                     data_value=f"{edge:g}")
    else:
        with_base = [p for p in points if p.baseline is not None and _finite(p.baseline)]
        for s in _series_order(points):
            for run in _tol_runs(_along(points, s, axis)):
                bases = [float(p.baseline or 0.0) for p in run]
                tols = [float(p.tolerance) if p.tolerance is not None and _finite(p.tolerance)
                        else 0.0 for p in run]
                xs = [axis(p.x) for p in run]
                title = "baseline ± tolerance: " + ", ".join(
                    f"{fmt_x(p.x)}: {fmt_value(b, unit)} ± {t:.3g}"
                    for p, b, t in zip(run, bases, tols, strict=True))
                upper = [y(b + t) for b, t in zip(bases, tols, strict=True)]
                lower = [y(b - t) for b, t in zip(bases, tols, strict=True)]
                if len(run) == 1:
                    svg.rect(xs[0] - 10, upper[0], 20, lower[0] - upper[0], class_="tol-band",
                             data_points="1", title=title)
                else:
                    svg.polygon(xs + xs[::-1], upper + lower[::-1], class_="tol-band",
                                data_points=str(len(run)), title=title)
                    svg.polyline(xs, [y(b) for b in bases], class_="baseline-line")
        if with_base:
            legend.append(("baseline ± tolerance", TOL_COLOR, "fill"))
            missing = [p for p in points if p not in with_base]
            if missing:
                note = ("no baseline at " + ", ".join(
                    fmt_x(p.x) + (f" ({p.series})" if p.series else "") for p in missing)
                    + ": no band there")
        else:
            note = "no baseline at any point: no tolerance band"
    # axes
    for v in ticks:
        svg.line(LEFT, y(v), WIDTH - RIGHT, y(v), class_="grid")
        svg.text(LEFT - 6, y(v) + 4, tick_label(v, ticks), class_="tick", text_anchor="end")
    svg.line(LEFT, bottom, WIDTH - RIGHT, bottom, class_="axis")
    for px, label in axis.ticks:
        svg.line(px, bottom, px, bottom + 4, class_="axis")
        svg.text(px, bottom + 16, label, class_="tick x-tick", text_anchor="middle",
                 data_x=label)
    svg.text(WIDTH - RIGHT, bottom + 32, x_param, class_="axis-label", text_anchor="end")
    # where the verdict changes
    for bd in bounds:
        px = (axis(bd.left) + axis(bd.right)) / 2
        svg.line(px, top, px, bottom, class_="boundary",
                 data_between=f"{fmt_x(bd.left)}|{fmt_x(bd.right)}", data_series=bd.series,
                 title=bd.describe(x_param))
        svg.text(px, top - 6, f"{bd.before} → {bd.after}", class_="boundary-label",
                 text_anchor="middle")
    # a line through the group means, then a dot per repeat
    series = _series_order(points)
    several = len(series) > 1
    for k, s in enumerate(series):
        color = SERIES_COLORS[k % len(SERIES_COLORS)]
        dash = SERIES_DASH[k % len(SERIES_DASH)] if several else None
        row = _along(points, s, axis)
        svg.polyline([axis(p.x) for p in row],
                     [y(p.mean) if p.mean is not None and _finite(p.mean) else math.nan
                      for p in row],
                     class_="mean-line", stroke=color, stroke_dasharray=dash,
                     data_series=s)
        name = f"{series_param}={s}" if several and series_param else s
        legend.append((f"group mean ({name})" if several else "group mean", color,
                       "dashed" if dash else "line"))
        for p in row:
            px = axis(p.x)
            if p.mean is not None and _finite(p.mean):
                svg.line(px - 7, y(p.mean), px + 7, y(p.mean), class_="mean",
                         data_group=p.group,
                         title=f"{p.group}: mean {fmt_value(p.mean, unit)} ({p.verdict})")
            n = len(p.values)
            for i, (rep, v) in enumerate(p.values):
                if not _finite(v):
                    continue
                svg.circle(px + (i - (n - 1) / 2) * 4.0, y(v), 3.6, class_="dot",
                           fill=verdict_color(p.verdict),
                           stroke=color if several else "#ffffff", data_group=p.group,
                           data_x=fmt_x(p.x), data_value=f"{v:g}", data_verdict=p.verdict,
                           title=f"{p.group} #{rep}: {fmt_value(v, unit)} ({p.verdict})")
    seen = list(dict.fromkeys(p.verdict for p in points if p.values))
    legend[:0] = [(v, verdict_color(v), "dot") for v in seen]
    return SweepFigure(metric, unit, svg.render(), tuple(legend), note)


def _night_scale(n: int) -> Scale:
    return Scale(-1.0, 1.0, 8.0, SPARK_WIDTH - 8.0) if n <= 1 else Scale(
        0.0, n - 1.0, 8.0, SPARK_WIDTH - 8.0)


def sparkline(values: Sequence[float | None], labels: Sequence[str], *, metric: str,
              unit: str = "", tonight_verdict: str | None = None) -> str:
    """One point per night (oldest → tonight, equally spaced), a hollow mark at the bottom
    for a night without a value; tonight's point larger, in its verdict's colour. The y range
    is the metric's own min … max over the nights."""
    n = len(values)
    x = _night_scale(n)
    finite = [float(v) for v in values if v is not None and _finite(v)]
    lo, hi = (min(finite), max(finite)) if finite else (0.0, 1.0)
    if hi - lo < 1e-12:
        lo, hi = lo - (abs(lo) * 0.1 or 0.5), hi + (abs(hi) * 0.1 or 0.5)
    y = Scale(lo, hi, SPARK_HEIGHT - 9.0, 7.0)
    svg = Svg(SPARK_WIDTH, SPARK_HEIGHT, label=f"{metric} over {n} nights", class_="spark")
    ys = [y(float(v)) if v is not None and _finite(v) else math.nan for v in values]
    svg.polyline([x(i) for i in range(n)], ys, class_="spark-line")
    for i, v in enumerate(values):
        last = i == n - 1
        if v is None or not _finite(v):
            svg.circle(x(i), SPARK_HEIGHT - 3.0, 2.2, class_="night missing",
                       title=f"{labels[i]}: no value")
            continue
        svg.circle(x(i), y(float(v)), 4.0 if last else 2.3,
                   class_="night tonight" if last else "night",
                   style=f"fill:{verdict_color(tonight_verdict)}" if last else None,
                   title=f"{labels[i]}: {fmt_value(v, unit)}")
    return svg.render()


def verdict_strip(verdicts: Sequence[str | None], labels: Sequence[str]) -> str:
    """A cell per night in the verdict's colour, on the sparklines' x layout; tonight's cell
    outlined."""
    n = len(verdicts)
    x = _night_scale(n)
    step = abs(x(1.0) - x(0.0)) if n > 1 else 24.0
    w = min(max(step * 0.8, 4.0), 24.0)
    svg = Svg(SPARK_WIDTH, STRIP_HEIGHT, label=f"verdicts over {n} nights", class_="spark")
    for i, v in enumerate(verdicts):
        svg.rect(x(i) - w / 2, 1.0, w, STRIP_HEIGHT - 2.0,
                 class_="strip-cell tonight" if i == n - 1 else "strip-cell",
                 fill=verdict_color(v), data_verdict=v or "",
                 title=f"{labels[i]}: {v or 'not run'}")
    return svg.render()
