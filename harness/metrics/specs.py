"""Specification metrics: the robustness of a scenario's STL formulas on a recorded run.

Signals are sampled on the run's tick grid, ``t_k = floor(k · 10⁹ / tick_hz)`` ns for
``k = 0 … K`` (the last tick at or before the recording's end), by sample-and-hold: the value
at ``t_k`` is the last sample stamped at or before ``t_k`` (ground truth by its stamp, topics
by log time). Before a signal's first sample it has no value, except the safety topics
(``alarm``, ``muted``), which are false until their first message (the monitor has not said
anything yet). A formula is evaluated from the first tick at which every signal it reads has
a value (the detail says when that is not the first tick).

Boolean signals are +1 where they hold and −1 where they do not, so a formula of booleans
only has robustness ±1. rtamt (:func:`harness.scenario.specs.evaluate`) computes the
robustness trace in discrete time (one step = one tick). The metric's value is the
robustness at the start; for a formula ``always φ`` it is the minimum of ``φ``'s trace,
and the violation windows are the maximal runs of ticks where ``φ`` is negative. Any other
formula has windows only when it is violated: the runs where its own trace is negative.
Each window runs from its first tick to the first tick after it (the end of the run for a
run that lasts). A required spec's metric carries the verdict
PASS (robustness ≥ 0) or FAIL (violated, or not evaluable).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from harness.metrics.types import MetricResult
from harness.scenario.specs import Formula, SpecError, evaluate

__all__ = ["as_bool", "held", "spec_metric", "tick_grid", "violation_windows"]


def tick_grid(end_ns: int, tick_hz: int) -> np.ndarray:
    """``floor(k · 10⁹ / tick_hz)`` for every tick ``k`` at or before ``end_ns``."""
    # the largest k with floor(k · 10⁹ / hz) <= end_ns, i.e. k · 10⁹ < (end_ns + 1) · hz
    k_max = ((max(0, end_ns) + 1) * tick_hz - 1) // 1_000_000_000
    return (np.arange(k_max + 1, dtype=np.int64) * 1_000_000_000) // tick_hz


def held(t_ns: np.ndarray, values: np.ndarray, grid: np.ndarray,
         before: float = math.nan) -> np.ndarray:
    """``values`` (stamped ``t_ns``, sorted) held onto ``grid``: the last sample at or
    before each tick; ``before`` where there is none yet."""
    t = np.asarray(t_ns, dtype=np.int64)
    v = np.asarray(values, dtype=np.float64)
    i = np.searchsorted(t, grid, side="right") - 1
    return np.where(i >= 0, v[np.clip(i, 0, None)] if v.size else before, before)


def as_bool(mask: np.ndarray) -> np.ndarray:
    """A boolean signal's values: +1 where it holds, −1 where not, NaN where undefined."""
    m = np.asarray(mask, dtype=np.float64)
    return np.where(np.isnan(m), np.nan, np.where(m > 0.5, 1.0, -1.0))


def violation_windows(trace: np.ndarray, grid: np.ndarray, t_end: int
                      ) -> tuple[tuple[float, float], ...]:
    """Maximal runs of ticks where ``trace`` < 0, in seconds: from the run's first tick to
    the first tick after it (``t_end`` when it lasts to the end)."""
    neg = np.concatenate(([False], np.asarray(trace) < 0, [False])).astype(np.int8)
    d = np.diff(neg)
    out = []
    for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True):
        end = int(grid[b]) if b < grid.size else t_end
        out.append((int(grid[a]) / 1e9, end / 1e9))
    return tuple(out)


def spec_metric(name: str, formula: Formula, signals: Mapping[str, np.ndarray],
                grid: np.ndarray, *, required: bool = True,
                undefined: Mapping[str, str] | None = None) -> MetricResult:
    """``spec.<name>.robustness`` of ``formula`` over ``signals`` (rtamt variable → values on
    ``grid``, NaN where undefined). ``undefined``: variable → why it has no values at all."""
    metric = f"spec.{name}.robustness"
    unit = formula.unit

    def result(value: float | None, detail: str,
               windows: tuple[tuple[float, float], ...] = ()) -> MetricResult:
        ok = value is not None and value >= 0
        verdict = ("PASS" if ok else "FAIL") if required else None
        return MetricResult(metric, value, unit, "higher", "spec", detail, windows, verdict)

    names = {s.var: s.text for s in formula.signals}
    for var, why in (undefined or {}).items():
        return result(None, f"not evaluated: {names.get(var, var)}: {why}")
    if grid.size == 0:
        return result(None, "not evaluated: no ticks recorded")
    arrays = {v: np.asarray(signals[v], dtype=np.float64) for v in names}
    if any(a.shape != grid.shape for a in arrays.values()):
        raise ValueError(f"{metric}: every signal needs one value per tick ({grid.size})")
    defined = np.logical_and.reduce([np.isfinite(a) for a in arrays.values()])
    start = int(np.argmax(defined)) if defined.any() else grid.size
    if start >= grid.size:
        missing = [names[v] for v, a in arrays.items() if not np.isfinite(a).any()]
        return result(None, "not evaluated: no tick at which every signal has a value"
                      + (f" ({', '.join(missing)} never has one)" if missing else ""))
    if not defined[start:].all():  # pragma: no cover - held signals stay defined
        return result(None, "not evaluated: a signal loses its value during the run")
    g = grid[start:]
    columns = {v: a[start:].tolist() for v, a in arrays.items()}
    try:
        trace_list, is_always = evaluate(formula, columns, int(g.size))
    except SpecError as err:
        return result(None, f"not evaluated: {err}")
    trace = np.asarray(trace_list, dtype=np.float64)
    value = float(trace.min()) if is_always else float(trace[0])
    t_end = int(grid[-1]) + (int(grid[1] - grid[0]) if grid.size > 1 else 0)
    windows = violation_windows(trace, g, t_end) if is_always or not value >= 0 else ()
    shown = f"{formula.source.strip()}"
    when = f"; evaluated from {g[0] / 1e9:g} s (first tick with every signal)" if start else ""
    if not math.isfinite(value):
        return result(None, f"{shown}: robustness {value} (a bounded operator's window "
                      f"runs past the end of the run){when}", windows)
    state = "holds" if value >= 0 else f"violated in {len(windows)} window" \
        f"{'' if len(windows) == 1 else 's'}"
    return result(value, f"{shown}: {state}{when}", windows)
