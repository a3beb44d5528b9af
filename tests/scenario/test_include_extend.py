"""``key+:`` extends an included list or mapping instead of replacing it; clashes are errors
naming the file and the field."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.errors import ScenarioError
from harness.scenario import load_scenario

SCENE = """\
robots:
  - {name: forklift, model: forklift}
cameras:
  - {name: cam_a, spawn: {position: [0, 0, 3]}}
routes:
  r1: {waypoints: [[0, 0], [1, 0]]}
"""
HEAD = "format_version: 1\nname: x\ninclude: [scene.yaml]\n"


def load(tmp_path: Path, body: str, scene: str = SCENE) -> object:
    (tmp_path / "scene.yaml").write_text(scene)
    (tmp_path / "x.yaml").write_text(HEAD + body)
    return load_scenario(tmp_path / "x.yaml")


def error(tmp_path: Path, body: str, scene: str = SCENE) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        load(tmp_path, body, scene)
    return info.value


def test_lists_and_mappings_are_extended(tmp_path: Path) -> None:
    sc = load(tmp_path, "cameras+:\n  - {name: cam_b}\nrobots+:\n  - {name: lift_b, model: "
                        "forklift, spawn: {position: [0, 5, 0]}}\nroutes+:\n"
                        "  r2: {waypoints: [[0, 5], [1, 5]]}\n")
    assert [c.name for c in sc.cameras] == ["cam_a", "cam_b"]  # type: ignore[attr-defined]
    assert [r.name for r in sc.robots] == ["forklift", "lift_b"]  # type: ignore[attr-defined]
    assert sorted(sc.routes) == ["r1", "r2"]  # type: ignore[attr-defined]
    # two robots now: both get a namespace and a frame prefix
    assert [(r.ns, r.frame_prefix) for r in sc.robots] == [  # type: ignore[attr-defined]
        ("forklift", "forklift/"), ("lift_b", "lift_b/")]
    # an error in an added item names the scenario file, one in an included item the include
    e = error(tmp_path, "robots+:\n  - {name: lift_b, model: tractor}\n")
    assert (e.file, e.field) == (str(tmp_path / "x.yaml"), "robots[1].model")
    e = error(tmp_path, "robots+:\n  - {name: lift_b, model: forklift}\n",
              SCENE.replace("model: forklift}", "model: forklift, spawn: {rpy_deg: oops}}"))
    assert (e.file, e.field) == (str(tmp_path / "scene.yaml"), "robots[0].spawn.rpy_deg")


def test_a_later_include_extends_an_earlier_one(tmp_path: Path) -> None:
    (tmp_path / "more.yaml").write_text("cameras+:\n  - {name: cam_c}\n")
    (tmp_path / "scene.yaml").write_text(SCENE)
    (tmp_path / "x.yaml").write_text("format_version: 1\nname: x\n"
                                     "include: [scene.yaml, more.yaml]\n")
    sc = load_scenario(tmp_path / "x.yaml")
    assert [c.name for c in sc.cameras] == ["cam_a", "cam_c"]


@pytest.mark.parametrize(("body", "field", "words"), [
    ("cameras+:\n  - {name: cam_a}\n", "cameras+[0].name",
     ["already has an item named 'cam_a'", "scene.yaml", "--set cameras.cam_a.FIELD=VALUE"]),
    ("routes+:\n  r1: {waypoints: [[0, 0], [2, 0]]}\n", "routes+.r1", ["already has 'r1'"]),
    ("cameras+: {name: cam_b}\n", "cameras+", ["expected a list of items to append"]),
    ("cameras: []\ncameras+: [{name: cam_b}]\n", "cameras+", ["both 'cameras' and 'cameras+'"]),
    ("duration+: 3\nduration: 1\n", "duration+", ["both 'duration' and 'duration+'"]),
    ("world:\n  shelves+: []\n", "world.shelves+", ["works for top-level keys only"]),
])
def test_clashes_and_misuse_are_errors(tmp_path: Path, body: str, field: str,
                                       words: list[str]) -> None:
    e = error(tmp_path, body)
    assert e.file == str(tmp_path / "x.yaml") and e.field == field, str(e)
    for w in words:
        assert w in str(e), str(e)


def test_a_duplicate_robot_names_both_files(tmp_path: Path) -> None:
    (tmp_path / "scene.yaml").write_text(SCENE)
    (tmp_path / "more.yaml").write_text("robots+:\n  - {name: forklift, model: forklift}\n")
    (tmp_path / "x.yaml").write_text("format_version: 1\nname: x\n"
                                     "include: [scene.yaml, more.yaml]\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(tmp_path / "x.yaml")
    assert info.value.file == str(tmp_path / "more.yaml")
    assert "robots already has an item named 'forklift' (from" in str(info.value)
    assert "scene.yaml" in str(info.value)
