"""Robots from ``.xacro`` files (``model: {xacro: FILE, args: {...}}``): the real ``xacro``
package expands them, with the scenario's args and ``$(find pkg)`` on srr's package path;
the model's digest covers every file xacro read and the args; errors are one line naming the
scenario file and ``robots[i].model.xacro``; a ``.xacro`` given as ``urdf:`` is refused.

The robot is tests/sim/xacro_robot: ``urdf/xbot.urdf.xacro`` (args ``wheel_radius`` and
``with_lidar`` with defaults) includes ``wheel.xacro`` (the wheel macro) beside it and
``$(find xbot_description)/urdf/caster.xacro`` (the caster macro) from the fake package under
``pkgs/``, whose chassis mesh it also names with ``$(find ...)``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
import yaml
from xacro import substitution_args

from harness import api
from harness.cli import main
from harness.errors import ScenarioError
from harness.scenario import load_scenario
from harness.sim import World
from tests.e2e.bagread import decoded

ROBOT = Path(__file__).parent / "xacro_robot"
CONTROL = {"joint_names": ["left_wheel_hinge", "right_wheel_hinge"], "wheel_radius": 0.05,
           "wheel_distance": 0.26}
LINKS = {"base_footprint", "base_link", "left_wheel", "right_wheel", "caster_link",
         "lidar_link"}


def tree(tmp: Path) -> Path:
    """A copy of the robot's files to edit: ``tmp/robot``."""
    shutil.copytree(ROBOT, tmp / "robot")
    return tmp / "robot"


def write(tmp: Path, root: Path, *, model: dict[str, Any] | None = None,
          **extra: Any) -> Path:
    """A scenario beside ``root`` with one xbot robot (its model block updated by
    ``model``)."""
    block = {"xacro": f"{root.name}/urdf/xbot.urdf.xacro", "package_paths": [f"{root.name}/pkgs"],
             "frictionless_links": ["caster_link"], **(model or {})}
    path = tmp / "scene.yaml"
    path.write_text(yaml.safe_dump({
        "format_version": 1, "name": "xbot", "duration": 1.0,
        "world": {"size": [8.0, 6.0], "shelves": [], "dock": {"enabled": False}},
        "robots": [{"name": "bot", "model": block, "control": dict(CONTROL)}], **extra}))
    return path


def build(path: Path) -> World:
    return World.build(load_scenario(path), str(path), environ={})


def digest(path: Path) -> str:
    return build(path).scene_files["robots[0].model"]


def error_of(path: Path) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        api.validate(load_scenario(path), source=str(path))
    return info.value


def test_a_xacro_robot_loads_with_its_macros_includes_and_packages(tmp_path: Path) -> None:
    path = write(tmp_path, tree(tmp_path))
    world = build(path)
    robot = world.robot("bot")
    assert set(robot.links) == LINKS  # the wheel macro twice, the caster from $(find ...)
    assert tuple(robot.joints) == ("left_wheel_hinge", "right_wheel_hinge")
    meshes = [world.model.mesh(i).name for i in range(world.model.nmesh)]
    assert meshes == ["bot/chassis"]  # named with $(find xbot_description)
    api.validate(load_scenario(path), source=str(path))
    # the hook that answers $(find ...) from srr's package path is taken off again
    assert substitution_args._eval_find.__module__ == "xacro.substitution_args"


def _wheel_radius(world: World) -> float:
    body = world.model.body("bot/left_wheel").id
    radii = [float(world.model.geom_size[g][0]) for g in range(world.model.ngeom)
             if int(world.model.geom_bodyid[g]) == body]
    assert len(radii) == 1
    return radii[0]


