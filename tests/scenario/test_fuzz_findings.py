"""What the input fuzzer (test_fuzz_inputs.py) found, each as a plain case: exit 2 with one
line naming the file and the field, where there was a traceback, exit 3 or a message on two
lines."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main
from harness.errors import ScenarioError
from harness.suite.spec import load_suite
from tests.conftest import SCENARIOS
from tests.scenario.minimal import GOOD


def _refused(capsys: pytest.CaptureFixture[str], path: Path) -> str:
    code = main(["validate", str(path)])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and err.startswith(f"srr validate: {path}: "), err
    return err


@pytest.mark.parametrize(("edit", "words"), [
    (lambda t: t.replace("marker_topics: [/perception/tracks]", "marker_topics: ['//x']"),
     "scoring.perception.marker_topics[0]: '//x' contains '//'"),
    (lambda t: t.replace("sut_outputs: {/perception/tracks: 1.0,",
                         "sut_outputs: {'/a b': 1.0,"),
     "scoring.health.sut_outputs./a b: "),
], ids=["marker-topic", "sut-output-topic"])
def test_topic_names_in_scoring_are_checked_at_load(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], edit: object, words: str) -> None:
    """A bad topic in scoring.perception.marker_topics (or a health mapping's key) escaped
    as a TopicNameError traceback from the wiring check."""
    text = (SCENARIOS / "dock_empty.yaml").read_text()
    new = edit(text)  # type: ignore[operator]
    assert new != text
    path = tmp_path / "dock_empty.yaml"
    (tmp_path / "dock").symlink_to(SCENARIOS / "dock")
    path.write_text(new)
    assert words in _refused(capsys, path)


@pytest.mark.parametrize(("extra", "field"), [
    ("    articulation_prim: ' '\n", "robots[0].articulation_prim"),
    ("cameras: [{name: c, camera_prim: 'World/c', spawn: {position: [0, 0, 2]}}]\n",
     "cameras[0].camera_prim"),
], ids=["robot", "camera"])
def test_a_bad_prim_path_is_exit_2_naming_the_field(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: str, field: str) -> None:
    """It was exit 3 ("not a valid prim path"), naming neither the file nor the field."""
    path = tmp_path / "s.yaml"
    path.write_text(GOOD + extra)
    assert f": {field}: not a valid prim path" in _refused(capsys, path)


@pytest.mark.parametrize(("extra", "words"), [
    ('include: "a\\0b.yaml"\n', "include: not a file name: 'a\\x00b.yaml'"),
    ("    control: {wheel_radius: 5.0e-324}\n",
     "robots[0].control.wheel_radius: must be > 0 (at least 1e-09), got 5e-324"),
    ('"render\\n": 1\n', "render\\n: unknown field"),
    ('    control: {drive_joint: "a\\0"}\n',
     "robots[0].control.drive_joint: contains a NUL character: 'a\\x00'"),
], ids=["nul-in-include", "subnormal-size", "newline-in-key", "nul-in-a-name"])
def test_fuzzed_values_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                    extra: str, words: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(GOOD + extra)
    assert words in _refused(capsys, path)


def test_a_name_is_ascii(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """'º' is a letter to str.isalnum, not to a prim path: validate exited 3."""
    path = tmp_path / "s.yaml"
    path.write_text(GOOD.replace("name: forklift", "name: º"))
    assert "robots[0].name: must be letters, digits and '_'" in _refused(capsys, path)


@pytest.mark.parametrize(("entry", "words"), [
    ("{path: " + "x" * 5000 + ".yaml}", "scenarios[0].path: cannot read 'xxx"),
    ("{path: s.yaml, repeat: 1000000000000}",
     "scenarios[0].repeat: must be <= 1000, got 1000000000000"),
    ("{path: s.yaml, sweep: {seed: {from: -1e308, to: 1e308, step: 1}}}",
     "scenarios[0].sweep.seed.step: gives too many values (at most 1000)"),
    ("{path: s.yaml, sweep: {seed: {from: 0, to: 1" + "0" * 400 + ", step: 1}}}",
     "suite.yaml: not valid YAML: line 2, column 56:"),
    ("{path: s.yaml, repeat: 1" + "0" * 400 + "}", "beyond ±1.8e308"),
], ids=["path-too-long", "huge-repeat", "infinite-sweep", "huge-int-sweep",
    "huge-int-repeat"])
def test_a_suite_entry_the_os_or_memory_cannot_take(tmp_path: Path, entry: str,
                                                    words: str) -> None:
    """A path too long escaped as OSError; a huge repeat built that many runs in memory."""
    (tmp_path / "s.yaml").write_text(GOOD)
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"suite: s\nscenarios: [{entry}]\n")
    with pytest.raises(ScenarioError) as caught:
        load_suite([suite])
    assert words in str(caught.value) and "\n" not in str(caught.value)


def test_a_robot_camera_resolution_is_in_range(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """A robot camera's resolution went unchecked to the render product: a graph error that
    named neither the file nor the field."""
    text = (SCENARIOS / "turtlebot3_room.yaml").read_text()
    assert "resolution: [320, 240]" in text
    path = tmp_path / "t.yaml"
    path.write_text(text.replace("resolution: [320, 240]", "resolution: [-1, 240]", 1))
    err = _refused(capsys, path)
    assert "robots[0].sensors.camera.resolution[0]: must be >= 1, got -1" in err
