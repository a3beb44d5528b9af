"""The report's figures as inline SVG: time-series panels on one shared time axis and the
top-down map of the run.

Every time-series panel has the same width and margins, so panels stacked in the page line up
second for second. Panels mark the run's numbered moments (M1, M2, …) and can highlight the
windows of a metric under review.

The panels and the map draw one run, or several runs overlaid (``srr diff``): pass a sequence
of ``(series, RunStyle)`` pairs instead of one series (``(RunData, RunStyle)`` pairs for the
map and :func:`time_panels`). One run is drawn exactly as the per-run report always drew it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

import numpy as np

from harness.report.data import (
    ControlSeries,
    Moment,
    PerceptionSeries,
    RunData,
    SafetySeries,
    Track,
    world_map,
)
from harness.report.svg import Scale, Svg, decimate, fmt_num, nice_ticks, tick_label
from harness.scenario import Scenario

__all__ = [
    "BASELINE",
    "CANDIDATE",
    "COLORS",
    "Highlight",
    "Panel",
    "RunStyle",
    "TimeAxis",
    "control_panel",
    "map_legend",
    "map_svg",
    "map_tracks",
    "perception_panels",
    "safety_panel",
    "time_panels",
]

WIDTH = 1200.0
LEFT = 168.0
RIGHT = 24.0
TOP = 22.0  # room for moment labels and highlight brackets
BOTTOM = 30.0
MAX_POINTS = 3000  # scatter points per panel
MAX_LAG_LABELS = 12  # reaction-lag labels per safety panel

COLORS = {
    "muted": "#16a34a",
    "inside": "#64748b",
    "roi": "#7c3aed",
    "over": "#dc2626",
    "under": "#f59e0b",
    "robot": "#2563eb",
    "odom": "#0891b2",
    "route": "#cbd5e1",
    "worker": "#92400e",
    "tracks": "#2563eb",
    "objects": "#475569",
    "error": "#0f766e",
    "miss": "#dc2626",
    "highlight": "#111827",
    "moment": "#6b7280",
    "collision": "#111827",
    "static": "#a8a29e",
}


@dataclass(frozen=True)
class RunStyle:
    """How one of several runs drawn in one figure looks: ``key`` gives the CSS class
    ``run-<key>``, ``label`` names the run in legends and tooltips, ``color`` is its robot and
    its series, ``color2`` its workers and ground-truth objects."""

    key: str
    label: str
    color: str
    color2: str


BASELINE = RunStyle("a", "baseline (A)", "#2563eb", "#92400e")
CANDIDATE = RunStyle("b", "candidate (B)", "#ea580c", "#be185d")

_S = TypeVar("_S")


def _layers(x: _S | Sequence[tuple[_S, RunStyle]]) -> list[tuple[_S, RunStyle | None]]:
    """One series (style None: the per-run look) or several with their styles."""
    if isinstance(x, (list, tuple)):
        if not x:
            raise ValueError("no series to draw")
        return [(item, style) for item, style in x]
    return [(x, None)]  # type: ignore[list-item]


@dataclass(frozen=True)
class Highlight:
    """Windows of the metric under review, outlined on its group's panels."""

    label: str
    windows: tuple[tuple[float, float], ...]


@dataclass
class Panel:
    """One figure: ``key`` (safety, control, perception…), ``group`` (the metric group it
    explains), a caption, a legend (label → colour, style) and the SVG text."""

    key: str
    group: str
    title: str
    svg: str
    legend: list[tuple[str, str, str]] = field(default_factory=list)
    note: str = ""


class TimeAxis:
    """The shared time axis: seconds of simulation time from 0 to the end of the run."""

    def __init__(self, end_s: float) -> None:
        self.end_s = max(float(end_s), 1e-3)
        self.x = Scale(0.0, self.end_s, LEFT, WIDTH - RIGHT)
        self.ticks = nice_ticks(0.0, self.end_s, 14)

    def frame(self, svg: Svg, top: float, bottom: float, moments: Sequence[Moment]) -> None:
        """Grid, time tick labels under the plot area and the moment markers."""
        for t in self.ticks:
            x = self.x(t)
            svg.line(x, top, x, bottom, class_="grid")
            svg.text(x, bottom + 14, tick_label(t, self.ticks), class_="tick",
                     text_anchor="middle")
        svg.text(WIDTH - RIGHT, bottom + 26, "sim time (s)", class_="axis-label",
                 text_anchor="end")
        svg.line(LEFT, bottom, WIDTH - RIGHT, bottom, class_="axis")
        # where the page's time cursor finds this panel's axis (sim seconds → x)
        svg.el("g", class_="t-axis", data_t0="0", data_t1=f"{self.end_s:.6g}",
               data_x0=fmt_num(LEFT), data_x1=fmt_num(WIDTH - RIGHT), data_y0=fmt_num(top),
               data_y1=fmt_num(bottom))
        for m in moments:
            x = self.x(m.t_s)
            svg.line(x, top - 6, x, bottom, class_="moment-line")
            svg.text(x, top - 9, f"M{m.number}", class_="moment-label", text_anchor="middle",
                     title=f"M{m.number} {m.t_s:.2f} s: {m.label}")

    def highlight(self, svg: Svg, top: float, bottom: float, hl: Highlight | None) -> None:
        if hl is None:
            return
        for a, b in hl.windows:
            x0, x1 = self.x(a), self.x(b)
            if x1 - x0 < 3:
                x0, x1 = x0 - 2, x1 + 2
            svg.rect(x0, top, x1 - x0, bottom - top, class_="hl-box",
                     title=f"{hl.label}: {a:.2f}–{b:.2f} s")
            svg.path(f"M{x0:.1f},{top + 5:.1f}V{top:.1f}H{x1:.1f}V{top + 5:.1f}",
                     class_="hl-bracket")


