"""``srr suite --update-baselines`` with two entries of one scenario: entries whose groups
would be blessed into one baseline file under different configurations are refused before
anything runs (the second bless would overwrite the first, which would be MISMATCH from then
on); entries with their own ``baseline:``, or of the same configuration, are blessed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.cli import main

TRUCK = Path(__file__).resolve().parents[2] / "scenarios" / "pallet_truck_mjcf.yaml"
SPEED = "systems_under_test.route_follower.params.speed"


def _suite(tmp_path: Path, *entries: dict[str, object]) -> Path:
    suite = tmp_path / "suite.yaml"
    suite.write_text(json.dumps({"suite": "shared", "scenarios": [
        {"path": str(TRUCK), **e} for e in entries]}), encoding="utf-8")
    return suite


@pytest.mark.parametrize(("entries", "where", "groups"), [
    ([{"name": "short", "set": {"duration": 1}}, {"name": "long", "set": {"duration": 2}}],
     "scenarios[1]", ("long", "short")),
    ([{"name": "a", "set": {"duration": 1}, "sweep": {SPEED: [1.0, 1.2]}},
      {"name": "b", "set": {"duration": 2}, "sweep": {SPEED: [1.2, 1.4]}}],
     "scenarios[1] [speed=1.2]", ("b[speed=1.2]", "a[speed=1.2]")),
])
def test_two_groups_blessed_into_one_baseline_are_refused_before_anything_runs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], entries: list[dict[str, object]],
        where: str, groups: tuple[str, str]) -> None:
    suite = _suite(tmp_path, *entries)
    bl, out = tmp_path / "bl", tmp_path / "out"
    assert main(["suite", str(suite), "--jobs", "1", "-q", "--out", str(out), "--baselines",
                 str(bl), "--update-baselines", "--reason", "try"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2, err  # the plan's warning, then the refusal
    assert err[0].startswith(f"srr suite: warning: {suite}: {where}: {groups[0]} is judged "
                             "against ")
    name = "pallet_truck_mjcf" + ("@speed=1.2" if "[" in groups[0] else "")
    assert err[1].startswith(
        f"srr suite: {suite}: {where}: --update-baselines would bless {groups[0]} into "
        f"{bl.resolve() / name}.json, the baseline it shares with {groups[1]} ")
    assert "(duration: 1.0 → 2.0)" in err[1] and "set: {baseline: NAME}" in err[1]
    assert not out.exists() and not bl.exists()


def test_two_groups_judged_against_one_baseline_are_warned_of_before_anything_runs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Without --update-baselines the suite runs, but one of the two groups would be
    MISMATCH on every run: `srr validate` and the plan say so, naming both and the file."""
    suite = _suite(tmp_path, {"name": "short", "set": {"duration": 1}},
                   {"name": "long", "set": {"duration": 2}},
                   {"name": "own", "set": {"duration": 3, "baseline": "own"}})
    assert main(["validate", str(suite)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"srr validate: warning: {suite}: scenarios[1]: long is judged against "
        f"{TRUCK.parents[1] / 'baselines' / 'pallet_truck_mjcf.json'}, the baseline it shares "
        f"with short ({suite}: scenarios[0]) under another configuration (duration: 1.0 → 2.0): "
        "one of the two is MISMATCH on every run; give one entry its own baseline "
        "(set: {baseline: NAME})"]


@pytest.mark.slow
def test_entries_with_their_own_baseline_or_the_same_configuration_are_blessed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    suite = _suite(tmp_path, {"name": "short", "set": {"duration": 1, "baseline": "short"}},
                   {"name": "long", "set": {"duration": 2}},
                   {"name": "long_again", "timeout": 100, "set": {"duration": 2}})
    bl = tmp_path / "bl"
    code = main(["suite", str(suite), "--jobs", "1", "-q", "--out", str(tmp_path / "out"),
                 "--baselines", str(bl), "--update-baselines", "--allow-failing", "--reason",
                 "try"])
    capsys.readouterr()
    assert code == 1  # judged before the blessing: no baseline yet
    blessed = json.loads((tmp_path / "out" / "summary.json").read_text())["baselines_blessed"]
    assert blessed["written"] == [str(bl.resolve() / "short.json"),
                                  str(bl.resolve() / "pallet_truck_mjcf.json")]
    assert blessed["unchanged"] == [str(bl.resolve() / "pallet_truck_mjcf.json")]
