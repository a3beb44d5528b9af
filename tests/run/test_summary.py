"""The typed run summary: summaries written by srr before :class:`RunSummary` existed (a run
judged against a baseline, an open-loop replay, a run recovered by ``srr recover``; kept in
``data/``, without ``schema_version``) read back typed as version 1 and write back with that
key; a fresh run's summary is the one its result holds; a malformed or newer summary is one
line naming the file and the field."""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from harness import api
from harness.errors import SrrError
from harness.run.summary import SCHEMA_VERSION, RunSummary
from harness.summary import SUMMARY_NAME, read_summary

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("kind", ["run", "replay", "recovered"])
def test_a_summary_of_earlier_srr_reads_and_writes_back_with_its_version(
        kind: str, tmp_path: Path) -> None:
    """Written before ``schema_version`` existed: read as version 1 and written back the same
    but for that key, which a rewrite then keeps byte for byte."""
    before = (DATA / kind / SUMMARY_NAME).read_text()
    assert "schema_version" not in json.loads(before)
    RunSummary.read(DATA / kind).write(tmp_path)
    after = (tmp_path / SUMMARY_NAME).read_text()
    assert json.loads(after) == json.loads(before) | {"schema_version": 1}
    assert after == json.dumps(json.loads(after), indent=2, sort_keys=True) + "\n"
    again = tmp_path / "again"
    again.mkdir()
    RunSummary.read(tmp_path).write(again)
    assert (again / SUMMARY_NAME).read_bytes() == (tmp_path / SUMMARY_NAME).read_bytes()


def test_a_summary_without_its_version_reads_as_version_1(tmp_path: Path) -> None:
    data = json.loads((DATA / "run" / SUMMARY_NAME).read_text())
    without = RunSummary.from_json(data)
    with_1 = RunSummary.from_json(data | {"schema_version": 1})
    assert without == with_1 and "schema_version" not in without.more
    assert without.to_json()["schema_version"] == 1 == SCHEMA_VERSION


def test_typed_parts_of_a_judged_run() -> None:
    s = RunSummary.read(DATA / "run")
    raw = json.loads((DATA / "run" / SUMMARY_NAME).read_text())
    assert (s.scenario, s.seed, s.verdict, s.exit_code) == ("forklift_warehouse", 7,
                                                            "MISMATCH", 1)
    assert s.ok and [h.name for h in s.health] == [h["name"] for h in raw["health"]]
    assert s.baseline is not None and s.baseline.path == raw["baseline"]["path"]
    assert s.baseline.config_differences == tuple(raw["baseline"]["config_differences"])
    assert {n: t.sha256 for n, t in s.topics.items()} == {
        n: t["sha256"] for n, t in raw["topics"].items()}
    assert s.replay_of is None and not s.recovered and s.more == {}


def test_typed_parts_of_a_replay_and_a_recovered_run() -> None:
    rep = RunSummary.read(DATA / "replay")
    assert rep.replay_of is not None and rep.replay_of["mode"] == "open-loop"
    rec = RunSummary.read(DATA / "recovered")
    assert rec.recovered and rec.recovery is not None and rec.verdict == "INVALID"
    assert not rec.ok and all(t.published is None for t in rec.topics.values())


def test_keys_it_does_not_know_are_kept(tmp_path: Path) -> None:
    data = json.loads((DATA / "replay" / SUMMARY_NAME).read_text())
    data["from_a_later_srr"] = {"x": 1}
    s = RunSummary.from_json(data)
    assert s.more == {"from_a_later_srr": {"x": 1}}
    assert s.to_json() == data | {"schema_version": 1}


MALFORMED = [
    ("schema_version", 2, r"schema_version: 2 is newer than this srr reads"),
    ("schema_version", "1", r"schema_version: expected an integer, got '1'"),
    ("reasons", "one reason", r"reasons: expected a list"),
    ("exit_code", "1", r"exit_code: expected an integer, got '1'"),
    ("exit_code", 0.5, r"exit_code: expected an integer, got 0.5"),
    ("seed", "7", r"seed: expected an integer"),
    ("metrics", [{"name": "m", "value": 1.0, "unit": "m", "direction": "sideways"}],
     r"metrics\[0\]\.direction: expected one of 'lower', 'higher', 'none', got 'sideways'"),
]