def _bool_runs(t: np.ndarray, v: np.ndarray, end: float) -> list[tuple[float, float]]:
    """[start, end) intervals where a sampled boolean is True (each sample holds until the
    next one, the last until ``end``)."""
    if t.size == 0:
        return []
    v = np.asarray(v, dtype=bool)
    m = np.concatenate(([False], v, [False])).astype(np.int8)
    d = np.diff(m)
    out = []
    for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True):
        out.append((float(t[a]), float(t[b]) if b < t.size else float(end)))
    return out


def _lane(svg: Svg, ax: TimeAxis, y: float, h: float, label: str, runs: Sequence[tuple[float,
          float]], color: str, sub: str = "") -> None:
    svg.text(LEFT - 8, y + h / 2 + (0 if sub else 4), label, class_="lane-label",
             text_anchor="end")
    if sub:
        svg.text(LEFT - 8, y + h / 2 + 12, sub, class_="lane-sub", text_anchor="end")
    svg.line(LEFT, y + h, WIDTH - RIGHT, y + h, class_="lane-base")
    for a, b in runs:
        svg.rect(ax.x(a), y + 3, ax.x(b) - ax.x(a), h - 3, fill=color, opacity="0.85",
                 title=f"{label}: {a:.2f}–{b:.2f} s")


# --------------------------------------------------------------------------- safety


def safety_panel(s: SafetySeries | Sequence[tuple[SafetySeries, RunStyle]], ax: TimeAxis,
                 moments: Sequence[Moment], hl: Highlight | None = None) -> Panel:
    """Lanes: forklift in trailer, worker in ROI, expected and actual muted state; mismatch
    windows shaded; every expected edge marked with the reaction lag to it. Several runs:
    worker in ROI, expected and actual muted per run (see :func:`_safety_overlay`)."""
    layers = _layers(s)
    if layers[0][1] is not None:
        return _safety_overlay([(x, st) for x, st in layers if st is not None], ax, moments, hl)
    s = layers[0][0]
    lane_h, gap = 24.0, 10.0
    n_lanes = 4
    lag_row = 30.0
    height = TOP + n_lanes * (lane_h + gap) + lag_row + BOTTOM
    top, bottom = TOP, TOP + n_lanes * (lane_h + gap) + lag_row
    svg = Svg(WIDTH, height, label="expected vs actual muted state")
    ax.frame(svg, top, bottom, moments)
    for w in s.mismatches:
        x0, x1 = ax.x(w.start_s), ax.x(w.end_s)
        svg.rect(x0, top, max(x1 - x0, 1.0), bottom - top - lag_row,
                 fill=COLORS[w.kind], opacity="0.28" if w.long else "0.12",
                 class_=f"mismatch mismatch-{w.kind}",
                 title=f"{w.kind}-mute {w.start_s:.2f}–{w.end_s:.2f} s "
                       f"({w.end_s - w.start_s:.2f} s)")
    ys = [top + 4 + i * (lane_h + gap) for i in range(n_lanes)]
    _lane(svg, ax, ys[0], lane_h, f"{s.robot} in trailer", _bool_runs(s.t, s.inside, s.end_s),
          COLORS["inside"], "past the tripwire")
    _lane(svg, ax, ys[1], lane_h, "worker in loading ROI",
          _bool_runs(s.t, s.worker_in_roi, s.end_s), COLORS["roi"])
    _lane(svg, ax, ys[2], lane_h, "expected muted", _bool_runs(s.t, s.expected, s.end_s),
          COLORS["muted"], "in trailer, ROI clear")
    _lane(svg, ax, ys[3], lane_h, "actual muted", _bool_runs(s.msg_t, s.msg_v, s.end_s),
          COLORS["muted"], s.topic)
    y_lag = ys[3] + lane_h + 12
    row_end = [-1e9, -1e9]  # right end of the last label in each of two label rows
    # many edges (a flapping state): label only the slowest reactions, arrows for all
    order = sorted(range(len(s.edges)), key=lambda k: -(
        math.inf if s.edges[k].lag_s is None else s.edges[k].lag_s or 0.0))
    labelled = set(order[:MAX_LAG_LABELS])
    for k, e in enumerate(s.edges):
        x0 = ax.x(e.t_s)
        end = e.response_s if e.response_s is not None else e.limit_s
        x1 = ax.x(end)
        if e.response_s is None:
            text = f"{e.kind}: never {'engaged' if e.target else 'released'}"
        else:
            text = f"{e.kind} lag {e.lag_s:.2f} s"
        width = 6.6 * len(text) if k in labelled else 0.0
        lx = max(x1, x0 + 4) + 4
        start = x0
        if lx + width > WIDTH - 2:  # no room right of the arrow: put the text left of it
            lx = x0 - 4 - width
            start = lx
        free = [r for r in (0, 1) if start > row_end[r] + 4]
        row = free[0] if free else int(row_end[1] < row_end[0])
        row_end[row] = max(lx + width, x1)
        y = y_lag + row * 13
        svg.line(x0, ys[2], x0, y + 4, class_="edge-line")
        cls = "lag-arrow" if e.response_s is not None else "lag-arrow never"
        svg.line(x0, y, x1, y, class_=cls)
        svg.path(f"M{x1:.1f},{y:.1f}l-6,-4v8z", class_=cls + " head")
        tip = (f"expected {e.kind} at {e.t_s:.2f} s, actual "
               + (f"at {e.response_s:.2f} s" if e.response_s is not None
                  else f"never before {e.limit_s:.2f} s"))
        if k not in labelled:
            svg.line(x0, y - 5, x0, y + 5, class_=cls, title=tip)
            continue
        svg.text(lx, y + 4, text, class_="lag-label",
                 title=tip)
    svg.text(LEFT - 8, y_lag + 4, "reaction lag", class_="lane-label", text_anchor="end")
    ax.highlight(svg, top, bottom, hl)
    note = f"strong shading: mismatches ≥ {s.min_window_s:g} s (the scored windows)"
    return Panel("safety", "safety", "Safety: expected vs actual muted state, reaction lags",
                 svg.render(), [("expected / actual muted", COLORS["muted"], "fill"),
                                ("over-mute (muted, should alarm)", COLORS["over"], "fill"),
                                ("under-mute (alarm, should be muted)", COLORS["under"], "fill"),
                                ("worker in ROI", COLORS["roi"], "fill"),
                                (f"{s.robot} in trailer", COLORS["inside"], "fill")], note)


