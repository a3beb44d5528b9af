"""A run's directory settled by the suite's process after its worker ended without a summary:
nothing there at all, or a recording that cannot be recovered."""

from __future__ import annotations

import io
import json
from dataclasses import replace
from pathlib import Path

import pytest
from mcap.writer import Writer

from harness import api, runmarker
from harness.suite.plan import RunSpec
from harness.suite.results import RunOutcome, group_runs, outcome_of
from harness.suite.unfinished import settle
from harness.summary import read_summary

FORKLIFT = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"


def _spec() -> RunSpec:
    return RunSpec(id="f#1", group="f", entry="f", scenario="forklift_warehouse",
                   scenario_file=str(FORKLIFT), overrides=("duration=2", "seed=11"), params=(),
                   sweep=False, repeat=1, repeats=1, timeout_s=5.0, run_dir="runs/f/nominal/r1",
                   renders=False)


def test_a_run_that_left_nothing_gets_its_directory(tmp_path: Path) -> None:
    run = tmp_path / "runs" / "f" / "nominal" / "r1"
    settled = settle(run, _spec(), "timed out after 5 s of wall-clock time and was stopped")
    assert settled.written and "before its first tick" in str(settled.note)
    summary = read_summary(run)
    assert summary["verdict"] == "INVALID" and summary["exit_code"] == 3
    assert summary["seed"] == 11 and summary["duration_s"] == 2  # the run's own overrides
    assert summary["reasons"] == ["health recording_complete: timed out after 5 s of "
                                  "wall-clock time and was stopped; it ended before its first "
                                  "tick: nothing was recorded"]
    assert summary["topics"] == {} and summary["metrics"] == []
    assert api.load(run / "scenario.yaml").seed == 11
    assert "health.recording_complete" in (run / "junit.xml").read_text()


def test_a_recording_that_cannot_be_recovered_is_said_so(tmp_path: Path) -> None:
    run = tmp_path / "r1"
    (run / "bag").mkdir(parents=True)
    (run / "bag" / "bag.mcap").write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 5)  # cut in its header
    runmarker.mark(run, "recording", scenario_file=str(FORKLIFT), command="srr run ...")
    settled = settle(run, _spec(), "the worker crashed: killed by signal SIGKILL")
    assert settled.written and "could not be recovered" in str(settled.note)
    summary = json.loads((run / "summary.json").read_text())
    assert summary["verdict"] == "INVALID"
    assert summary["reasons"][0].startswith("health recording_complete: the worker crashed: "
                                            "killed by signal SIGKILL; what it recorded could "
                                            "not be recovered (")
    assert runmarker.read(run) is None  # settled: no longer in progress
    assert (run / "bag" / "bag.mcap").read_bytes().startswith(b"\x89MCAP0")  # left as it was


def test_a_finished_run_is_left_alone(tmp_path: Path) -> None:
    run = tmp_path / "r1"
    run.mkdir()
    (run / "summary.json").write_text('{"verdict": "INTERRUPTED"}')
    assert settle(run, _spec(), "the worker exited with status 130").note is None
    assert sorted(p.name for p in run.iterdir()) == ["summary.json"]
    assert (run / "summary.json").read_text() == '{"verdict": "INTERRUPTED"}'


def test_a_worker_stopped_by_ctrl_c_before_its_first_tick_is_interrupted(tmp_path: Path
                                                                          ) -> None:
    """A worker that exits 130 (Ctrl-C or SIGTERM) without a summary was interrupted, not
    broken: INTERRUPTED, exit 130, in the outcome and in the summary the suite writes."""
    spec = _spec()
    out = outcome_of(spec, tmp_path, exit_code=130, error=None, wall_s=0.4)
    assert (out.verdict, out.exit_code) == ("INTERRUPTED", 130)
    assert out.reasons[0] == "interrupted (Ctrl-C or SIGTERM) before it wrote summary.json"
    summary = read_summary(tmp_path / spec.run_dir)
    assert (summary["verdict"], summary["exit_code"]) == ("INTERRUPTED", 130)
    # the same exit status at the run's timeout is the suite's doing: INVALID, timed out
    late = outcome_of(replace(spec, run_dir="runs/f/nominal/r2"), tmp_path, exit_code=130,
                      error=None, wall_s=5.0, timed_out=True)
    assert (late.verdict, late.exit_code) == ("INVALID", 3)
    assert late.reasons[0].startswith("timed out after 5 s")


