"""The comparison engine: statuses by direction, tolerances by name/glob/unit, verdicts."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.metrics.types import HealthResult, MetricResult
from harness.regression import (
    Baseline,
    BaselineMetric,
    compare,
    decide,
    load_baseline,
    save_baseline,
    tolerance_for,
)
from harness.scenario.schema import ToleranceSpec


def _m(name: str, value: float | None, unit: str = "m", direction: str = "lower") -> MetricResult:
    return MetricResult(name, value, unit, direction, "control")  # type: ignore[arg-type]


def _baseline(**values: tuple[float | None, str, str]) -> Baseline:
    return Baseline(scenario="s", metrics={k.replace("__", "."): BaselineMetric(*v)
                                           for k, v in values.items()},
                    topics={}, digest="", seed=0, versions={}, blessed_by="t", reason="r",
                    blessed_at="", source_run="")


def test_statuses_follow_direction_and_tolerance() -> None:
    base = _baseline(control__xte=(0.20, "m", "lower"), safety__match=(97.0, "%", "higher"),
                     control__dist=(30.0, "m", "none"), control__gone=(1.0, "m", "lower"))
    metrics = [_m("control.xte", 0.30), _m("safety.match", 99.5, "%", "higher"),
               _m("control.dist", 30.01, "m", "none"), _m("control.fresh", 1.0)]
    cmp = compare(metrics, base, {})
    by = {e.name: e for e in cmp.entries}
    # m: max(0.05, 5 % of 0.20) = 0.05 allowed; +0.10 is worse → regressed
    assert by["control.xte"].status == "regressed"
    assert by["control.xte"].tolerance == pytest.approx(0.05)
    assert by["control.xte"].delta == pytest.approx(0.10)
    assert by["safety.match"].status == "improved"  # +2.5 % beyond the 1 % tolerance
    assert by["control.dist"].status == "ok"  # 0.01 m within max(0.05, 1.5) m
    assert by["control.fresh"].status == "new"
    assert by["control.gone"].status == "missing"
    assert [e.name for e in cmp.regressions] == ["control.xte", "control.gone"]
    assert cmp.entries[0].name == "control.xte"  # regressions first


def test_higher_is_better_regresses_downwards_only() -> None:
    base = _baseline(p__recall=(0.9, "ratio", "higher"))
    assert compare([_m("p.recall", 0.85, "ratio", "higher")], base, {}).regressed
    assert not compare([_m("p.recall", 0.95, "ratio", "higher")], base, {}).regressed
    assert not compare([_m("p.recall", 0.895, "ratio", "higher")], base, {}).regressed


def test_undefined_value_is_a_regression() -> None:
    base = _baseline(control__time_to_goal=(25.0, "s", "lower"))
    cmp = compare([_m("control.time_to_goal", None, "s")], base, {})
    assert cmp.entries[0].status == "regressed"
    assert "undefined" in cmp.entries[0].describe()


def test_tolerance_lookup_exact_then_most_specific_glob_then_unit() -> None:
    tols = {"perception.*": ToleranceSpec(abs=0.2), "perception.position_error_*":
            ToleranceSpec(abs=0.1), "perception.mota": ToleranceSpec(rel=0.5)}
    assert tolerance_for("perception.mota", "ratio", tols).rel == 0.5
    assert tolerance_for("perception.position_error_p95", "m", tols).abs == 0.1
    assert tolerance_for("perception.recall", "ratio", tols).abs == 0.2
    assert tolerance_for("control.xte_max", "m", tols).abs == 0.05  # unit default


def test_describe_names_metric_value_baseline_and_tolerance() -> None:
    base = _baseline(safety__lag_p95=(0.2, "s", "lower"))
    (e,) = compare([_m("safety.lag_p95", 0.9, "s")], base, {}).entries
    text = e.describe()
    for part in ("safety.lag_p95", "0.9 s", "baseline 0.2 s", "tolerance ±0.1", "regressed"):
        assert part in text


def test_verdict_precedence() -> None:
    base = _baseline(a=(1.0, "m", "lower"))
    bad = compare([_m("a", 2.0)], base, {})
    good = compare([_m("a", 1.0)], base, {})
    sick = [HealthResult("clock_monotonic", False, "went backwards at 3.0 s")]
    assert decide(sick, [_m("a", 2.0)], bad, None).name == "INVALID"
    assert decide(sick, [], bad, None).exit_code == 3
    assert decide([], [_m("a", 2.0)], bad, None).name == "REGRESSED"
    assert decide([], [_m("a", 1.0)], good, None).name == "PASS"
    no_base = decide([], [_m("a", 1.0)], None, "no baseline at baselines/s.json")
    assert no_base.name == "FAIL" and "no baseline" in no_base.reasons[0]
    missed = decide([], [MetricResult("control.goal_reached", 0.0, "bool", "higher",
                                      "control")], None, None)
    assert missed.name == "FAIL"


def test_nothing_compared_is_never_a_pass() -> None:
    # no scoring at all: recorded, not judged
    unscored = decide([HealthResult("clock_monotonic", True, "ok")], [], None, "no baseline")
    assert (unscored.name, unscored.exit_code) == ("UNSCORED", 1)
    assert "nothing was scored" in unscored.reasons[0]
    # a baseline that holds none of the run's metrics: an empty comparison
    other = compare([_m("b", 1.0), _m("c", 2.0)], _baseline(a=(1.0, "m", "lower")), {})
    assert {e.status for e in other.entries} == {"new", "missing"}
    empty = compare([_m("b", 1.0)], _baseline(), {})
    assert [e.status for e in empty.entries] == ["new"]
    verdict = decide([], [_m("b", 1.0)], empty, None)
    assert (verdict.name, verdict.exit_code) == ("FAIL", 1)
    assert "holds none of this run's 1 metrics" in verdict.reasons[0]


def test_goal_not_reached_fails_for_every_scored_robot() -> None:
    metrics = [MetricResult("control.lift_a.goal_reached", 1.0, "bool", "higher", "control"),
               MetricResult("control.lift_b.goal_reached", 0.0, "bool", "higher", "control")]
    base = _baseline(control__lift_a__goal_reached=(1.0, "bool", "higher"),
                     control__lift_b__goal_reached=(0.0, "bool", "higher"))
    verdict = decide([], metrics, compare(metrics, base, {}), None)
    assert verdict.name == "FAIL"
    assert verdict.reasons == ("control.lift_b.goal_reached: the robot did not reach the end "
                               "of its route",)


def test_save_and_load_round_trip(tmp_path: Path) -> None:
    summary = {"scenario": "s", "seed": 3, "digest": "d", "versions": {"srr": "0"},
               "metrics": [{"name": "a", "value": 1.5, "unit": "m", "direction": "lower"}],
               "topics": {"/clock": {"count": 5, "sha256": "x", "type": "T"}}}
    path = tmp_path / "baselines" / "s.json"
    saved = save_baseline(path, summary, reason="first green run", source_run="r1")
    loaded = load_baseline(path)
    assert loaded == saved
    assert loaded is not None and loaded.metrics["a"].value == 1.5
    assert json.loads(path.read_text())["reason"] == "first green run"
    assert load_baseline(tmp_path / "none.json") is None
