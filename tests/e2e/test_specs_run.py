"""Specs on a real short run: the worker crossing cut to 10 s (forklift near the dock, the
worker walking into the loading ROI at 6.5 s). Robustness and windows are checked against a
hand computation from the recorded ground truth, read back with the independent mcap reader;
the specs change no recorded byte; against a baseline blessed without specs their metrics
are ``new``, a violated required spec fails the run, and the report shows them."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness import api
from tests.conftest import SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded

pytestmark = pytest.mark.slow

CROSSING = SCENARIOS / "dock_worker_crossing.yaml"
SHORT = ["robots.forklift.spawn.position=[7.0, 0.0, 0.0]",
         "routes.dock_approach.waypoints=[[7.0, 0.0], [15.0, 0.0], [21.0, 0.0]]",
         "workers.0.start_delay=4.0"]
SPECS = ('specs=['
         '{name: keep_clear, formula: "always (clearance(forklift, character_0) >= 0.5)"},'
         '{name: too_close, formula: "always (clearance(forklift, character_0) >= 5)"},'
         '{name: alarm_follows_worker, formula: '
         '"always (in_zone(character_0, loading_roi) -> eventually[0, 0.5] alarm)"},'
         '{name: alarm_at_once, required: false, formula: '
         '"always (in_zone(character_0, loading_roi) -> eventually[0, 0.05] alarm)"},'
         '{name: odom_speed, required: false, formula: '
         '"always (topic(\'/odom\', \'twist.twist.linear.x\') <= 1.0)"}]')
DURATION = 10.0
ROI = [(10.0, -3.0), (14.5, -3.0), (14.5, 3.0), (10.0, 3.0)]  # scenarios/dock/scene.yaml


@pytest.fixture(scope="module")
def runs(module_tmp: ModuleTmp) -> tuple[api.RunResult, api.RunResult]:
    root = module_tmp("specs")
    baselines = root / "baselines"
    plain = api.load(CROSSING, duration=DURATION, overrides=SHORT)
    first = api.run_scenario(plain, source=str(CROSSING), out=root / "plain",
                             baselines=baselines, update_baseline=True,
                             update_reason="the short crossing, without specs",
                             allow_failing=True)  # short: the forklift does not reach its goal
    with_specs = api.load(CROSSING, duration=DURATION, overrides=[*SHORT, SPECS])
    second = api.run_scenario(with_specs, source=str(CROSSING), out=root / "specs",
                              baselines=baselines)
    return first, second


def _summary(run: api.RunResult) -> dict[str, Any]:
    return json.loads((run.run_dir / "summary.json").read_text())


def _ground_truth(run_dir: Path) -> tuple[dict[str, np.ndarray], list[tuple[int, bool]]]:
    """``/gt/<name>/tf`` as (t_ns, x, y) rows, and ``/safety/alarm`` (t_ns, value)."""
    gt: dict[str, list[tuple[int, float, float]]] = {}
    alarm: list[tuple[int, bool]] = []
    for topic, _schema, t_ns, msg in decoded(run_dir):
        if topic.startswith("/gt/"):
            tr = msg.transforms[0]
            stamp = tr.header.stamp.sec * 1_000_000_000 + tr.header.stamp.nanosec
            gt.setdefault(topic.split("/")[2], []).append(
                (stamp, tr.transform.translation.x, tr.transform.translation.y))
        elif topic == "/safety/alarm":
            alarm.append((t_ns, bool(msg.data)))
    return {k: np.array(sorted(v)) for k, v in gt.items()}, sorted(alarm)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    out, start = [], None
    for i, m in enumerate([*mask.tolist(), False]):
        if m and start is None:
            start = i
        elif not m and start is not None:
            out.append((start, i))
            start = None
    return out


def test_spec_values_and_windows_match_the_recorded_ground_truth(
        runs: tuple[api.RunResult, api.RunResult]) -> None:
    _, run = runs
    metrics = {m["name"]: m for m in _summary(run)["metrics"]}
    gt, alarm = _ground_truth(run.run_dir)
    fork, worker = gt["forklift"], gt["character_0"]
    assert fork[:, 0].tolist() == worker[:, 0].tolist()  # one pose each per tick
    t = fork[:, 0].astype(np.int64)
    clearance = np.hypot(fork[:, 1] - worker[:, 1], fork[:, 2] - worker[:, 2]) - 1.23 - 0.25
    keep = metrics["spec.keep_clear.robustness"]
    assert keep["value"] == pytest.approx(clearance.min() - 0.5, abs=1e-9) and keep["value"] > 0
    assert keep["verdict"] == "PASS" and keep["windows"] == [] and keep["unit"] == "m"
    close = metrics["spec.too_close.robustness"]
    assert close["value"] == pytest.approx(clearance.min() - 5.0, abs=1e-9) and close["value"] < 0
    assert close["verdict"] == "FAIL"
    tick = int(np.median(np.diff(t)))
    hand = [(t[a] / 1e9, (t[b] if b < t.size else t[-1] + tick) / 1e9)
            for a, b in _runs(clearance < 5.0)]
    assert len(close["windows"]) == len(hand) >= 1
    assert [v for w in close["windows"] for v in w] == pytest.approx(
        [v for w in hand for v in w], abs=1e-6)
    # the alarm reaction: every tick with the worker in the ROI has the alarm (held from
    # its messages, false before the first) within 30 ticks (0.5 s at 60 Hz)
    x, y = worker[:, 1], worker[:, 2]
    inside = (x >= ROI[0][0]) & (x <= ROI[1][0]) & (y >= ROI[0][1]) & (y <= ROI[2][1])
    at = np.searchsorted([a for a, _ in alarm], t, side="right") - 1
    on = np.where(at >= 0, np.array([v for _, v in alarm])[np.clip(at, 0, None)], False)
    assert inside.any(), "the worker never entered the loading ROI"
    for name, ticks in (("alarm_follows_worker", 30), ("alarm_at_once", 3)):
        late = [i for i in np.flatnonzero(inside) if not on[i:i + ticks + 1].any()]
        react = metrics[f"spec.{name}.robustness"]
        assert react["value"] == (-1.0 if late else 1.0) and react["unit"] == "", name
        hand = [(t[a] / 1e9, (t[b] if b < t.size else t[-1] + tick) / 1e9)
                for a, b in _runs(np.isin(np.arange(t.size), late))]
        assert [v for w in react["windows"] for v in w] == pytest.approx(
            [v for w in hand for v in w], abs=1e-6), name
    # the perception's latency: the alarm comes later than 3 ticks, within 30
    assert metrics["spec.alarm_follows_worker.robustness"]["value"] == 1.0
    assert metrics["spec.alarm_at_once.robustness"]["value"] == -1.0
    odom = metrics["spec.odom_speed.robustness"]
    assert odom["verdict"] is None and odom["value"] is not None


def test_specs_change_no_recorded_byte_and_are_new_against_a_baseline_without_them(
        runs: tuple[api.RunResult, api.RunResult]) -> None:
    plain, specs = _summary(runs[0]), _summary(runs[1])
    assert specs["digest"] == plain["digest"]
    assert {k: v["sha256"] for k, v in specs["topics"].items()} == \
        {k: v["sha256"] for k, v in plain["topics"].items()}
    status = {e["name"]: e["status"] for e in specs["comparison"]}
    spec_names = {n for n in status if n.startswith("spec.")}
    assert spec_names == {"spec.keep_clear.robustness", "spec.too_close.robustness",
                          "spec.alarm_follows_worker.robustness",
                          "spec.alarm_at_once.robustness", "spec.odom_speed.robustness"}
    assert {status[n] for n in spec_names} == {"new"}
    assert {s for n, s in status.items() if n not in spec_names} <= {"ok"}
    # the violated required spec fails the run (the baseline has nothing to say about it)
    assert specs["verdict"] == "FAIL" and runs[1].exit_code == 1
    assert any(r.startswith("spec.too_close.robustness: required spec violated")
               for r in specs["reasons"]), specs["reasons"]


def test_the_report_shows_the_spec_metrics_with_their_windows(
        runs: tuple[api.RunResult, api.RunResult]) -> None:
    html = (runs[1].run_dir / "report.html").read_text()
    close = next(m for m in _summary(runs[1])["metrics"]
                 if m["name"] == "spec.too_close.robustness")
    row = html[html.index('data-metric="spec.too_close.robustness"'):]
    row = row[:row.index("</tr>")]
    a, b = close["windows"][0]
    assert f"{a:.2f}–{b:.2f}" in row
    assert "always (clearance(forklift, character_0) &gt;= 5): violated" in row
    assert 'data-metric="spec.keep_clear.robustness"' in html