def _repeat(k: int, verdict: str, digest: str | None) -> RunOutcome:
    spec = replace(_spec(), id=f"f#{k}", repeat=k, repeats=4, run_dir=f"runs/f/nominal/r{k}")
    return RunOutcome(spec=spec, verdict=verdict, exit_code={"PASS": 0}.get(verdict, 130),
                      reasons=(), wall_s=1.0, run_dir=spec.run_dir, report=None, log=None,
                      digest=digest)


def test_interrupted_repeats_do_not_make_a_group_flaky(tmp_path: Path) -> None:
    """Repeats stopped by Ctrl-C (a shorter recording, or none) are no disagreement between
    repeats: the group is INTERRUPTED, not FLAKY; two finished repeats that differ still are."""
    (group,) = group_runs([_repeat(1, "PASS", "a" * 64), _repeat(2, "PASS", "a" * 64),
                           _repeat(3, "INTERRUPTED", "b" * 64),
                           _repeat(4, "INTERRUPTED", None)], tmp_path)
    assert (group.verdict, group.flaky) == ("INTERRUPTED", False)
    assert not any(r.startswith("flaky") for r in group.reasons)
    (group,) = group_runs([_repeat(1, "PASS", "a" * 64), _repeat(2, "FAIL", "a" * 64),
                           _repeat(3, "INTERRUPTED", None)], tmp_path)
    assert (group.verdict, group.flaky) == ("FLAKY", True)
    assert group.flaky_detail is not None and group.flaky_detail["verdicts"] == ["PASS", "FAIL"]
    assert group.reasons[0].startswith("flaky over 2 repeats (PASS / FAIL)")


def test_a_worker_stopped_after_its_loop_keeps_its_recording(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C while the run is scored (after its loop): the worker says the run's directory
    holds its recording, and the suite recovers every message of it, INTERRUPTED."""
    from harness.run import record
    from harness.suite.worker import run_job

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(record, "_score", interrupted)
    spec = _spec()
    job = spec.job()
    ended = run_job(job, tmp_path)
    assert (ended["exit_code"], ended["error"]) == (
        130, "interrupted before the run's summary was written")
    monkeypatch.undo()
    out = outcome_of(spec, tmp_path, exit_code=ended["exit_code"], error=ended["error"],
                     wall_s=1.0)
    assert (out.verdict, out.exit_code) == ("INTERRUPTED", 130)
    assert "recorded messages were recovered" in " ".join(out.reasons)
    summary = read_summary(tmp_path / spec.run_dir)
    assert summary["recovered"] and sum(t["count"] for t in summary["topics"].values()) > 0


def test_a_run_killed_before_its_first_chunk_recorded_nothing(tmp_path: Path) -> None:
    run = tmp_path / "r1"
    (run / "bag").mkdir(parents=True)
    header = io.BytesIO()
    Writer(header).start(profile="ros2", library="srr")  # the MCAP header, no chunk
    (run / "bag" / "bag.mcap").write_bytes(header.getvalue())
    runmarker.mark(run, "recording", scenario_file=str(FORKLIFT), command="srr run ...")
    settled = settle(run, _spec(), "the worker crashed: killed by signal SIGKILL")
    assert settled.written, settled
    assert "it ended before its first chunk was written: nothing was recorded (bag.mcap: " \
        in str(settled.note), settled
    assert json.loads((run / "summary.json").read_text())["topics"] == {}
