"""Specification metrics: robustness values and violation windows against hand computations,
on plain arrays (rtamt's discrete time on the tick grid) and on a synthetic recording read
back through the scoring path (ground truth, held topics, ``topic(...)`` fields)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from harness.frames import load_frames
from harness.metrics.specs import held, spec_metric, tick_grid, violation_windows
from harness.scenario import Scenario, scenario_from_mapping
from harness.scenario.specs import SignalContext, parse_formula
from harness.scoring import spec_fields, spec_metrics
from tests.conftest import ModuleTmp
from tests.metrics.synthbag import ROI, SynthSpec, character_xy, forklift_xy, write_synthetic_bag

HZ = 60
CTX = SignalContext(objects={"forklift", "worker"}, zones={"loading_roi"},
                    routed={"forklift"}, tick_hz=HZ)


def test_tick_grid_and_sample_and_hold() -> None:
    grid = tick_grid(50_000_000, 60)
    assert grid.tolist() == [0, 16666666, 33333333, 50000000]  # floor(k * 1e9 / 60)
    # a tick stamped floor(k * 1e9 / hz) is on the grid, one ns before it is not
    assert tick_grid(1_983_333_333, 60).size == 120 and tick_grid(1_983_333_332, 60).size == 119
    # the last sample at or before each tick; before the first one: `before`
    v = held(np.array([16666666, 40000000]), np.array([1.0, 2.0]), grid)
    assert np.isnan(v[0]) and v[1:].tolist() == [1.0, 1.0, 2.0]
    assert held(np.zeros(0, np.int64), np.zeros(0), grid, before=0.0).tolist() == [0.0] * 4


def test_always_robustness_is_the_minimum_and_windows_are_where_the_body_is_negative() -> None:
    n = 120
    grid = tick_grid(1_000_000_000 * (n - 1) // HZ, HZ)
    c = np.full(n, 2.0)
    c[30:45] = 0.2  # below 0.5 from tick 30 to 44
    c[100:] = 0.4  # and from tick 100 to the end
    f = parse_formula("always (clearance(forklift, worker) >= 0.5)", CTX)
    m = spec_metric("keep_clear", f, {"s0": c}, grid)
    assert m.name == "spec.keep_clear.robustness" and m.unit == "m" and m.group == "spec"
    assert m.value == pytest.approx(0.2 - 0.5) and m.verdict == "FAIL"
    end = int(grid[-1]) + int(grid[1])
    assert m.windows == ((grid[30] / 1e9, grid[45] / 1e9), (grid[100] / 1e9, end / 1e9))
    ok = spec_metric("keep_clear", f, {"s0": np.full(n, 0.75)}, grid, required=False)
    assert ok.value == pytest.approx(0.25) and ok.windows == () and ok.verdict is None


@pytest.mark.parametrize(("alarm_tick", "holds"), [(40, True), (41, False)])
def test_a_bounded_eventually_counts_whole_ticks(alarm_tick: int, holds: bool) -> None:
    """``eventually[0, 0.5]`` at 60 Hz reaches 30 ticks ahead: an alarm 30 ticks after the
    worker enters holds, 31 ticks after does not."""
    n = 90
    grid = tick_grid(1_000_000_000 * (n - 1) // HZ, HZ)
    zone = np.where((np.arange(n) >= 10) & (np.arange(n) < 20), 1.0, -1.0)
    alarm = np.where(np.arange(n) >= alarm_tick, 1.0, -1.0)
    f = parse_formula("always (in_zone(worker, loading_roi) -> eventually[0, 0.5] alarm)", CTX)
    m = spec_metric("react", f, {"s0": zone, "s1": alarm}, grid)
    assert m.value == (1.0 if holds else -1.0) and m.unit == ""
    # violated: at the entry tick only (tick 11 sees the alarm at 41)
    assert m.windows == (() if holds else ((grid[10] / 1e9, grid[11] / 1e9),))


def test_other_formulas_have_windows_only_when_violated() -> None:
    n = 60
    grid = tick_grid(1_000_000_000 * (n - 1) // HZ, HZ)
    up = np.where(np.arange(n) >= 20, 1.0, -1.0)
    f = parse_formula("eventually alarm", CTX)
    assert spec_metric("e", f, {"s0": up}, grid).windows == ()
    never = spec_metric("e", f, {"s0": np.full(n, -1.0)}, grid)
    assert never.value == -1.0 and never.windows == ((0.0, (int(grid[-1]) + 16666666) / 1e9),)


def test_evaluation_starts_where_every_signal_has_a_value() -> None:
    n = 10
    grid = tick_grid(1_000_000_000 * (n - 1) // HZ, HZ)
    s = np.array([math.nan, math.nan, 3.0, 3.0, 0.5, 3.0, 3.0, 3.0, 3.0, 3.0])
    f = parse_formula("always (speed(forklift) <= 1)", CTX)
    m = spec_metric("slow", f, {"s0": s}, grid)
    assert m.value == pytest.approx(-2.0)
    end = int(grid[-1]) + int(grid[1])
    assert m.windows == ((grid[2] / 1e9, grid[4] / 1e9), (grid[5] / 1e9, end / 1e9))
    assert "evaluated from 0.0333333 s" in m.detail
    none = spec_metric("slow", f, {"s0": np.full(n, math.nan)}, grid)
    assert none.value is None and none.verdict == "FAIL" and "never has one" in none.detail
    gone = spec_metric("slow", f, {}, grid, undefined={"s0": "/x: not in the recording"})
    assert gone.value is None and "speed(forklift): /x: not in the recording" in gone.detail


@pytest.mark.parametrize(("formula", "words"), [
    ("always (speed(forklift) / 0 > 1)", "float division by zero"),
    ("always (sqrt(speed(forklift)) > 1)", "math domain error")])
def test_arithmetic_that_fails_on_the_values_leaves_the_spec_not_evaluated(
        formula: str, words: str) -> None:
    grid = tick_grid(1_000_000_000, HZ)
    m = spec_metric("x", parse_formula(formula, CTX), {"s0": np.full(grid.size, -2.0)}, grid)
    assert m.value is None and m.verdict == "FAIL"
    assert m.detail == f"not evaluated: rtamt cannot evaluate it on this run: {words}"


def test_violation_windows_of_an_empty_or_all_negative_trace() -> None:
    grid = np.array([0, 10, 20], dtype=np.int64)
    assert violation_windows(np.array([1.0, 0.0, 2.0]), grid, 30) == ()
    assert violation_windows(np.array([-1.0, -1.0, -1.0]), grid, 30) == ((0.0, 3e-8),)


# --------------------------------------------------------------------------- a recording

DURATION = 6.0


@pytest.fixture(scope="module")
def synth(module_tmp: ModuleTmp) -> Path:
    path = module_tmp("specs") / "bag"
    write_synthetic_bag(path, SynthSpec(duration_s=DURATION, n_characters=1))
    return path


def _scenario(*specs: tuple[str, str]) -> Scenario:
    return scenario_from_mapping({
        "format_version": 1, "name": "synth", "duration": DURATION, "srr_gt": True,
        "robots": [{"name": "forklift", "model": "forklift"}],
        "routes": {"r": {"waypoints": [[3.0, 0.0], [21.0, 0.0]]}},
        "workers": [{"route": [[10.0, -4.0], [10.0, 4.0]]}],
        "zones": {"loading_roi": [list(p) for p in ROI]},
        "scoring": {"control": {"robot": "forklift", "route": "r"}},
        "specs": [{"name": n, "formula": f} for n, f in specs]})


def test_spec_metrics_on_a_recording_match_the_closed_form(synth: Path) -> None:
    sc = _scenario(
        ("clear", "always (clearance(forklift, character_0) >= 3)"),
        ("slow", "always (speed(forklift) <= 1.0)"),
        ("odom", "always (topic('/odom', 'twist.twist.linear.x') < 2)"),
        ("zone", "eventually (in_zone(character_0, loading_roi))"),
        ("alarm", "always (alarm)"),
        ("nofield", "always (topic('/odom', 'twist.twist.linear.q') < 2)"),
        ("route", "always (tracking_error(forklift) < 0.1)"))
    assert spec_fields(sc) == [("/odom", "twist.twist.linear.x"), ("/safety/alarm", "data"),
                               ("/odom", "twist.twist.linear.q")]
    frames = load_frames(synth, fields=spec_fields(sc))
    m = {r.name.split(".")[1]: r for r in spec_metrics(sc, frames)}
    # the grid: every tick the bag has, t_k = floor(k * 1e9 / 60)
    n = round(DURATION * HZ)
    t = (np.arange(n) * 1_000_000_000 // HZ) / 1e9
    fx = np.array([forklift_xy(x)[0] for x in t])
    cx, cy = np.array([character_xy(0, x) for x in t]).T
    clearance = np.hypot(fx - cx, cy) - 1.23 - 0.25  # forklift footprint, worker radius
    assert m["clear"].value == pytest.approx(float(clearance.min()) - 3.0, abs=1e-9)
    low = np.flatnonzero(clearance < 3.0)
    assert low.size and m["clear"].windows[0][0] == pytest.approx(t[low[0]])
    assert len(m["clear"].windows) == len(np.flatnonzero(np.diff(low) > 1)) + 1
    # ground-truth speed by backward difference: 1.5 m/s from the second tick on
    assert m["slow"].value == pytest.approx(1.0 - 1.5, abs=1e-6)
    assert "evaluated from 0.0166667 s" in m["slow"].detail
    assert m["odom"].value == pytest.approx(2.0 - 1.5) and m["odom"].unit == ""
    inside = [(10 <= x <= 15) and (-3 <= y <= 3) for x, y in zip(cx, cy, strict=True)]
    assert m["zone"].value == (1.0 if any(inside) else -1.0)
    assert m["route"].value == pytest.approx(0.1) and m["route"].unit == "m"
    # a signal the recording cannot give: not evaluated, which fails a required spec
    assert m["alarm"].value is None and m["alarm"].verdict == "FAIL"
    assert "alarm: /safety/alarm: not in the recording" in m["alarm"].detail
    assert m["nofield"].value is None
    assert "nav_msgs/msg/Odometry twist.twist.linear.q: no field 'q'" in m["nofield"].detail


def test_muted_is_false_before_its_first_message(synth: Path) -> None:
    sc = _scenario(("m", "always (not muted)"))
    frames = load_frames(synth, fields=spec_fields(sc))
    (m,) = spec_metrics(sc, frames)
    first_true = frames.muted[frames.muted["value"]]["t_ns"]
    if first_true.empty:
        assert m.value == 1.0
    else:
        assert m.value == -1.0 and m.windows[0][0] == pytest.approx(first_true.iloc[0] / 1e9)