def test_args_change_the_model_and_its_digest(tmp_path: Path) -> None:
    root = tree(tmp_path)
    default = build(write(tmp_path, root))
    assert _wheel_radius(default) == pytest.approx(0.05)  # the arg's default
    first = default.scene_files["robots[0].model"]
    bigger = build(write(tmp_path, root, model={"args": {"wheel_radius": 0.07,
                                                         "with_lidar": False}}))
    assert _wheel_radius(bigger) == pytest.approx(0.07)
    assert set(bigger.robot("bot").links) == LINKS - {"lidar_link"}  # xacro:if on a bool arg
    pos, _ = bigger.prim_pose("/World/bot/base_link")
    assert pos[2] == pytest.approx(0.07, abs=2e-3)  # the axle is the wheels' radius up
    assert bigger.scene_files["robots[0].model"] != first
    assert digest(write(tmp_path, root)) == first
    # an int stays an int: xacro reads "0" as false (a float would be "0.0", no boolean)
    off = build(write(tmp_path, root, model={"args": {"with_lidar": 0}}))
    assert "lidar_link" not in off.robot("bot").links


def test_editing_any_file_xacro_read_changes_the_digest(tmp_path: Path) -> None:
    root = tree(tmp_path)
    path = write(tmp_path, root)
    seen = {digest(path)}
    wheel = root / "urdf" / "wheel.xacro"  # xacro:include beside the main file
    wheel.write_text(wheel.read_text().replace('mass value="0.1"', 'mass value="0.12"'))
    seen.add(digest(path))
    caster = root / "pkgs" / "xbot_description" / "urdf" / "caster.xacro"  # via $(find ...)
    caster.write_text(caster.read_text().replace('mass value="0.01"', 'mass value="0.02"'))
    seen.add(digest(path))
    assert len(seen) == 3