@pytest.mark.parametrize(("field", "value", "message"), MALFORMED)
def test_a_malformed_or_newer_summary_names_the_file_and_field(
        tmp_path: Path, field: str, value: object, message: str) -> None:
    """The one check of a summary (:func:`check_summary`): what ``srr diff``, ``report``, the
    suite (:func:`read_summary`) and ``replay``, ``baseline bless`` (:meth:`RunSummary.read`)
    read. ``schema_version`` or ``exit_code`` as a string passed the first and not the
    second."""
    data = json.loads((DATA / "replay" / SUMMARY_NAME).read_text())
    data[field] = value
    (tmp_path / SUMMARY_NAME).write_text(json.dumps(data))
    for read in (read_summary, RunSummary.read):
        with pytest.raises(SrrError, match=rf"^{tmp_path / SUMMARY_NAME}: {message}"):
            read(tmp_path)


@pytest.mark.parametrize(("field", "value"), [("schema_version", "1"), ("exit_code", "0")])
def test_every_command_refuses_a_mistyped_summary_in_the_same_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], field: str, value: str) -> None:
    from harness.cli import main

    run = tmp_path / "run"
    shutil.copytree(DATA / "replay", run)
    data = json.loads((run / SUMMARY_NAME).read_text())
    data[field] = value
    (run / SUMMARY_NAME).write_text(json.dumps(data))
    want = f"{run / SUMMARY_NAME}: {field}: expected an integer, got {value!r}"
    for argv in (["report", str(run)], ["diff", str(run), str(run)],
                 ["replay", str(run), "--out", str(tmp_path / "out"), "-q"],
                 ["baseline", "bless", str(run), "--reason", "r", "--baselines",
                  str(tmp_path / "b")]):
        assert main(argv) == 2, argv
        assert capsys.readouterr().err == f"srr {_said(argv)}: {want}\n", argv
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def _drop_sha(d: dict[str, Any]) -> str:
    name = sorted(d["topics"])[0]
    del d["topics"][name]["sha256"]
    return rf"topics\.{re.escape(name)}\.sha256: required field is missing"


def _health_ok_word(d: dict[str, Any]) -> str:
    d["health"][1]["ok"] = "yes"
    return r"health\[1\]\.ok: expected true or false, got 'yes'"


def _no_digest(d: dict[str, Any]) -> str:
    del d["digest"]
    return r"digest: missing \(not an srr run summary\)"


def _null_ticks(d: dict[str, Any]) -> str:
    d["ticks"] = None
    return r"ticks: expected an integer, got null"


@pytest.mark.parametrize("spoil", [_drop_sha, _health_ok_word, _no_digest, _null_ticks])
def test_a_malformed_summary_names_the_field_inside_a_row(
        tmp_path: Path, spoil: Callable[[dict[str, Any]], str]) -> None:
    """The row and the key in it, not just the row: what is missing or of the wrong type."""
    data = json.loads((DATA / "replay" / SUMMARY_NAME).read_text())
    message = spoil(data)
    (tmp_path / SUMMARY_NAME).write_text(json.dumps(data))
    for read in (read_summary, RunSummary.read):
        with pytest.raises(SrrError, match=rf"^{re.escape(str(tmp_path / SUMMARY_NAME))}: "
                           rf"{message}$"):
            read(tmp_path)


def test_the_summary_in_memory_is_what_json_reads_back() -> None:
    """``RunResult.summary`` (``to_json``) equals ``json.load`` of the file: a metric's
    ``windows`` (tuples in :class:`MetricResult`) are lists, as on disk (they were ``()``
    in memory and ``[]`` in the file)."""
    from harness.metrics.types import HealthResult, MetricResult

    base = RunSummary.read(DATA / "run")
    metric = MetricResult("safety.match_rate", 80.0, "%", "higher", "safety", "detail",
                          ((1.0, 2.5), (3.0, 4.0)), "NEAR")
    s = dataclasses.replace(base, metrics=(dataclasses.asdict(metric),
                                           dataclasses.asdict(dataclasses.replace(
                                               metric, name="m", windows=()))),
                            health=(HealthResult("g", True, "ok"),), reasons=("a", "b"),
                            graphs=(("a", "b"),))
    data = s.to_json()
    assert data == json.loads(json.dumps(data))
    assert data["metrics"][0]["windows"] == [[1.0, 2.5], [3.0, 4.0]]
    assert data["metrics"][1]["windows"] == [] and data["graphs"] == [["a", "b"]]


