"""A run that fails an absolute criterion of the verdict (a required spec, the safety match
rate's FAIL band, a route goal not reached) does not become the baseline unless asked with
``--allow-failing``: ``srr baseline bless``, ``srr run --update-baseline`` and
``srr suite --update-baselines`` share the rule (:func:`harness.run.baselines.blessing_refusal`).
A run that is FAIL only for want of a baseline is blessed as before."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.cli import main
from harness.run.baselines import blessing_refusal
from harness.run.summary import RunSummary

DATA = Path(__file__).resolve().parents[1] / "run" / "data" / "run" / "summary.json"
DOCK = Path(__file__).resolve().parents[2] / "scenarios" / "dock_empty.yaml"
# the monitor's tripwire with the whole dock on its inside: it mutes from the start, and
# the safety match rate falls to 0 % (its FAIL band)
WHOLE_ROOM_INSIDE = {"systems_under_test.safety_monitor.params.tripwire": [[-20, 3], [-20, -3]],
                     "systems_under_test.safety_monitor.params.inside": "left"}
SETS = [a for k, v in WHOLE_ROOM_INSIDE.items() for a in ("--set", f"{k}={json.dumps(v)}")]
SHORT = ["--duration", "2", "-q", "--no-video"]


def _summary(**changes: object) -> RunSummary:
    """A recorded run's summary (FAIL: its route goal not reached), with a violated required
    spec added, and ``changes``."""
    data = json.loads(DATA.read_text())
    data |= {"verdict": "FAIL", "exit_code": 1, "reasons": ["control.goal_reached: ..."]}
    data["metrics"].append({"name": "spec.keep_clear", "value": -0.25, "unit": "m",
                            "direction": "higher", "group": "spec", "windows": [],
                            "detail": "G(clearance > 0.5) fails at 3.2 s", "verdict": "FAIL"})
    return RunSummary.from_json(data | changes)


def test_the_refusal_names_every_failed_criterion() -> None:
    assert blessing_refusal(_summary()) == (
        "the run fails absolute criteria (control.goal_reached: the robot did not reach the "
        "end of its route; spec.keep_clear: required spec violated (robustness -0.25)), and "
        "every later run would FAIL against it; add --allow-failing to bless it anyway")
    assert blessing_refusal(_summary(), allow_failing=True) is None


def test_allow_failing_never_lifts_the_refusal_of_an_invalid_or_interrupted_run() -> None:
    invalid = _summary(verdict="INVALID", exit_code=3, reasons=["health topic_rate:/clock"])
    cut = _summary(verdict="INTERRUPTED", exit_code=130, interrupted=True, reasons=[])
    for summary, said in ((invalid, "INVALID (health topic_rate:/clock)"),
                          (cut, "INTERRUPTED (no reason recorded)")):
        assert blessing_refusal(summary, allow_failing=True) == (
            f"the run is {said}; only a valid, complete run can become the baseline")


def test_a_run_failing_only_for_want_of_a_baseline_may_be_blessed() -> None:
    data = json.loads(DATA.read_text())
    for m in data["metrics"]:
        if m["name"] == "control.goal_reached":
            m["value"] = 1.0
    data |= {"verdict": "FAIL", "reasons": ["no baseline at /x.json: bless one with ..."]}
    assert blessing_refusal(RunSummary.from_json(data)) is None


@pytest.mark.parametrize(("argv", "line"), [
    (["run", str(DOCK), "--allow-failing"], "srr run: --allow-failing: only with "
     "--update-baseline"),
    (["suite", str(DOCK), "--allow-failing"], "srr suite: --allow-failing: only with "
     "--update-baselines"),
])
def test_allow_failing_without_a_bless_is_refused(
        argv: list[str], line: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    assert capsys.readouterr().err.splitlines()[-1] == line


@pytest.mark.slow
def test_run_suite_and_bless_agree_on_a_failing_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bl = tmp_path / "bl"
    run = tmp_path / "run"
    # srr run --update-baseline: written out, judged, not blessed
    assert main(["run", str(DOCK), *SHORT, *SETS, "--baselines", str(bl), "--out", str(run),
                 "--update-baseline", "--reason", "try"]) == 1
    said = capsys.readouterr()
    assert "verdict: FAIL" in said.out and "blessed" not in said.out
    refusal = ("not blessed: the run fails an absolute criterion (safety.match_rate 0.0 % is "
               "below 80 % (FAIL band)), and every later run would FAIL against it; add "
               "--allow-failing to bless it anyway")
    assert said.err.splitlines()[-1] == f"srr run: {run}: {refusal}", said.err
    assert not bl.exists()
    # srr baseline bless: the same words; with --allow-failing, blessed
    assert main(["baseline", "bless", str(run), "--reason", "x", "--baselines", str(bl)]) == 2
    assert capsys.readouterr().err.splitlines() == [f"srr baseline bless: {run}: {refusal}"]
    assert main(["baseline", "bless", str(run), "--reason", "known bug", "--baselines",
                 str(bl), "--allow-failing"]) == 0
    assert capsys.readouterr().out.strip() == f"blessed {run} as {bl / 'dock_empty.json'}"
    # srr suite --update-baselines: the run is judged, not blessed, and the outputs say why
    suite = tmp_path / "suite.yaml"
    suite.write_text(json.dumps({"suite": "s", "scenarios": [{"path": str(DOCK), "set": {
        "duration": 2, **WHOLE_ROOM_INSIDE}}]}))
    fresh = tmp_path / "fresh"
    assert main(["suite", str(suite), "--jobs", "1", "-q", "--out", str(tmp_path / "out"),
                 "--baselines", str(fresh), "--update-baselines", "--reason", "nightly",
                 "--summary-md", str(tmp_path / "pr.md")]) == 1
    err = capsys.readouterr().err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    refused = summary["baselines_blessed"]["not_blessed"]
    assert len(refused) == 1 and refused[0].endswith(refusal), refused
    assert summary["baselines_blessed"]["written"] == [] and not fresh.exists()
    assert f"srr suite: {refused[0]}" in err.splitlines()
    assert "**Not blessed** (1):" in (tmp_path / "pr.md").read_text()