def test_the_digest_does_not_depend_on_where_the_files_are(tmp_path: Path) -> None:
    """The includes are hashed by content, not by their (machine-dependent) paths."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    here = digest(write(tmp_path / "a", tree(tmp_path / "a")))
    assert digest(write(tmp_path / "b", tree(tmp_path / "b"))) == here


@pytest.mark.parametrize(("edit", "model", "words"), [
    (None, {"xacro": "robot/urdf/nope.urdf.xacro"}, ["nope.urdf.xacro: file not found"]),
    (lambda r: (r / "urdf" / "wheel.xacro").write_text("<robot><link></robot>"), {},
     ["not well-formed XML", "wheel.xacro"]),
    (lambda r: (r / "urdf" / "xbot.urdf.xacro").write_text(
        (ROBOT / "urdf" / "xbot.urdf.xacro").read_text().replace(
            '<xacro:wheel side="left"', '<xacro:wheeel side="left"')), {},
     ["xacro cannot expand it", "wheeel"]),
    (lambda r: (r / "urdf" / "xbot.urdf.xacro").write_text(
        (ROBOT / "urdf" / "xbot.urdf.xacro").read_text().replace(
            '<xacro:arg name="wheel_radius" default="0.05"/>', "")), {},
     ["$(arg wheel_radius) has no value: give it in the model's args"]),
    (lambda r: (r / "urdf" / "xbot.urdf.xacro").write_text(  # a tag without an attribute
        (ROBOT / "urdf" / "xbot.urdf.xacro").read_text().replace(
            '<xacro:arg name="wheel_radius" default="0.05"/>',
            '<xacro:arg name="wheel_radius"/>')), {},
     ["xacro cannot expand it", "missing attribute 'default'"]),
    (lambda r: (r / "urdf" / "wheel.xacro").write_text(
        (ROBOT / "urdf" / "wheel.xacro").read_text().replace(
            "</xacro:macro>", '<xacro:wheel side="x" y="0" radius="1"/></xacro:macro>')), {},
     ["xacro cannot expand it: too deep a recursion"]),
    (lambda r: (r / "urdf" / "wheel.xacro").unlink(), {},
     ["xacro cannot expand it: No such file or directory:", "wheel.xacro"]),
    (None, {"package_paths": []},
     ["$(find xbot_description): package 'xbot_description' not found",
      "SRR_PACKAGE_PATH"]),
    (lambda r: (r / "urdf" / "wheel.xacro").write_text(
        (ROBOT / "urdf" / "wheel.xacro").read_text().replace(
            'type="continuous"', 'type="spinny"')), {},
     ["MuJoCo cannot read the URDF xacro made of it"]),
])
def test_bad_xacro_is_one_line_naming_the_scenario_and_field(
        tmp_path: Path, edit: Any, model: dict[str, Any], words: list[str]) -> None:
    root = tree(tmp_path)
    if edit is not None:
        edit(root)
    path = write(tmp_path, root, model=model)
    err = error_of(path)
    assert (err.file, err.field) == (str(path), "robots[0].model.xacro")
    for word in words:
        assert word in err.message
    assert "\n" not in str(err)
    assert substitution_args._eval_find.__module__ == "xacro.substitution_args"


def test_srr_validate_refuses_a_xacro_file_given_as_urdf(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    root = tree(tmp_path)
    path = write(tmp_path, root, model={"xacro": None,
                                        "urdf": "robot/urdf/xbot.urdf.xacro"})
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert err.startswith(f"srr validate: {path}: robots[0].model.urdf: ")
    assert "is a xacro file: write 'xacro: robot/urdf/xbot.urdf.xacro'" in err


def test_a_world_file_given_as_xacro_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, tree(tmp_path))
    data = yaml.safe_load(path.read_text())
    data["world"] = {"model": {"urdf": "robot/urdf/xbot.urdf.xacro"}}
    path.write_text(yaml.safe_dump(data))
    err = error_of(path)
    assert err.field == "world.model.urdf" and "is a xacro file" in err.message


def test_args_belong_to_a_xacro_file(tmp_path: Path) -> None:
    root = tree(tmp_path)
    urdf = tmp_path / "plain.urdf"
    urdf.write_text("<robot name='r'><link name='a'/></robot>")
    path = write(tmp_path, root, model={"xacro": None, "urdf": "plain.urdf",
                                        "args": {"wheel_radius": 0.1}})
    err = error_of(path)
    assert err.field == "robots[0].model.args" and "set 'xacro', not 'urdf'" in err.message


def test_srr_validate_answers_a_missing_package_with_exit_2(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, tree(tmp_path), model={"package_paths": []})
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.startswith(f"srr validate: {path}: robots[0].model.xacro: ")
    assert "package 'xbot_description' not found" in err


def test_srr_runs_a_xacro_robot_and_records_its_digest(tmp_path: Path) -> None:
    teleop = [{"name": "teleop", "plugin": "harness.sut.teleop:ScriptedTeleop",
               "params": {"rate_hz": 10, "cmd_vel_topic": "cmd_vel",
                          "segments": [{"duration": 1.0, "linear": 0.2}]}}]
    path = write(tmp_path, tree(tmp_path), systems_under_test=teleop,
                 scoring={"record_only": True})
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene_files"]["robots[0].model"] == digest(path)
    xs = [msg.pose.pose.position.x for topic, _, _, msg in decoded(out) if topic == "/odom"]
    assert xs and xs[-1] > 0.1  # driven forward by the teleop through its wheel joints


def test_an_argument_the_file_does_not_declare_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A misspelt arg was accepted and its value never used (the file's default was); it is
    refused naming the arg's field, the xacro file and the args the file declares."""
    root = tree(tmp_path)
    path = write(tmp_path, root, model={"args": {"wheel_radus": 0.1}})
    err = error_of(path)
    assert (err.file, err.field) == (str(path), "robots[0].model.args.wheel_radus")
    assert err.message == (f"{root / 'urdf' / 'xbot.urdf.xacro'}: declares no argument "
                           "'wheel_radus' (did you mean 'wheel_radius'?); its arguments: "
                           "wheel_radius, with_lidar")
    assert main(["validate", str(path)]) == 2
    said = capsys.readouterr().err.strip()
    assert "\n" not in said and said.startswith(
        f"srr validate: {path}: robots[0].model.args.wheel_radus: ")
    # one declared in a branch xacro did not take, or only read with $(arg ...), is the file's
    main_file = root / "urdf" / "xbot.urdf.xacro"
    main_file.write_text(main_file.read_text().replace(
        '<xacro:property name="track" value="0.26"/>',
        '<xacro:property name="track" value="0.26"/>\n'
        '<xacro:if value="false"><xacro:arg name="lidar_range" default="5"/></xacro:if>\n'
        '<xacro:if value="${\'$(arg colour)\' == \'red\'}"/>'))
    build(write(tmp_path, root, model={"args": {"lidar_range": 8, "colour": "red"}}))