def _safety_overlay(layers: Sequence[tuple[SafetySeries, RunStyle]], ax: TimeAxis,
                    moments: Sequence[Moment], hl: Highlight | None) -> Panel:
    """Per run, three lanes (worker in ROI, expected muted, actual muted in the run's colour)
    with the run's mismatch windows shaded across them; reaction lags are in the metric
    table."""
    lane_h, gap, block_gap = 20.0, 6.0, 12.0
    block = 3 * (lane_h + gap)
    top = TOP
    bottom = top + len(layers) * (block + block_gap)
    svg = Svg(WIDTH, bottom + BOTTOM, label="expected vs actual muted state of each run")
    ax.frame(svg, top, bottom, moments)
    for k, (s, st) in enumerate(layers):
        y0 = top + 4 + k * (block + block_gap)
        for w in s.mismatches:
            x0, x1 = ax.x(w.start_s), ax.x(w.end_s)
            svg.rect(x0, y0 - 2, max(x1 - x0, 1.0), block, fill=COLORS[w.kind],
                     opacity="0.28" if w.long else "0.12",
                     class_=f"mismatch mismatch-{w.kind} run-{st.key}",
                     title=f"{st.label}: {w.kind}-mute {w.start_s:.2f}–{w.end_s:.2f} s")
        lanes = [("worker in loading ROI", _bool_runs(s.t, s.worker_in_roi, s.end_s),
                  COLORS["roi"]),
                 ("expected muted", _bool_runs(s.t, s.expected, s.end_s), COLORS["muted"]),
                 ("actual muted", _bool_runs(s.msg_t, s.msg_v, s.end_s), st.color)]
        for i, (label, runs, color) in enumerate(lanes):
            _lane(svg, ax, y0 + i * (lane_h + gap), lane_h, label, runs, color, st.label)
    ax.highlight(svg, top, bottom, hl)
    legend = [("expected muted", COLORS["muted"], "fill")]
    legend += [(f"{st.label}: actual muted", st.color, "fill") for _, st in layers]
    legend += [("over-mute (muted, should alarm)", COLORS["over"], "fill"),
               ("under-mute (alarm, should be muted)", COLORS["under"], "fill"),
               ("worker in ROI", COLORS["roi"], "fill")]
    note = (f"strong shading: mismatches ≥ {layers[0][0].min_window_s:g} s (the scored "
            "windows), per run")
    return Panel("safety", "safety", "Safety: expected vs actual muted state of each run",
                 svg.render(), legend, note)


# --------------------------------------------------------------------------- line panels


def _y_axis(svg: Svg, y: Scale, ticks: Sequence[float], label: str) -> None:
    for v in ticks:
        py = y(v)
        svg.line(LEFT, py, WIDTH - RIGHT, py, class_="grid")
        svg.text(LEFT - 6, py + 4, tick_label(v, ticks), class_="tick", text_anchor="end")
    svg.text(LEFT - 48, (y.r0 + y.r1) / 2, label, class_="axis-label", text_anchor="middle",
             transform=f"rotate(-90 {LEFT - 48:.1f} {(y.r0 + y.r1) / 2:.1f})")


def _point_label(svg: Svg, px: float, y: float, text: str) -> None:
    """A label beside a marked point, on its left when it would run off the plot."""
    if px + 8 + 6.8 * len(text) > WIDTH - RIGHT:
        svg.text(px - 8, y, text, class_="point-label", text_anchor="end")
    else:
        svg.text(px + 8, y, text, class_="point-label")


def _value_ticks(hi: float) -> list[float]:
    """About four round ticks from 0, the last one at or above ``hi``."""
    ticks = nice_ticks(0.0, hi, 4)
    if len(ticks) > 1 and ticks[-1] < hi:
        ticks.append(round(ticks[-1] + ticks[1] - ticks[0], 10))
    return ticks


def _prefix(st: RunStyle | None, text: str) -> str:
    return text if st is None else f"{st.label}: {text}"


def _series_class(st: RunStyle | None, cls: str = "series") -> str:
    return cls if st is None else f"{cls} run-{st.key}"


