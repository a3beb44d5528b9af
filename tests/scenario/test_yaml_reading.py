"""How srr reads YAML, seen from the command line: YAML 1.2 numbers (``1e3``), keys set twice
refused, include names the OS refuses and very long values each in one short line, exit 2."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main
from harness.suite.spec import load_suite
from tests.conftest import SCENARIOS
from tests.scenario.minimal import GOOD


def _cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out.strip(), err.strip()


def _refused(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    code, _out, err = _cli(capsys, *argv)
    assert code == 2, err
    assert len(err.splitlines()) == 1 and err.startswith(f"srr {argv[0]}: "), err
    return err


@pytest.mark.parametrize(("text", "field", "lines"), [
    (GOOD + "duration: 5\n", "duration", "lines 3 and 7"),
    (GOOD.replace("    model: forklift\n", "    model: forklift\n    name: other\n"),
     "robots[0].name", "lines 5 and 7"),
    (GOOD + "physics: {tick_hz: 60, tick_hz: 30}\n", "physics.tick_hz",
     "lines 7 and 7"),
], ids=["top-level", "in-a-list-item", "flow-mapping"])
def test_a_key_set_twice_is_refused_with_its_path_and_lines(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, field: str,
        lines: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    err = _refused(capsys, "validate", str(path))
    assert f"{path}: {field}: set twice ({lines})" in err


def test_a_key_set_twice_in_an_include_names_the_include(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "inc.yaml").write_text("seed: 1\nseed: 2\n")
    path = tmp_path / "s.yaml"
    path.write_text(GOOD + "include: inc.yaml\n")
    err = _refused(capsys, "validate", str(path))
    assert f"{tmp_path / 'inc.yaml'}: seed: set twice (lines 1 and 2)" in err


def test_a_key_set_twice_in_a_set_value_or_a_suite_file_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(GOOD)
    err = _refused(capsys, "validate", str(path), "--set", "physics={timestep: 1, timestep: 2}")
    assert "--set: physics: value is not valid YAML" in err and "'timestep'" in err
    suite = tmp_path / "suite.yaml"
    suite.write_text("suite: s\nscenarios: [s.yaml]\nsuite: t\n")
    err = _refused(capsys, "suite", str(suite), "--out", str(tmp_path / "out"))
    assert f"{suite}: suite: set twice (lines 1 and 3)" in err
    assert not (tmp_path / "out").exists()


def test_exponent_numbers_read_as_numbers_everywhere(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(GOOD.replace("duration: 2", "duration: 1e3") +
                    "recording: {chunk_s: 5E-1}\n")
    code, out, err = _cli(capsys, "validate", str(path))
    assert code == 0 and "1000 s" in out, err
    code, out, err = _cli(capsys, "validate", str(path), "--set", "duration=5e1")
    assert code == 0 and "50 s" in out, err
    suite = tmp_path / "suite.yaml"
    suite.write_text("suite: s\ndefaults: {timeout: 1e3}\n"
                     "scenarios: [{path: s.yaml, set: {duration: 2e1}}]\n")
    (entry,) = load_suite([suite]).entries
    assert entry.timeout_s == 1000.0 and entry.overrides == ("duration=20.0",)


def test_yes_and_on_are_text_not_booleans(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(GOOD + "render: {shadows: yes}\n")
    err = _refused(capsys, "validate", str(path))
    assert "render.shadows: expected true or false, got 'yes' (YAML 1.2 booleans" in err


def test_a_text_that_looks_like_a_number_stays_text_through_a_suite_set(
        tmp_path: Path) -> None:
    (tmp_path / "s.yaml").write_text(GOOD)
    suite = tmp_path / "suite.yaml"
    suite.write_text("suite: s\nscenarios: [{path: s.yaml, set: {description: '1e3'}}]\n")
    (entry,) = load_suite([suite]).entries
    assert entry.overrides == ("description='1e3'",)


def test_an_include_name_the_os_refuses_is_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(GOOD + f"include: {'a' * 5000}.yaml\n")
    err = _refused(capsys, "validate", str(path))
    assert f"{tmp_path}/aaa" in err and "…: include: cannot read: File name too long" in err
    assert len(err) < 400


@pytest.mark.parametrize("text", [
    GOOD + f"render: {{lights: {'l' * 5000}}}\n",
    GOOD.replace("duration: 2", f"duration: [{', '.join(['1'] * 3000)}]"),
    GOOD + f"? {'k' * 5000}\n: 1\n",
], ids=["long-string", "long-list", "long-key"])
def test_a_long_value_is_cut_in_the_message(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    err = _refused(capsys, "validate", str(path))
    assert "…" in err and len(err) < 300, err
    assert str(path) in err


def test_bundled_scenarios_still_read_the_same() -> None:
    """No bundled file used a YAML 1.1-only form (yes/on, 1e3, 012, dates, keys twice)."""
    import yaml

    from harness import yamlio

    files = [*SCENARIOS.glob("*.yaml"), *SCENARIOS.glob("*/*.yaml")]
    assert len(files) > 10
    for f in files:
        text = f.read_text(encoding="utf-8")
        assert yamlio.load(text) == yaml.safe_load(text), f


@pytest.mark.parametrize(("text", "value"), [
    ("[1e3, -1E-5, .inf, -.Inf, 012, 0o17, 0x1F, +3, 1., .5]",
     [1000.0, -1e-5, float("inf"), float("-inf"), 12, 15, 31, 3, 1.0, 0.5]),
    ("[yes, no, on, off, y, True, FALSE, ~, Null, 2024-01-02, 1_000, 1:20]",
     ["yes", "no", "on", "off", "y", True, False, None, None, "2024-01-02", "1_000", "1:20"]),
    ("{base: &b {x: 1, y: 2}, use: {<<: *b, x: 3}}",
     {"base": {"x": 1, "y": 2}, "use": {"x": 3, "y": 2}}),
])
def test_yaml_1_2_core_scalars(text: str, value: object) -> None:
    from harness import yamlio

    assert yamlio.load(text) == value
    assert yamlio.load(yamlio.dump(value)) == value


@pytest.mark.parametrize(("text", "words"), [
    ("a: !!int abc", "'abc' is not an integer"),
    ("a: !!bool maybe", "'maybe' is not true or false"),
    ("a: !!timestamp 2024-01-02", "is not supported"),
    ("a: !!python/object:os.system x", "is not supported"),
    (f"a: {'9' * 5000}", "too many digits"),
    ("a: {b: 1}\nc: 2\na: 3", "line 3, column 1: duplicate key 'a' (first set on line 1)"),
])
def test_yaml_values_srr_cannot_hold_are_yaml_errors(text: str, words: str) -> None:
    import yaml

    from harness import yamlio

    with pytest.raises(yaml.YAMLError) as caught:
        yamlio.load(text)
    assert words in yamlio.describe(caught.value)


def test_a_long_command_line_value_is_cut(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:  # argparse's error: exit 2
        main(["run", "s.yaml", "--compression", "z" * 5000])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "…" in err and len(err) < 300, err
