"""Semantic checks of a scenario beyond its types: defaults that follow the scene, values the
simulation cannot give, positions outside the world. Each is refused in one line (exit 2)
naming the file and the field, by ``srr validate`` as by ``srr run``."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main
from harness.scenario import load_scenario


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    return path


def _validate(capsys: pytest.CaptureFixture[str], path: Path) -> tuple[int, str, str]:
    code = main(["validate", str(path)])
    out, err = capsys.readouterr()
    return code, out.strip(), err.strip()


TB3 = """\
format_version: 1
name: t
duration: 2
srr_gt: true
robots:
  - {name: tb3, model: turtlebot3_waffle_pi}
routes:
  r: {waypoints: [[0, 0], [1, 0]]}
"""


def test_control_scoring_defaults_to_the_only_robot(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, TB3 + "scoring:\n  control: {route: r}\n")
    assert load_scenario(path).scoring.control.robot == "tb3"  # type: ignore[union-attr]
    code, _out, err = _validate(capsys, path)
    assert code == 0, err


def test_control_scoring_without_robot_in_a_two_robot_scene_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    two = TB3.replace("robots:\n", "robots:\n  - {name: other, model: turtlebot3_waffle_pi,"
                      " spawn: {position: [2, 2, 0]}}\n")
    path = _write(tmp_path, two + "scoring:\n  control: {route: r}\n")
    code, _out, err = _validate(capsys, path)
    assert code == 2
    assert len(err.splitlines()) == 1
    assert f"{path}: scoring.control.robot: " in err
    assert "tb3" in err and "other" in err