def control_panel(c: ControlSeries | Sequence[tuple[ControlSeries, RunStyle]], ax: TimeAxis,
                  moments: Sequence[Moment], hl: Highlight | None = None) -> Panel:
    """Cross-track error to the route over time, its maximum marked, collisions shaded;
    several runs overlaid in their colours."""
    layers = _layers(c)
    c = layers[0][0]
    plot_h = 150.0
    top, bottom = TOP, TOP + plot_h
    svg = Svg(WIDTH, bottom + BOTTOM, label="cross-track error over time")
    peaks = [float(np.nanmax(s.cte)) for s, _ in layers if s.cte.size]
    hi = max(peaks) if peaks else 1.0
    ticks = _value_ticks(max(hi, 0.01))
    y = Scale(0.0, max(ticks[-1], hi * 1.08), bottom, top)
    _y_axis(svg, y, ticks, "cross-track (m)")
    ax.frame(svg, top, bottom, moments)
    for s, st in layers:
        for a, b in s.collisions:
            svg.rect(ax.x(a), top, max(ax.x(b) - ax.x(a), 2.0), plot_h, fill=COLORS["over"],
                     opacity="0.25", title=_prefix(st, f"collision {a:.2f}–{b:.2f} s"))
    for k, (s, st) in enumerate(layers):
        color = COLORS["robot"] if st is None else st.color
        xs, vs = decimate(s.t, s.cte, int(WIDTH))
        svg.polyline(ax.x.array(xs), y.array(vs), stroke=color, stroke_width="1.6",
                     class_=_series_class(st))
        if s.cte.size:
            i = int(np.argmax(s.cte))
            px, py = ax.x(s.t[i]), y(s.cte[i])
            svg.circle(px, py, 4, fill=color, stroke="#fff", stroke_width="1.5")
            _point_label(svg, px, (py - 6 if py > top + 14 else py + 14) + 14 * k,
                         _prefix(st, f"max {s.cte[i]:.3f} m at {s.t[i]:.2f} s"))
    ax.highlight(svg, top, bottom, hl)
    if layers[0][1] is None:
        legend = [(f"cross-track error of {c.robot} ({c.source})", COLORS["robot"], "line")]
    else:
        legend = [(f"{st.label}: cross-track error of {s.robot} ({s.source})", st.color, "line")
                  for s, st in layers if st is not None]
    if any(s.collisions for s, _ in layers):
        legend.append(("collision", COLORS["over"], "fill"))
    several = c.prefix != "control."
    return Panel(f"control.{c.robot}" if several else "control", "control",
                 f"Control ({c.robot}): cross-track error to the route" if several
                 else "Control: cross-track error to the route", svg.render(), legend)


