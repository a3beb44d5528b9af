"""A replay says what it replays and what it changed (``--set``, ``--sut``): in its console
lines and report, and in ``srr diff``'s console and page when one side is the replay."""

from __future__ import annotations

import html as htmllib
from pathlib import Path

import pytest

from harness import api
from harness.cli import main
from tests.conftest import SCENARIOS

FW = SCENARIOS / "forklift_warehouse.yaml"
SET = "systems_under_test.route_follower.params.speed=1.0"
SUT = "route_follower=harness.sut.route_follower:RouteFollower"


@pytest.mark.slow
def test_a_replay_and_its_diff_say_what_was_replayed_and_changed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a = api.run_scenario(api.load(FW, duration=1.0), source=str(FW), out=tmp_path / "a").run_dir
    b = tmp_path / "b"
    main(["replay", str(a), "--set", SET, "--sut", SUT, "--out", str(b), "-q"])
    changed = f"changed: --set {SET}, --sut {SUT}"
    note = f"open-loop replay of {a} ({changed})"
    assert f"this run is an {note}" in capsys.readouterr().out
    assert note in htmllib.unescape((b / "report.html").read_text())

    page = tmp_path / "diff.html"
    assert main(["diff", str(a), str(b), "--html", str(page)]) == 1  # the speed changed
    out = capsys.readouterr().out
    said = f"B is an open-loop replay of A ({a}; {changed})"
    assert said in out
    assert said in htmllib.unescape(page.read_text())
    # the other way round, and a run that is no replay says nothing of the kind
    main(["diff", str(b), str(a)])
    assert f"A is an open-loop replay of B ({a}; {changed})" in capsys.readouterr().out
    main(["diff", str(a), str(a)])
    assert "open-loop replay" not in capsys.readouterr().out


@pytest.mark.parametrize("into", ["", " into external ROS 2 nodes in lockstep"])
def test_srr_diff_names_the_run_a_replay_plays_back(tmp_path: Path, into: str) -> None:
    """`srr diff A B` with B a replay of A (open loop, or into ROS 2 nodes in lockstep) says
    "B is a … replay … of A"; a replay of a third run names that run's path."""
    from harness.diff.result import RunInfo

    def info(path: Path, replay: str | None) -> RunInfo:
        return RunInfo(path, "dock", 7, "PASS", 3.0, "d", replay)

    a = tmp_path / "a"
    b = info(tmp_path / "b", f"open-loop replay{into} of {a.resolve()} (changed: --set x=1)")
    assert b.describe_replay("B", info(a, None), "A") == (
        f"B is an open-loop replay{into} of A ({a.resolve()}; changed: --set x=1)")
    third = info(tmp_path / "c", None)
    assert b.describe_replay("B", third, "A") == (
        f"B is an open-loop replay{into} of {a.resolve()} (changed: --set x=1)")
