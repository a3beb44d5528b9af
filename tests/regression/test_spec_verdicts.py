"""Spec metrics in the baseline comparison and the verdict: a spec is its own metric, compared
by name (a spec a baseline lacks is ``new``: shown, never a regression, never what makes a
run PASS); a required spec that is violated or cannot be evaluated fails the run whatever
the baseline says; adding specs to a scenario does not change its configuration."""

from __future__ import annotations

from harness import api
from harness.metrics.types import HealthResult, MetricResult
from harness.regression import Baseline, BaselineMetric, compare, config_differences, decide
from harness.scenario import scenario_to_mapping
from tests.conftest import SCENARIOS

OK_HEALTH = [HealthResult("rates", True, "")]


def _spec(name: str, value: float | None, verdict: str | None) -> MetricResult:
    return MetricResult(f"spec.{name}.robustness", value, "m", "higher", "spec",
                        "always (...)", (), verdict)


def _baseline(**values: float) -> Baseline:
    return Baseline(scenario="s", metrics={k.replace("__", "."): BaselineMetric(v, "m", "lower")
                                           for k, v in values.items()},
                    topics={}, digest="", seed=0)


def test_a_spec_the_baseline_lacks_is_new_and_a_held_required_spec_passes() -> None:
    metrics = [MetricResult("control.xte", 0.2, "m", "lower", "control"),
               _spec("keep_clear", 1.5, "PASS")]
    cmp = compare(metrics, _baseline(control__xte=0.2), {})
    assert {e.name: e.status for e in cmp.entries} == {
        "control.xte": "ok", "spec.keep_clear.robustness": "new"}
    assert decide(OK_HEALTH, metrics, cmp, None).name == "PASS"
    # a new spec alone is nothing compared: not a PASS
    only = decide(OK_HEALTH, metrics[1:], compare(metrics[1:], _baseline(), {}), None)
    assert only.name == "FAIL" and "holds none of this run's 1 metrics" in only.reasons[-1]


def test_a_violated_or_unevaluated_required_spec_fails_whatever_the_baseline_says() -> None:
    held_before = _baseline(control__xte=0.2, spec__keep_clear__robustness=-0.4)  # as bad
    for spec, base, words in (
            (_spec("keep_clear", -0.4, "FAIL"), held_before, "violated (robustness -0.4)"),
            (_spec("keep_clear", None, "FAIL"), _baseline(control__xte=0.2), "not evaluated")):
        metrics = [MetricResult("control.xte", 0.2, "m", "lower", "control"), spec]
        cmp = compare(metrics, base, {})
        v = decide(OK_HEALTH, metrics, cmp, None)
        assert v.name == "FAIL" and v.exit_code == 1, v
        assert any(r.startswith("spec.keep_clear.robustness: required spec " + words)
                   for r in v.reasons), v.reasons
    # not required: only compared (same value as the baseline: ok, the run passes)
    informational = [MetricResult("control.xte", 0.2, "m", "lower", "control"),
                     _spec("keep_clear", -0.4, None)]
    cmp = compare(informational, _baseline(control__xte=0.2,
                                           spec__keep_clear__robustness=-0.4), {})
    assert decide(OK_HEALTH, informational, cmp, None).name == "PASS"


def test_specs_are_not_part_of_the_configuration() -> None:
    crossing = scenario_to_mapping(api.load(SCENARIOS / "dock_worker_crossing.yaml"))
    specs = scenario_to_mapping(api.load(SCENARIOS / "dock_worker_crossing_specs.yaml"))
    assert specs["specs"] and not crossing["specs"]
    assert config_differences(crossing, specs) == []