def perception_panels(p: PerceptionSeries | Sequence[tuple[PerceptionSeries, RunStyle]],
                      ax: TimeAxis, moments: Sequence[Moment],
                      hl: Highlight | None = None) -> list[Panel]:
    """Position error of matched tracks (misses marked) and tracks vs ground-truth objects;
    several runs overlaid in their colours (misses then show in the counts only)."""
    layers = _layers(p)
    single = layers[0][1] is None
    p = layers[0][0]
    out = []
    plot_h = 120.0
    top, bottom = TOP, TOP + plot_h
    svg = Svg(WIDTH, bottom + BOTTOM, label=f"{p.cls} position error over time")
    peaks = [float(np.max(s.err_v)) for s, _ in layers if s.err_v.size]
    hi = max(peaks) if peaks else p.gate
    ticks = _value_ticks(max(hi, 0.05))
    y = Scale(0.0, max(ticks[-1], hi * 1.08), bottom, top)
    _y_axis(svg, y, ticks, "error (m)")
    ax.frame(svg, top, bottom, moments)
    if single:
        dt = float(np.median(np.diff(p.frame_t))) if p.frame_t.size > 1 else 0.0
        for a, b in _bool_runs(p.frame_t, p.n_missed > 0, float(p.frame_t[-1]) + dt
                               if p.frame_t.size else 0.0):
            svg.rect(ax.x(a), top - 5, max(ax.x(b) - ax.x(a), 2.0), 5, fill=COLORS["miss"],
                     title=f"frames with a missed object {a:.2f}–{b:.2f} s")
    for s, st in layers:
        stride = max(1, s.err_t.size // MAX_POINTS)  # long runs: thin the scatter evenly
        keep = np.zeros(s.err_t.size, dtype=bool)
        keep[::stride] = True
        if s.err_v.size:
            keep[int(np.argmax(s.err_v))] = True
        color = COLORS["error"] if st is None else st.color
        for t, v in zip(s.err_t[keep], s.err_v[keep], strict=True):
            svg.circle(ax.x(t), y(v), 2.2, fill=color,
                       title=_prefix(st, f"{t:.2f} s: {v:.3f} m"))
    for k, (s, st) in enumerate(layers):
        if s.err_v.size:
            color = COLORS["error"] if st is None else st.color
            i = int(np.argmax(s.err_v))
            px, py = ax.x(s.err_t[i]), y(s.err_v[i])
            svg.circle(px, py, 4.5, fill="none", stroke=color, stroke_width="1.5")
            _point_label(svg, px, (py + 4 if py > top + 10 else py + 14) + 14 * k,
                         _prefix(st, f"max {s.err_v[i]:.3f} m at {s.err_t[i]:.2f} s"))
    ax.highlight(svg, top, bottom, hl)
    legend = [("matched track error", COLORS["error"], "dot"),
              ("frames with a missed object", COLORS["miss"], "fill")] if single else [
        (f"{st.label}: matched track error", st.color, "dot") for _, st in layers
        if st is not None]
    out.append(Panel(f"perception.{p.cls}.error", "perception",
                     f"Perception ({p.cls}): position error of matched tracks", svg.render(),
                     legend,
                     f"per frame, objects and {p.cls} tracks paired within the {p.gate:g} m "
                     f"gate (minimum total distance); topic {p.topic}"))
    svg = Svg(WIDTH, TOP + 80 + BOTTOM, label=f"{p.cls} track count over time")
    top, bottom = TOP, TOP + 80.0
    hi_n = int(max(max(max(s.n_tracks.max(initial=0), s.n_objects.max(initial=0))
                       for s, _ in layers), 1))
    ticks = [float(v) for v in range(0, hi_n + 1, max(1, math.ceil(hi_n / 4)))]
    y = Scale(0.0, max(hi_n + 0.3, 1.0), bottom, top)
    _y_axis(svg, y, ticks, "count")
    ax.frame(svg, top, bottom, moments)
    lines: list[tuple[PerceptionSeries, np.ndarray, str, str]] = []
    if single:
        lines = [(p, p.n_objects, COLORS["objects"], "series dashed"),
                 (p, p.n_tracks, COLORS["tracks"], "series")]
        legend = [(f"{p.cls} tracks", COLORS["tracks"], "line"),
                  ("ground-truth objects", COLORS["objects"], "dashed")]
    else:
        legend = []
        for s, st in layers:
            assert st is not None
            lines.append((s, s.n_objects, st.color2, _series_class(st, "series dashed")))
            legend.append((f"{st.label}: ground-truth objects", st.color2, "dashed"))
        for s, st in layers:
            assert st is not None
            lines.append((s, s.n_tracks, st.color, _series_class(st)))
            legend.append((f"{st.label}: {s.cls} tracks", st.color, "line"))
    end = ax.end_s
    for s, series, color, cls in lines:
        if not s.frame_t.size:
            continue
        xs = np.repeat(np.append(s.frame_t, end), 2)[1:-1]
        vs = np.repeat(series.astype(np.float64), 2)
        xs, vs = decimate(xs, vs, int(WIDTH))
        svg.polyline(ax.x.array(xs), y.array(vs), stroke=color, stroke_width="1.6",
                     class_=cls)
    ax.highlight(svg, top, bottom, hl)
    out.append(Panel(f"perception.{p.cls}.count", "perception",
                     f"Perception ({p.cls}): tracks vs ground-truth objects in the area",
                     svg.render(), legend))
    return out


def time_panels(data: RunData | Sequence[tuple[RunData, RunStyle]],
                highlights: dict[str, Highlight] | None = None,
                moments: Sequence[Moment] | None = None) -> list[Panel]:
    """Every panel whose data exist, in order safety, control, perception. Several runs: one
    panel per robot and class that any of them has, with every run that has it overlaid, on
    a time axis long enough for the longest run; ``moments`` replace the runs' own."""
    layers = _layers(data)
    hl = highlights or {}
    out: list[Panel] = []
    if layers[0][1] is None:
        data = layers[0][0]
        ax = TimeAxis(data.end_s)
        ms = data.moments if moments is None else moments
        if data.safety is not None:
            out.append(safety_panel(data.safety, ax, ms, hl.get("safety")))
        for c in data.control:
            out.append(control_panel(c, ax, ms, hl.get("control")))
        for p in data.perception:
            out += perception_panels(p, ax, ms, hl.get("perception"))
        return out
    runs = [(d, st) for d, st in layers if st is not None]
    ax = TimeAxis(max(d.end_s for d, _ in runs))
    ms = list(moments or ())
    safety = [(d.safety, st) for d, st in runs if d.safety is not None]
    if safety:
        out.append(safety_panel(safety, ax, ms, hl.get("safety")))
    for robot in dict.fromkeys(c.robot for d, _ in runs for c in d.control):
        out.append(control_panel([(c, st) for d, st in runs for c in d.control
                                  if c.robot == robot], ax, ms, hl.get("control")))
    for cls in dict.fromkeys(p.cls for d, _ in runs for p in d.perception):
        out += perception_panels([(p, st) for d, st in runs for p in d.perception
                                  if p.cls == cls], ax, ms, hl.get("perception"))
    return out


# --------------------------------------------------------------------------- map


def _rot(points: Sequence[tuple[float, float]], cx: float, cy: float, yaw_deg: float
         ) -> list[tuple[float, float]]:
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return [(cx + c * x - s * y, cy + s * x + c * y) for x, y in points]


def _trailer(sc: Scenario) -> list[tuple[float, float]]:
    d = sc.world.dock
    hw = d.width / 2 + 0.1
    return _rot([(0.0, -hw), (d.length + 0.1, -hw), (d.length + 0.1, hw), (0.0, hw)],
                d.position[0], d.position[1], d.yaw_deg)


def map_svg(data: RunData | Sequence[tuple[RunData, RunStyle]], *, width: float = WIDTH,
            max_height: float = 560.0, moments: Sequence[Moment] | None = None) -> str:
    """Top-down view: walls, shelves, trailer (the procedural warehouse) and a world file's
    static outlines (``summary.json``'s ``world_map``), routes, zones, cameras, trajectories
    (ground truth solid, odometry dashed), workers' paths, collisions and the numbered moments.

    Several runs: the scene of the first, every run's robots and workers in its colours
    (class ``robot-path run-<key>``), collisions; odometry and mismatch segments are left to
    the per-run reports. ``moments`` (default: the first run's) sit on the first run's
    robot."""
    layers = _layers(data)
    data = layers[0][0]
    sc = data.scenario
    if sc is None:
        return ""
    wm = world_map(data.summary)  # a world file's static geometry, as the run recorded it
    warehouse = sc.world.procedural
    wx, wy = sc.world.size
    xs, ys = ([-wx / 2, wx / 2], [-wy / 2, wy / 2]) if warehouse else ([], [])
    trailer = _trailer(sc) if warehouse and sc.world.dock.enabled else []
    for x, y in [*trailer, *(p for o in (wm.outlines if wm else ()) for p in o.points)]:
        xs.append(x)
        ys.append(y)
    for tr in (t for d, _ in layers for t in d.tracks):
        if tr.x.size:
            xs += [float(np.nanmin(tr.x)), float(np.nanmax(tr.x))]
            ys += [float(np.nanmin(tr.y)), float(np.nanmax(tr.y))]
    if not xs:  # a world file without static geometry, and nothing moved
        xs, ys = [-1.0, 1.0], [-1.0, 1.0]
    x0, x1, y0, y1 = min(xs) - 1.0, max(xs) + 1.0, min(ys) - 1.0, max(ys) + 1.0
    pad_l, pad_b, pad_t, pad_r = 40.0, 26.0, 10.0, 10.0
    k = min((width - pad_l - pad_r) / (x1 - x0), (max_height - pad_b - pad_t) / (y1 - y0))
    w = pad_l + pad_r + k * (x1 - x0)
    h = pad_t + pad_b + k * (y1 - y0)
    X = Scale(x0, x1, pad_l, pad_l + k * (x1 - x0))
    Y = Scale(y0, y1, pad_t + k * (y1 - y0), pad_t)
    svg = Svg(w, h, label="top-down map of the run" if len(layers) == 1
              else "top-down map of the runs", class_="plot map")

    def poly(pts: Sequence[tuple[float, float]], **attrs: object) -> None:
        svg.polygon([X(p[0]) for p in pts], [Y(p[1]) for p in pts], **attrs)

    def line(pts: Sequence[tuple[float, float]] | np.ndarray, **attrs: object) -> None:
        a = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
        svg.polyline(X.array(a[:, 0]), Y.array(a[:, 1]), **attrs)

    svg.rect(X(x0), Y(y1), X(x1) - X(x0), Y(y0) - Y(y1), class_="map-bg")
    gx = nice_ticks(x0, x1, 12)
    gy = nice_ticks(y0, y1, 6)
    for v in gx:
        svg.line(X(v), Y(y0), X(v), Y(y1), class_="grid")
        svg.text(X(v), Y(y0) + 15, tick_label(v, gx), class_="tick", text_anchor="middle")
    for v in gy:
        svg.line(X(x0), Y(v), X(x1), Y(v), class_="grid")
        svg.text(X(x0) - 5, Y(v) + 4, tick_label(v, gy), class_="tick", text_anchor="end")
    if warehouse:
        poly([(-wx / 2, -wy / 2), (wx / 2, -wy / 2), (wx / 2, wy / 2), (-wx / 2, wy / 2)],
             class_="floor", title=f"warehouse floor {wx:g} × {wy:g} m (walls)")
        for i, sh in enumerate(sc.world.shelves):
            lx, ly = sh.size[0] / 2, sh.size[1] / 2
            poly(_rot([(-lx, -ly), (lx, -ly), (lx, ly), (-lx, ly)], sh.position[0],
                      sh.position[1], sh.yaw_deg), class_="shelf", title=f"shelf {i}")
    for o in (wm.outlines if wm is not None else ()):
        poly(o.points, class_="static", title=f"{o.name} ({Path(wm.file).name})"
             if wm is not None else o.name)
    if trailer:
        poly(trailer, class_="trailer", title="trailer (open end at the dock)")
        d = sc.world.dock
        lx, ly = _rot([(d.length * 0.8, -d.width / 2 - 0.6)], d.position[0], d.position[1],
                      d.yaw_deg)[0]
        svg.text(X(lx), Y(ly) + 4, "trailer", class_="map-label", text_anchor="middle")
    z = sc.zones
    if len(z.loading_roi) >= 3:
        poly(list(z.loading_roi), class_="roi", title="loading ROI")
        svg.text(X(min(p[0] for p in z.loading_roi)) + 4,
                 Y(max(p[1] for p in z.loading_roi)) + 13, "loading ROI",
                 class_="map-label roi-label")
    p = sc.scoring.perception
    if p is not None and p.enabled and len(p.area) >= 3:
        poly(list(p.area), class_="area", title="perception scoring area")
    if z.trailer_tripwire is not None:
        a, b = z.trailer_tripwire.a, z.trailer_tripwire.b
        line([a, b], class_="tripwire")
        mx, my = (a[0] + b[0]) / 2, (a[1] + b[1]) / 2
        dx, dy = b[0] - a[0], b[1] - a[1]
        n = math.hypot(dx, dy) or 1.0
        sgn = 1.0 if z.trailer_tripwire.inside == "left" else -1.0
        ix, iy = -dy / n * sgn, dx / n * sgn
        svg.line(X(mx), Y(my), X(mx + ix * 1.2), Y(my + iy * 1.2), class_="tripwire-dir")
        svg.text(X(a[0]) + 4, Y(a[1]) - 4, "tripwire", class_="map-label trip-label")
    for name, route in sc.routes.items():
        pts = np.asarray(route.waypoints, dtype=np.float64)
        line(pts, class_="route", title=f"route {name}")
        for wx_, wy_ in pts:
            svg.circle(X(wx_), Y(wy_), 3, class_="waypoint")
        svg.text(X(pts[0, 0]), Y(pts[0, 1]) + 16, f"route {name}", class_="map-label")
    for cam in sc.cameras:
        if cam.enabled:
            cx, cy = cam.spawn.position[0], cam.spawn.position[1]
            svg.path(f"M{X(cx):.1f},{Y(cy) - 6:.1f}l6,10h-12z", class_="camera",
                     title=f"camera {cam.name}")
            svg.text(X(cx) - 8, Y(cy) + 3, cam.name, class_="map-label cam-label",
                     text_anchor="end")
    for run, st in layers:
        _map_run(svg, X, Y, run, st, planned=run is data)
    # world → map pixels, for the page's time cursor: px = r0 + (x - d0) * k
    svg.el("g", class_="map-frame", data_sx=f"{X.d0:.6g} {X.r0:.6g} {X.k:.6g}",
           data_sy=f"{Y.d0:.6g} {Y.r0:.6g} {Y.k:.6g}")
    robots = [t for t in data.tracks if t.kind == "robot"]
    workers = [t for t in data.tracks if t.kind == "worker"]
    focus = robots[0] if robots else None
    placed: list[tuple[float, float]] = []
    for m in (data.moments if moments is None else moments):
        if focus is None:
            break
        pos = focus.at(m.t_s)
        if pos is None:
            continue
        if m.kind in ("over", "under", "collision"):
            for wk in workers:
                wp = wk.at(m.t_s)
                if wp:
                    svg.rect(X(wp[0]) - 4, Y(wp[1]) - 4, 8, 8, class_="worker-at",
                             title=f"{wk.name} at M{m.number} ({m.t_s:.2f} s)")
                    svg.text(X(wp[0]) + 6, Y(wp[1]) + 4, f"M{m.number}",
                             class_="moment-map worker-m")
        px, py = X(pos[0]), Y(pos[1])
        mx, my = px, py
        for k in range(12):  # markers of a standing robot would hide each other: fan out
            mx, my = px + 22 * ((k + 1) // 2) * (1 if k % 2 else -1) * (k > 0), py - 24 * (k > 0)
            if all(math.hypot(mx - qx, my - qy) >= 19 for qx, qy in placed):
                break
        placed.append((mx, my))
        if (mx, my) != (px, py):
            svg.line(px, py, mx, my, class_="moment-leader")
            svg.circle(px, py, 2.5, fill="#111827")
        svg.circle(mx, my, 9, class_="moment-dot",
                   title=f"M{m.number} {m.t_s:.2f} s: {m.label}")
        svg.text(mx, my + 3.5, str(m.number), class_="moment-num", text_anchor="middle")
    return svg.render()


def _map_run(svg: Svg, X: Scale, Y: Scale, data: RunData, st: RunStyle | None, *,
             planned: bool) -> None:
    """One run's workers, robots and collisions on the map; ``st`` None: the per-run look
    (with odometry and mismatch segments)."""
    robots = [t for t in data.tracks if t.kind == "robot"]
    workers = [t for t in data.tracks if t.kind == "worker"]
    run_cls = "" if st is None else f" run-{st.key}"
    for tr in workers:
        if tr.planned and planned:
            a = np.asarray(list(tr.planned), dtype=np.float64).reshape(-1, 2)
            svg.polyline(X.array(a[:, 0]), Y.array(a[:, 1]), class_="worker-plan",
                         title=f"{tr.name} planned route")
        _track(svg, X, Y, tr, COLORS["worker"] if st is None else st.color2,
               "worker-path" + run_cls, st)
    s = data.safety
    for tr in robots:
        if st is None and tr.odom_x is not None and tr.odom_y is not None:
            ox, oy = tr.odom_x, tr.odom_y
            step = max(1, ox.size // 1500)
            svg.polyline(X.array(ox[::step]), Y.array(oy[::step]), class_="odom-path",
                         stroke=COLORS["odom"])
        _track(svg, X, Y, tr, COLORS["robot"] if st is None else st.color,
               "robot-path" + run_cls, st)
        if len(robots) > 1 and tr.x.size:  # name each robot at its end point
            svg.text(X(tr.x[-1]) + 6, Y(tr.y[-1]) - 6, tr.name, class_="map-label robot-label")
        if st is None and s is not None and tr.name == s.robot:
            for win in s.mismatches:
                if not win.long:
                    continue
                sel = (tr.t >= win.start_s) & (tr.t <= win.end_s)
                if sel.sum() >= 1:
                    svg.polyline(X.array(tr.x[sel]), Y.array(tr.y[sel]),
                                 class_=f"mismatch-path mismatch-{win.kind}",
                                 stroke=COLORS[win.kind],
                                 title=f"{win.kind}-mute {win.start_s:.2f}–{win.end_s:.2f} s")
                    px, py = tr.at(win.start_s) or (0.0, 0.0)
                    svg.circle(X(px), Y(py), 5, fill=COLORS[win.kind], class_="mismatch-point",
                               title=f"{win.kind}-mute from {win.start_s:.2f} s")
    for tr in robots:
        for c in (cs for cs in data.control if cs.robot == tr.name):
            for t0, _ in c.collisions:
                hit = tr.at(t0)
                if hit:
                    svg.path(f"M{X(hit[0]) - 6:.1f},{Y(hit[1]) - 6:.1f}l12,12m0,-12l-12,12",
                             class_="collision", title=_prefix(st, f"collision at {t0:.2f} s"))


def map_tracks(data: RunData | Sequence[tuple[RunData, RunStyle]], max_hz: float = 20.0
               ) -> list[dict[str, object]]:
    """The robots' and workers' trajectories for the page's time cursor, which puts a marker
    on the map at each one's position at the cursor's time: name, kind, run key ("" for one
    run), colour, times (s) and world x, y (m), at most ``max_hz`` samples a second."""
    out: list[dict[str, object]] = []
    for run, st in _layers(data):
        for tr in run.tracks:
            if tr.t.size == 0:
                continue
            span = float(tr.t[-1] - tr.t[0])
            step = max(1, int(tr.t.size / max(span * max_hz, 1.0)))
            idx = np.unique(np.append(np.arange(0, tr.t.size, step), tr.t.size - 1))
            idx = idx[np.isfinite(tr.t[idx]) & np.isfinite(tr.x[idx]) & np.isfinite(tr.y[idx])]
            color = (COLORS["robot"] if tr.kind == "robot" else COLORS["worker"]) \
                if st is None else (st.color if tr.kind == "robot" else st.color2)
            out.append({"name": tr.name, "kind": tr.kind, "run": "" if st is None else st.key,
                        "color": color,
                        "t": [round(float(v), 3) for v in tr.t[idx]],
                        "x": [round(float(v), 3) for v in tr.x[idx]],
                        "y": [round(float(v), 3) for v in tr.y[idx]]})
    return out


def map_legend(data: RunData | Sequence[tuple[RunData, RunStyle]]
               ) -> list[tuple[str, str, str]]:
    """(label, colour, style) of what :func:`map_svg` draws for this run (or these runs)."""
    layers = _layers(data)
    data = layers[0][0]
    sc = data.scenario
    if sc is None:
        return []
    if layers[0][1] is not None:
        return _overlay_legend([(d, st) for d, st in layers if st is not None])
    robots = [t for t in data.tracks if t.kind == "robot"]
    out = _static_legend(data)
    for source in sorted({t.source for t in robots}):
        out.append((f"robot ({source})", COLORS["robot"], "line"))
    if any(t.odom_x is not None for t in robots):
        out.append(("odometry (world frame)", COLORS["odom"], "dashed"))
    if sc.routes:
        out.append(("route", COLORS["route"], "line"))
    if any(t.kind == "worker" for t in data.tracks):
        out.append(("worker (ground truth; dotted: planned)", COLORS["worker"], "line"))
    if len(sc.zones.loading_roi) >= 3:
        out.append(("loading ROI", COLORS["roi"], "fill"))
    if sc.zones.trailer_tripwire is not None:
        out.append(("trailer tripwire (tick: inside)", COLORS["over"], "dashed"))
    p = sc.scoring.perception
    if p is not None and p.enabled and len(p.area) >= 3:
        out.append(("perception area", COLORS["error"], "dashed"))
    if sc.cameras:
        out.append(("camera", "#111827", "tri"))
    if data.safety is not None and any(w.long for w in data.safety.mismatches):
        kinds = {w.kind for w in data.safety.mismatches if w.long}
        out += [(f"{k}-mute", COLORS[k], "line") for k in ("over", "under") if k in kinds]
    if any(c.collisions for c in data.control):
        out.append(("collision", COLORS["collision"], "x"))
    if data.moments:
        out.append(("moment M1… (robot; square: worker)", "#111827", "dot"))
    return out


def _static_legend(data: RunData) -> list[tuple[str, str, str]]:
    wm = world_map(data.summary)
    if wm is None or not wm.outlines:
        return []
    return [(f"static geometry of {Path(wm.file).name}", COLORS["static"], "fill")]


def _overlay_legend(layers: Sequence[tuple[RunData, RunStyle]]) -> list[tuple[str, str, str]]:
    sc = layers[0][0].scenario
    assert sc is not None
    out = _static_legend(layers[0][0])
    for d, st in layers:
        for source in sorted({t.source for t in d.tracks if t.kind == "robot"}):
            out.append((f"{st.label}: robot ({source})", st.color, "line"))
        if any(t.kind == "worker" for t in d.tracks):
            out.append((f"{st.label}: worker (ground truth)", st.color2, "line"))
    if sc.routes:
        out.append(("route", COLORS["route"], "line"))
    if len(sc.zones.loading_roi) >= 3:
        out.append(("loading ROI", COLORS["roi"], "fill"))
    if sc.zones.trailer_tripwire is not None:
        out.append(("trailer tripwire (tick: inside)", COLORS["over"], "dashed"))
    if sc.cameras:
        out.append(("camera", "#111827", "tri"))
    if any(c.collisions for d, _ in layers for c in d.control):
        out.append(("collision", COLORS["collision"], "x"))
    return out


def _track(svg: Svg, X: Scale, Y: Scale, tr: Track, color: str, cls: str,
           st: RunStyle | None = None) -> None:
    if tr.x.size == 0:
        return
    step = max(1, tr.x.size // 1500)
    svg.polyline(X.array(tr.x[::step]), Y.array(tr.y[::step]), class_=cls, stroke=color,
                 title=_prefix(st, f"{tr.name} ({tr.source})"))
    svg.circle(X(tr.x[0]), Y(tr.y[0]), 4, fill="#fff", stroke=color, stroke_width="2",
               title=_prefix(st, f"{tr.name} start"))
    svg.rect(X(tr.x[-1]) - 3.5, Y(tr.y[-1]) - 3.5, 7, 7, fill=color,
             title=_prefix(st, f"{tr.name} end"))
