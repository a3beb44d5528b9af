"""Open-loop replay: a recorded run played back into its own systems under test reproduces
their outputs byte for byte; changed systems are scored against the recorded ground truth and
the same baseline; bad input exits 2 with one line and writes nothing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness import api
from harness.cli import main
from tests.conftest import SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded

pytestmark = pytest.mark.slow

CROSSING = SCENARIOS / "dock_worker_crossing.yaml"
SUT_OUTPUTS = ["/cmd_vel", "/perception/tracks", "/safety/alarm", "/safety/is_muted"]


@pytest.fixture(scope="module")
def recorded(module_tmp: ModuleTmp) -> api.RunResult:
    out = module_tmp("replay") / "recorded"
    res = api.run_scenario(api.load(CROSSING), source=str(CROSSING), out=out)
    assert res.verdict == "PASS"
    return res


@pytest.fixture(scope="module")
def same(recorded: api.RunResult, module_tmp: ModuleTmp) -> api.RunResult:
    return api.replay(recorded.run_dir, out=module_tmp("replay") / "same")


def test_replaying_the_same_systems_reproduces_every_topic(recorded: api.RunResult,
                                                           same: api.RunResult) -> None:
    a, b = recorded.summary["topics"], same.summary["topics"]
    assert set(a) == set(b)
    assert {t: v["sha256"] for t, v in a.items()} == {t: v["sha256"] for t, v in b.items()}
    assert same.summary["digest"] == recorded.summary["digest"]
    assert same.summary["replay_of"]["withheld"] == SUT_OUTPUTS  # produced again, live
    assert (same.verdict, same.exit_code) == ("PASS", 0)
    assert {e["status"] for e in same.summary["comparison"]} == {"ok"}
    # a whole run directory, read back by the independent reader
    for name in ("scenario.yaml", "summary.json", "junit.xml", "report.html"):
        assert (same.run_dir / name).is_file()
    assert sum(1 for _ in decoded(same.run_dir)) == sum(v["count"] for v in b.values())
    html = (same.run_dir / "report.html").read_text()
    assert f"open-loop replay of {recorded.run_dir}" in html


def test_degraded_perception_parameters_are_caught(recorded: api.RunResult,
                                                   tmp_path: Path) -> None:
    res = api.replay(recorded.run_dir, out=tmp_path / "short",
                     overrides=["systems_under_test.perception.params.max_range=3.0"])
    assert (res.verdict, res.exit_code) == ("REGRESSED", 1)
    regressed = {e["name"] for e in res.summary["comparison"] if e["status"] == "regressed"}
    assert {"perception.recall", "safety.match_rate"} <= regressed
    # the inputs are the recording's: ground truth and sensors unchanged, outputs new
    for topic in ("/gt/character_0/tf", "/dock_cam_left_depth", "/odom"):
        assert res.summary["topics"][topic]["sha256"] == \
            recorded.summary["topics"][topic]["sha256"]
    assert res.summary["topics"]["/perception/tracks"]["sha256"] != \
        recorded.summary["topics"]["/perception/tracks"]["sha256"]


def test_a_replacement_plugin_is_scored_like_the_original(recorded: api.RunResult,
                                                          tmp_path: Path) -> None:
    res = api.replay(recorded.run_dir, out=tmp_path / "blind",
                     suts=["perception=tests.e2e.replay_plugins:BlindTracker"])
    assert res.verdict == "REGRESSED"
    m = {x["name"]: x["value"] for x in res.summary["metrics"]}
    assert m["perception.recall"] == 0.0
    assert res.summary["replay_of"]["replaced"] == {
        "perception": "tests.e2e.replay_plugins:BlindTracker"}
    assert res.summary["sut_endpoints"]["perception"]["plugin"] == \
        "tests.e2e.replay_plugins:BlindTracker"


def test_a_run_recorded_before_outputs_were_kept_still_replays(
        recorded: api.RunResult, tmp_path: Path) -> None:
    old = tmp_path / "old"
    old.mkdir()
    for name in ("scenario.yaml", "bag"):
        (old / name).symlink_to(recorded.run_dir / name)
    summary = dict(recorded.summary)
    del summary["sut_endpoints"]
    (old / "summary.json").write_text(json.dumps(summary))
    res = api.replay(old, out=tmp_path / "again")
    assert res.summary["digest"] == recorded.summary["digest"]


@pytest.mark.parametrize(("args", "words"), [
    (["--set", "world.wall_height=3"], "--set: world.wall_height: changes the recorded scene"),
    (["--set", "duration=5"], "--set: duration: changes the recorded scene"),
    (["--sut", "percepton=x:Y"], "--sut: percepton: no system under test named 'percepton'"),
    (["--sut", "perception"], "--sut: perception: expected NAME=module:Class"),
    (["--sut", "perception=no_such_module:X"],  # said of the flag that named it, verbatim
     "srr replay: --sut perception=no_such_module:X: cannot import module 'no_such_module'"),
    (["--set", "systems_under_test.perception.params.max_rang=3"], "max_rang: unknown field"),
])
def test_bad_replay_arguments_exit_2(recorded: api.RunResult, tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str], args: list[str],
                                     words: str) -> None:
    code = main(["replay", str(recorded.run_dir), "--out", str(tmp_path / "o"), "-q", *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and words in err, err
    assert not (tmp_path / "o").exists()


def test_a_replays_warnings_are_said_of_srr_replay(recorded: api.RunResult, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """They were printed as `srr run: warning: ...`."""
    main(["replay", str(recorded.run_dir), "--out", str(tmp_path / "o"), "-q",
          "--set", "systems_under_test.safety_monitor.enabled=false"])  # its verdict: not here
    err = capsys.readouterr().err.strip().splitlines()
    assert all(line.startswith("srr replay: warning: ") for line in err), err
    assert any("subscribes to /safety/alarm" in line for line in err), err


def test_bad_recordings_exit_2(recorded: api.RunResult, tmp_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "scenario.yaml").symlink_to(recorded.run_dir / "scenario.yaml")
    (broken / "summary.json").symlink_to(recorded.run_dir / "summary.json")
    (broken / "bag").mkdir()
    (broken / "bag" / "metadata.yaml").symlink_to(recorded.run_dir / "bag" / "metadata.yaml")
    (mcap,) = (recorded.run_dir / "bag").glob("*.mcap")
    data = mcap.read_bytes()
    (broken / "bag" / mcap.name).write_bytes(data[: len(data) // 3])
    cases = {tmp_path / "nowhere": "not a run directory", broken: "cannot read"}
    for path, words in cases.items():
        code = main(["replay", str(path), "--out", str(tmp_path / "o"), "-q"])
        err = capsys.readouterr().err.strip()
        assert code == 2 and len(err.splitlines()) == 1 and words in err, err
        assert not (tmp_path / "o").exists()