@pytest.mark.slow
def test_a_fresh_run_writes_the_summary_its_result_holds(tmp_path: Path) -> None:
    path = ROOT / "scenarios" / "forklift_warehouse.yaml"
    res = api.run_scenario(api.load(path, duration=0.5), source=str(path), out=tmp_path / "r")
    on_disk = RunSummary.read(res.run_dir)
    assert res.summary == json.loads((res.run_dir / SUMMARY_NAME).read_text())
    assert on_disk.to_json() == res.summary
    assert (on_disk.topics, on_disk.health, on_disk.verdict) == (
        res.run_summary.topics, res.run_summary.health, res.verdict)
    copy = tmp_path / "copy"
    shutil.copytree(res.run_dir, copy)
    on_disk.write(copy)
    assert (copy / SUMMARY_NAME).read_bytes() == (res.run_dir / SUMMARY_NAME).read_bytes()


def test_the_command_reproduces_the_run_from_anywhere(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``summary.json``'s command names every ``--set`` and ``--baselines``, with absolute
    paths: run from another directory (once the run directory is moved away), it records
    the same bytes."""
    import shlex

    from harness.cli import main

    scenario = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(scenario), "--duration", "1", "-q", "--no-video", "--set",
                 "systems_under_test.route_follower.params.speed=0.7", "--baselines", "bl",
                 "--out", "first"]) in (0, 1)
    first = json.loads((tmp_path / "first" / "summary.json").read_text())
    argv = shlex.split(first["command"])
    assert argv[:3] == ["srr", "run", str(scenario)]
    assert "systems_under_test.route_follower.params.speed=0.7" in argv
    assert argv[argv.index("--baselines") + 1] == str(tmp_path / "bl")
    assert argv[-2:] == ["--out", str(tmp_path / "first")]
    (tmp_path / "first").rename(tmp_path / "kept")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    assert main([*argv[1:], "-q", "--no-video"]) in (0, 1)
    again = json.loads((tmp_path / "first" / "summary.json").read_text())
    assert again["digest"] == first["digest"] and again["command"] == first["command"]


def test_a_run_and_its_replay_record_the_scenario_file_absolute(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """``scenario_file`` in ``summary.json`` names the file from anywhere, however the
    command named it; a replay's is the recorded run's file, and a parameter its ``--set``
    got wrong is said of the flag, not of that file."""
    import os

    from harness.cli import main

    scenario = ROOT / "scenarios" / "turtlebot3_urdf.yaml"
    monkeypatch.chdir(tmp_path)
    assert main(["run", os.path.relpath(scenario), "--duration", "1", "-q", "--no-video",
                 "--out", "run"]) in (0, 1)  # UNSCORED: nothing to score
    assert json.loads((tmp_path / "run" / SUMMARY_NAME).read_text())["scenario_file"] == \
        str(scenario)
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    capsys.readouterr()
    assert main(["replay", "../run", "-q", "--out", "bad", "--set",
                 "systems_under_test.teleop.params.bogus=1"]) == 2
    assert capsys.readouterr().err.strip() == (
        "srr replay: --set: systems_under_test[0].params.bogus: unknown field (expected "
        "segments, rate_hz, cmd_vel_topic)")
    assert not (tmp_path / "elsewhere" / "bad").exists()
    assert main(["replay", "../run", "-q", "--out", "again"]) in (0, 1)
    assert json.loads((tmp_path / "elsewhere" / "again" / SUMMARY_NAME).read_text())[
        "scenario_file"] == str(scenario)


def _said(argv: list[str]) -> str:
    """The command as srr names it in an error: ``baseline bless``, ``diff``, ..."""
    return " ".join(argv[:2]) if argv[0] == "baseline" else argv[0]


def test_a_suites_summary_is_said_to_be_one(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    # `srr report SUITE_OUT` said "scenario: missing (not an srr run summary)"
    from harness.cli import main

    (tmp_path / "summary.json").write_text(json.dumps(
        {"format": 1, "name": "nightly", "groups": [], "runs": []}))
    assert main(["report", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"srr report: {tmp_path / 'summary.json'}: the summary of a suite, not of a "
                   f"run: the suite's page is {tmp_path / 'index.html'}, and each run's directory "
                   "is under its runs/ (srr report RUN_DIR renders one)"), err
