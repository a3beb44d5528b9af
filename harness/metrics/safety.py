"""Safety metrics: the forklift SIL's mute logic against ground truth.

Expected state, per frame (every ground-truth sample of the forklift):
``muted = forklift inside the trailer AND no worker inside the loading ROI``.

* Inside the trailer: the forklift's reference point lies strictly on the ``inside`` side of
  the tripwire's line (the signed side of the infinite line through ``a`` and ``b``; "left"
  is counter-clockwise of the direction a → b).
* A worker inside the ROI: its ground-truth position (nearest stamp within the tolerance) lies
  in the polygon (even-odd rule; a point exactly on an edge may fall either way).

Actual state: ``/safety/is_muted`` held from each message on (a message at the frame's own
stamp counts). Before the first message the state is *not muted*: the indicator starts in
alarm and the monitor has not muted anything yet, so a monitor that never speaks is scored
as one that never mutes.

Scores, over all frames (frames are equally spaced ticks, so shares of frames are shares of
time):

* match rate (%), verdict PASS >= 95, NEAR >= 80, FAIL below (``MetricResult.verdict``);
* over-mute % (muted although it should not be) and under-mute % (not muted although it
  should be), every mismatching frame counted; their windows are the contiguous runs lasting
  at least ``min_window_s``, each from its first frame to the first frame after it;
* reaction lag: for every change of the expected state at time ``t_e`` (an *edge*), the time
  until the actual state first equals the new expected state: 0 when it already does at
  ``t_e``, else the stamp of the first message with that value minus ``t_e``. A lag exists
  only when that happens before the next expected edge (or the end of the run); otherwise the
  edge counts as *never engaged* (a mute edge) or *never released* (an unmute edge). Lags are
  reported separately for mute and unmute edges (p50, p95 with linear interpolation, max).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pandas as pd

from harness.frames import Frames
from harness.metrics.types import NEAR_AT, PASS_AT, MetricResult

__all__ = [
    "NEAR_AT",
    "PASS_AT",
    "Tripwire",
    "expected_muted",
    "mute_metrics",
    "points_in_polygon",
    "safety_metrics",
    "verdict",
]

Point = tuple[float, float]


@dataclass(frozen=True)
class Tripwire:
    """A line segment ``a`` → ``b`` and the side of it that is inside the trailer."""

    a: Point
    b: Point
    inside: Literal["left", "right"]

    def past(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """True where (x, y) is strictly on the inside side of the line."""
        (ax, ay), (bx, by) = self.a, self.b
        cross = (bx - ax) * (np.asarray(y) - ay) - (by - ay) * (np.asarray(x) - ax)
        return np.asarray(cross > 0 if self.inside == "left" else cross < 0)


def points_in_polygon(x: np.ndarray, y: np.ndarray, polygon: Sequence[Point]) -> np.ndarray:
    """Even-odd test of many points against one simple polygon (vertices in order)."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    inside = np.zeros(x.shape, dtype=bool)
    pts = [(float(px), float(py)) for px, py in polygon]
    for (x1, y1), (x2, y2) in zip(pts, pts[1:] + pts[:1], strict=True):
        if y1 == y2:
            continue
        crosses = (y1 > y) != (y2 > y)
        x_at = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
        inside ^= crosses & (x < x_at)
    return inside


def verdict(match_rate_pct: float) -> str:
    return "PASS" if match_rate_pct >= PASS_AT else "NEAR" if match_rate_pct >= NEAR_AT \
        else "FAIL"


def expected_muted(forklift: pd.DataFrame, workers: pd.DataFrame, *, tripwire: Tripwire,
                   roi: Sequence[Point], tolerance_ns: int = 8_333_333) -> pd.DataFrame:
    """``t_ns, inside, worker_in_roi, expected`` per forklift sample.

    ``forklift``: ``t_ns, x, y``; ``workers``: ``t_ns, name, x, y`` (world frame)."""
    f = forklift.sort_values("t_ns", kind="stable")
    t = f["t_ns"].to_numpy(np.int64)
    inside = tripwire.past(f["x"].to_numpy(), f["y"].to_numpy())
    in_roi = np.zeros(t.size, dtype=bool)
    for _, w in workers.groupby("name", sort=True, observed=True):
        w = w.sort_values("t_ns", kind="stable")
        wt = w["t_ns"].to_numpy(np.int64)
        if wt.size == 0:
            continue
        i = np.clip(np.searchsorted(wt, t), 1, max(wt.size - 1, 1))
        lo, hi = np.clip(i - 1, 0, wt.size - 1), np.clip(i, 0, wt.size - 1)
        k = np.where(np.abs(wt[hi] - t) < np.abs(t - wt[lo]), hi, lo)
        near = np.abs(wt[k] - t) <= tolerance_ns
        hit = points_in_polygon(w["x"].to_numpy()[k], w["y"].to_numpy()[k], roi)
        in_roi |= near & hit
    return pd.DataFrame({"t_ns": t, "inside": inside, "worker_in_roi": in_roi,
                         "expected": inside & ~in_roi})


def _held(frame_t: np.ndarray, muted: pd.DataFrame) -> np.ndarray:
    m = muted.sort_values("t_ns", kind="stable")
    mt = m["t_ns"].to_numpy(np.int64)
    mv = m["value"].to_numpy(bool)
    if mv.size == 0:
        return np.zeros(frame_t.size, dtype=bool)
    i = np.searchsorted(mt, frame_t, side="right") - 1
    return np.where(i >= 0, mv[np.clip(i, 0, None)], False)


