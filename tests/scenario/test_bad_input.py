"""Every kind of bad scenario input exits 2 with one line naming the file and the field."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main
from harness.scenario import ToleranceSpec
from tests.scenario.minimal import GOOD


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    _out, err = capsys.readouterr()
    return code, err.strip()


@pytest.mark.parametrize(
    ("text", "field", "words"),
    [
        ("", "", "empty"),
        ("format_version: 1\nname: [unclosed\n", "", "YAML syntax error at line"),
        (GOOD.replace("duration: 2", "duraton: 2"), "duraton", "did you mean 'duration'"),
        (GOOD.replace("duration: 2", "duration: soon"), "duration", "expected a number"),
        (GOOD.replace("duration: 2", "duration: -5"), "duration", "must be > 0"),
        (GOOD.replace("model: forklift", "model: tractor"), "robots[0].model", "'tractor'"),
        (GOOD + "include: missing_robots.yaml\n", "include", "file not found"),
        (GOOD.replace("name: t", "name: 3d"), "name", "must be letters"),
        (GOOD + "clock: {clock_topic: 'bad//topic'}\n", "clock.clock_topic", "'//'"),
        (GOOD.replace("format_version: 1", "format_version: 99"), "format_version",
         "unsupported version"),
        (GOOD + "recording: {chunk_s: 0}\n", "recording.chunk_s", "must be > 0"),
        (GOOD + "recording: {chunk_sec: 1}\n", "recording.chunk_sec", "did you mean"),
        (GOOD + "render: {lights: moon}\n", "render.lights", "expected one of 'all', 'sun'"),
        (GOOD + "render: {shadows: sometimes}\n", "render.shadows", "expected true or false"),
        (GOOD + "render: {shadow_size: 8}\n", "render.shadow_size", "must be >= 64"),
        (GOOD + "render: {shadow: true}\n", "render.shadow", "did you mean 'shadows'"),
    ],
    ids=["empty", "yaml-syntax", "misspelt-key", "text-for-number", "negative-duration",
         "unknown-model", "missing-include", "bad-name", "bad-topic", "format-version",
         "zero-chunk-span", "misspelt-recording-key", "render-lights", "render-shadows",
         "render-shadow-size", "misspelt-render-key"],
)
def test_bad_scenario_is_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                         text: str, field: str, words: str) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    for command in ("validate", "run"):
        code, err = _run(capsys, command, str(path), "--out", str(tmp_path / "out")) \
            if command == "run" else _run(capsys, command, str(path))
        assert code == 2, err
        assert len(err.splitlines()) == 1, err
        assert "Traceback" not in err
        assert str(path) in err  # the file that says it (a missing include: the including)
        if "include" in field:
            assert f"{path}: include: {tmp_path / 'missing_robots.yaml'}: " in err, err
        assert f": {field}:" in err if field else True
        assert words in err
    assert not (tmp_path / "out").exists(), "a rejected scenario must not leave a run dir"


def test_missing_scenario_path(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, err = _run(capsys, "run", str(tmp_path / "nope.yaml"))
    assert code == 2
    assert err == f"srr run: {tmp_path / 'nope.yaml'}: file not found"


def test_error_in_included_file_names_that_file(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "robots.yaml").write_text(
        "robots:\n  - name: f\n    model: forklift\n    control: {wheelbase: wide}\n")
    main_file = tmp_path / "s.yaml"
    main_file.write_text("format_version: 1\nname: s\ninclude: robots.yaml\n")
    code, err = _run(capsys, "validate", str(main_file))
    assert code == 2
    assert f"{tmp_path / 'robots.yaml'}: robots[0].control.wheelbase: expected a number" in err


def test_bad_override(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(GOOD)
    code, err = _run(capsys, "validate", str(path), "--set", "robots.nobody.model=forklift")
    assert code == 2
    assert "robots.nobody" in err and len(err.splitlines()) == 1
    code, err = _run(capsys, "validate", str(path), "--set", "duration=-1")
    assert code == 2 and ": duration: must be > 0" in err


def test_bad_cli_argument_is_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["run", "x.yaml", "--seed", "many"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--seed" in err


@pytest.mark.parametrize(("override", "field"), [
    ("scoring.control.route=nowhere", "scoring.control.route"),
    ("srr_gt=false", "scoring"),
    ("scoring.safety={robot: forklift}", "zones"),
])
def test_unscorable_scoring_is_refused_before_running(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str],
                                                      override: str, field: str) -> None:
    from tests.conftest import SCENARIOS

    path = str(SCENARIOS / "forklift_warehouse.yaml")
    for argv in (["validate", path, "--set", override],
                 ["run", path, "--set", override, "--out", str(tmp_path / "r")]):
        code, err = _run(capsys, *argv)
        assert code == 2 and f"{path}: {field}:" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "r").exists()


def test_a_lidar_range_min_above_its_range_max_is_a_scenario_error(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from tests.conftest import SCENARIOS

    path = str(SCENARIOS / "forklift_warehouse.yaml")
    override = "robots.0.sensors.lidar={range_min: 10, range_max: 6}"
    for argv in (["validate", path, "--set", override],
                 ["run", path, "--set", override, "--out", str(tmp_path / "r")]):
        code, err = _run(capsys, *argv)
        assert code == 2 and len(err.splitlines()) == 1, err
        assert err.endswith("robots[0].sensors.lidar.range_min: must be below range_max (6), "
                            "got 10"), err
    assert not (tmp_path / "r").exists()


def test_a_perception_area_is_a_polygon(capsys: pytest.CaptureFixture[str]) -> None:
    """Two points make no area: every perception metric would have been '—', silently."""
    from tests.conftest import SCENARIOS

    path = str(SCENARIOS / "dock_nominal.yaml")
    code, err = _run(capsys, "validate", path, "--set", "scoring.perception.area=[[0,0],[1,1]]")
    assert code == 2 and err.endswith(
        "scoring.perception.area: a polygon needs at least three points, got 2"), err


def test_a_tolerance_for_no_metric_group_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    """A misspelt group in a tolerance's key would match no metric, and the tolerance would
    silently not apply."""
    from tests.conftest import SCENARIOS

    path = str(SCENARIOS / "dock_nominal.yaml")
    code, err = _run(capsys, "validate", path, "--set",
                     'scoring.tolerances={"percepton.*": {abs: 1}}')
    assert code == 2 and err.endswith("scoring.tolerances.percepton.*: matches no metric: "
                                      "metric names start with control, perception, safety, "
                                      "spec (did you mean 'perception'?)"), err
    code, err = _run(capsys, "validate", path, "--set",
                     'scoring.tolerances={"perception.*": {abs: 1}, "*.rms": {rel: 0.1}}')
    assert code == 0, err


def test_a_camera_output_listed_twice_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    from tests.conftest import SCENARIOS

    code, err = _run(capsys, "validate", str(SCENARIOS / "dock_nominal.yaml"), "--set",
                     "cameras.0.outputs=[rgb, depth, rgb]")
    assert code == 2 and err.endswith("cameras[0].outputs[2]: 'rgb' is listed twice"), err


@pytest.mark.parametrize(("override", "said"), [
    ("systems_under_test.teleop.params.bogus=1",
     "--set: systems_under_test[0].params.bogus: unknown field (expected segments, rate_hz, "
     "cmd_vel_topic)"),
    ("systems_under_test.0.params.rate_hz=0",
     "--set: systems_under_test[0].params.rate_hz: must be > 0, got 0"),
    ("robots.turtlebot3.spawn.bogus=1",
     "--set: robots[0].spawn.bogus: unknown field (expected position, rpy_deg)"),
    ("seed=x", "--set: seed: expected an integer, got 'x'"),
])
def test_a_bad_value_a_set_gave_is_said_of_the_flag(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], override: str, said: str) -> None:
    """A value ``--set`` gave is the flag's, not the scenario file's, wherever it is found
    wrong: as it is read, or as a plug-in reads its parameters in set-up."""
    from tests.conftest import SCENARIOS

    path = str(SCENARIOS / "turtlebot3_urdf.yaml")
    for argv in (["validate", path, "--set", override],
                 ["run", path, "--set", override, "--out", str(tmp_path / "r")]):
        code, err = _run(capsys, *argv)
        assert code == 2 and err == f"srr {argv[0]}: {said}", err
    assert not (tmp_path / "r").exists()
    # beside it, a parameter the file gave is still the file's
    own = tmp_path / "s.yaml"
    own.write_text(GOOD + "systems_under_test:\n  - name: teleop\n"
                   "    plugin: harness.sut.teleop:ScriptedTeleop\n"
                   "    params: {rate_hz: 0, segments: [{duration: 1, linear: 0.2}]}\n")
    code, err = _run(capsys, "validate", str(own), "--set",
                     "systems_under_test.teleop.params.cmd_vel_topic=cmd")
    assert code == 2 and err == (f"srr validate: {own}: systems_under_test[0].params.rate_hz: "
                                 "must be > 0, got 0"), err


def test_set_addresses_a_tolerance_of_a_metric_name_with_dots(
        capsys: pytest.CaptureFixture[str]) -> None:
    """A tolerance's key is a metric name, ``perception.position_error.p95``: in quotes it is
    one key of a ``--set`` path; unquoted, the error says how to write it."""
    from harness import api
    from tests.conftest import SCENARIOS

    path = str(SCENARIOS / "dock_nominal.yaml")
    metric = "perception.position_error.p95"
    for key in (f'"{metric}"', f"'{metric}'"):
        sc = api.load(path, overrides=[f"scoring.tolerances.{key}.abs=0.1",
                                       f"scoring.tolerances.{key}.rel=0.2"])
        assert sc.scoring.tolerances[metric] == ToleranceSpec(abs=0.1, rel=0.2)
        assert sc.scoring.tolerances["perception.*"] == ToleranceSpec(abs=0.05, rel=0.1)
    code, err = _run(capsys, "validate", path, "--set", f"scoring.tolerances.{metric}.abs=0.1")
    assert code == 2 and err == (
        "srr validate: --set: scoring.tolerances.perception.position_error: unknown field "
        "(expected abs, rel); a metric name with dots is one key: quote it, --set "
        f"'scoring.tolerances.\"{metric}\".abs=0.1'"), err
    for bad, said in ((f'scoring.tolerances."{metric}.abs=1', "is not closed"),
                      ('scoring.tolerances."perception"x.abs=1', "a quoted key is a whole")):
        code, err = _run(capsys, "validate", path, "--set", bad)
        assert code == 2 and said in err and len(err.splitlines()) == 1, err
