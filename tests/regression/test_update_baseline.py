"""``srr run --update-baseline``: the run is judged against the baseline it replaces (RECORDED
when there is none yet), written out whole, and only then blessed; an invalid run is written
out and not blessed; a malformed baseline is refused before the run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.cli import main

DOCK = Path(__file__).resolve().parents[2] / "scenarios" / "dock_empty.yaml"
SHORT = ["--duration", "2", "-q", "--no-video"]
LATE_TRIPWIRE = ["--set", "systems_under_test.safety_monitor.params.tripwire=[[-20,3],[-20,-3]]",
                 "--set", "systems_under_test.safety_monitor.params.inside=left"]

pytestmark = pytest.mark.slow


def _run(out: Path, baselines: Path, *extra: str) -> int:
    return main(["run", str(DOCK), *SHORT, "--baselines", str(baselines), "--out", str(out),
                 "--update-baseline", "--reason", "test", *extra])


def test_update_baseline_judges_against_the_baseline_it_replaces(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bl = tmp_path / "bl"
    path = bl / "dock_empty.json"
    assert _run(tmp_path / "first", bl) == 0  # nothing to compare with: recorded, blessed
    out = capsys.readouterr().out
    assert "verdict: RECORDED" in out and f"blessed {tmp_path / 'first'} as {path}" in out
    assert f"no baseline at {path} before this run: it becomes the first one" in out
    first = json.loads(path.read_text())
    # a change that regresses: the run says so against the old baseline; its match rate is
    # in the FAIL band, so it replaces it only when blessed with --allow-failing
    assert _run(tmp_path / "second", bl, *LATE_TRIPWIRE) == 1
    said = capsys.readouterr()
    assert "verdict: REGRESSED" in said.out
    assert "safety.match_rate: 0 % vs baseline 100 %" in said.out
    assert f"srr run: {tmp_path / 'second'}: not blessed: the run fails an absolute " \
        "criterion (safety.match_rate 0.0 % is below 80 % (FAIL band))" in said.err
    assert json.loads(path.read_text())["digest"] == first["digest"]
    assert main(["baseline", "bless", str(tmp_path / "second"), "--reason", "test",
                 "--allow-failing"]) == 0
    assert f"blessed {tmp_path / 'second'} as {path}" in capsys.readouterr().out
    second = json.loads((tmp_path / "second" / "summary.json").read_text())
    assert second["verdict"] == "REGRESSED" and second["baseline"]["digest"] == first["digest"]
    assert json.loads(path.read_text())["digest"] == second["digest"] != first["digest"]


def test_an_invalid_run_is_written_out_and_not_blessed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bl = tmp_path / "bl"
    assert _run(tmp_path / "first", bl) == 0
    capsys.readouterr()
    before = (bl / "dock_empty.json").read_bytes()
    md = tmp_path / "pr.md"
    run = tmp_path / "invalid"
    assert _run(run, bl, "--set", "scoring.health.sut_outputs={/perception/tracks: 0.01}",
                "--summary-md", str(md)) == 3
    said = capsys.readouterr()
    assert "verdict: INVALID" in said.out and "blessed" not in said.out
    assert said.err.strip().splitlines()[-1].startswith(
        f"srr run: {run}: not blessed: the run is INVALID (health "
        "sut_output_alive:/perception/tracks: ")
    assert said.err.strip().endswith("only a valid, complete run can become the baseline")
    assert json.loads((run / "summary.json").read_text())["verdict"] == "INVALID"
    assert (run / "report.html").is_file() and not (run / "incomplete.json").exists()
    assert "INVALID" in md.read_text()
    assert (bl / "dock_empty.json").read_bytes() == before


def test_a_malformed_baseline_is_refused_before_the_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bl = tmp_path / "bl"
    bl.mkdir()
    for text in ("{}", "{bad"):
        (bl / "dock_empty.json").write_text(text)
        out = tmp_path / "r"
        assert main(["run", str(DOCK), *SHORT, "--baselines", str(bl), "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert err.startswith(f"srr run: {bl / 'dock_empty.json'}: not a valid baseline: ")
        assert not out.exists()


def test_a_report_rendered_after_a_re_bless_draws_no_other_runs_reference(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A run judged against one baseline, whose baseline was blessed again since: its page,
    rendered again, does not draw the new baseline's recording against it under the verdict
    judged against the old one; it says why."""
    bl = tmp_path / "bl"
    assert _run(tmp_path / "first", bl) == 0
    late = tmp_path / "late"
    assert main(["run", str(DOCK), *SHORT, "--baselines", str(bl), "--out", str(late),
                 *LATE_TRIPWIRE]) == 1  # REGRESSED against the first
    assert "was blessed again" not in (late / "report.html").read_text()
    assert main(["baseline", "bless", str(late), "--reason", "accept", "--allow-failing"]) == 0
    capsys.readouterr()
    assert main(["report", str(late), "--no-video"]) == 0
    page = (late / "report.html").read_text()
    assert f"the baseline {bl / 'dock_empty.json'} was blessed again after this run was " \
           "judged" in page