def _windows(mask: np.ndarray, t: np.ndarray, t_end: int, min_ns: int
             ) -> tuple[tuple[float, float], ...]:
    m = np.concatenate(([False], mask, [False])).astype(np.int8)
    d = np.diff(m)
    out = []
    for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True):
        end = int(t[b]) if b < t.size else t_end
        if end - int(t[a]) >= min_ns:
            out.append((int(t[a]) / 1e9, end / 1e9))
    return tuple(out)


def _sm(name: str, value: float | None, unit: str, direction: Any, detail: str = "",
        windows: tuple[tuple[float, float], ...] = (), verdict_: str | None = None
        ) -> MetricResult:
    v = None if value is None or not math.isfinite(value) else float(value)
    return MetricResult(name, v, unit, direction, "safety", detail, windows, verdict_)


def _lag_stats(kind: str, lags: list[float], never: int, n_edges: int) -> list[MetricResult]:
    detail = f"{n_edges} expected {kind} edges, {len(lags)} followed"
    none_why = f"no expected {kind} edge" if n_edges == 0 else f"no {kind} edge followed"
    out = []
    for stat in ("p50", "p95", "max"):
        if lags:
            arr = np.asarray(lags)
            v = float(arr.max()) if stat == "max" else float(
                np.percentile(arr, 50 if stat == "p50" else 95))
            out.append(_sm(f"safety.{kind}_lag.{stat}", v, "s", "lower", detail))
        else:
            out.append(_sm(f"safety.{kind}_lag.{stat}", None, "s", "lower", none_why))
    return out


def mute_metrics(expected: pd.DataFrame, muted: pd.DataFrame, *,
                 min_window_s: float = 0.5) -> list[MetricResult]:
    """Score the actual mute state against ``expected`` (``t_ns, expected`` per frame).

    ``muted``: ``t_ns, value`` messages."""
    e = expected.sort_values("t_ns", kind="stable")
    t = e["t_ns"].to_numpy(np.int64)
    exp = e["expected"].to_numpy(bool)
    n = t.size
    names = ("safety.match_rate", "safety.over_mute", "safety.under_mute")
    if n == 0:
        why = "no forklift ground truth"
        return [_sm(names[0], None, "%", "higher", why), _sm(names[1], None, "%", "lower", why),
                _sm(names[2], None, "%", "lower", why),
                *_lag_stats("mute", [], 0, 0), *_lag_stats("unmute", [], 0, 0),
                _sm("safety.mute_never_engaged", None, "count", "lower", why),
                _sm("safety.unmute_never_released", None, "count", "lower", why)]
    act = _held(t, muted)
    dt = int(np.median(np.diff(t))) if n > 1 else 0
    t_end = int(t[-1]) + dt
    over, under = act & ~exp, ~act & exp
    match = 100.0 * float((act == exp).mean())
    min_ns = round(min_window_s * 1e9)
    band = verdict(match)
    out = [
        _sm(names[0], match, "%", "higher",
            f"{band} ({n} frames; PASS >= {PASS_AT:g} %, NEAR >= {NEAR_AT:g} %)",
            verdict_=band),
        _sm(names[1], 100.0 * float(over.mean()), "%", "lower",
            f"windows >= {min_window_s} s", _windows(over, t, t_end, min_ns)),
        _sm(names[2], 100.0 * float(under.mean()), "%", "lower",
            f"windows >= {min_window_s} s", _windows(under, t, t_end, min_ns)),
    ]
    m = muted.sort_values("t_ns", kind="stable")
    mt = m["t_ns"].to_numpy(np.int64)
    mv = m["value"].to_numpy(bool)
    edges = np.flatnonzero(exp[1:] != exp[:-1]) + 1
    lags: dict[bool, list[float]] = {True: [], False: []}
    never = {True: 0, False: 0}
    for k, idx in enumerate(edges):
        te = int(t[idx])
        target = bool(exp[idx])
        limit = int(t[edges[k + 1]]) if k + 1 < edges.size else t_end
        if bool(act[idx]) == target:
            lags[target].append(0.0)
            continue
        later = np.flatnonzero((mt > te) & (mv == target))
        if later.size and int(mt[later[0]]) < limit:
            lags[target].append((int(mt[later[0]]) - te) / 1e9)
        else:
            never[target] += 1
    n_mute = int(exp[edges].sum())
    n_unmute = int(edges.size - n_mute)
    out += _lag_stats("mute", lags[True], never[True], n_mute)
    out += _lag_stats("unmute", lags[False], never[False], n_unmute)
    out += [
        _sm("safety.mute_never_engaged", float(never[True]), "count", "lower",
            f"of {n_mute} expected mute edges"),
        _sm("safety.unmute_never_released", float(never[False]), "count", "lower",
            f"of {n_unmute} expected unmute edges"),
    ]
    return out


def safety_metrics(frames: Frames, *, tripwire: Tripwire, roi: Sequence[Point],
                   robot: str = "forklift", worker_prefix: str = "character_",
                   min_window_s: float = 0.5, tolerance_ns: int = 8_333_333
                   ) -> list[MetricResult]:
    """Expected vs actual mute state of a run (see the module docstring)."""
    g = frames.gt_poses
    fork = g[g["name"] == robot]
    workers = g[g["name"].str.startswith(worker_prefix)]
    exp = expected_muted(fork, workers, tripwire=tripwire, roi=roi, tolerance_ns=tolerance_ns)
    return mute_metrics(exp, frames.muted, min_window_s=min_window_s)
