"""Robots from model files: package:// lookup, errors that name the scenario file, the field
and the model file, several instances of one file, the spawn pose, the articulation's links,
and a TurtleBot3 described by a URDF driving exactly like the built-in one."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from harness import api
from harness.cli import main
from harness.errors import ScenarioError
from harness.geometry import rpy_from_quat_wxyz, yaw_from_quat_wxyz
from harness.scenario import load_scenario
from harness.sim import World
from harness.sim.robots.paths import ModelPathError, PackagePath, resolve_uri
from tests.conftest import SCENARIOS
from tests.e2e.bagread import decoded

MODELS = SCENARIOS / "models"
DIFFBOT = MODELS / "srr_diffbot" / "urdf" / "srr_diffbot.urdf"
PALLET = MODELS / "pallet_truck" / "pallet_truck.xml"
DIFFBOT_LINKS = {"base_footprint", "base_link", "left_wheel", "right_wheel", "caster_link",
                 "lidar_link"}
DIFF_CONTROL = {"joint_names": ["left_wheel_hinge", "right_wheel_hinge"], "wheel_radius": 0.05,
                "wheel_distance": 0.26}
PALLET_CONTROL = {"drive_joint": "traction_motor", "swivel_joint": "steer_hinge",
                  "wheelbase": 1.2, "wheel_radius": 0.12,
                  "reverse_logic": {"flip_linear_x": False, "flip_angular_z": False}}


def diffbot(name: str = "bot", **extra: Any) -> dict[str, Any]:
    model = {"urdf": str(DIFFBOT), "package_paths": [str(MODELS)],
             "frictionless_links": ["caster_link"]}
    model.update(extra.pop("model", {}))
    return {"name": name, "model": model, "control": dict(DIFF_CONTROL), **extra}


def pallet(name: str = "truck", **extra: Any) -> dict[str, Any]:
    model = {"mjcf": str(PALLET), "drive": "swivel_drive", **extra.pop("model", {})}
    return {"name": name, "model": model, "control": dict(PALLET_CONTROL), **extra}


def write(tmp: Path, *robots: dict[str, Any]) -> Path:
    path = tmp / "scene.yaml"
    path.write_text(yaml.safe_dump({
        "format_version": 1, "name": "models", "duration": 1.0,
        "world": {"size": [12.0, 8.0], "shelves": [], "dock": {"enabled": False}},
        "robots": list(robots)}))
    return path


def error_of(path: Path) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        api.validate(load_scenario(path), source=str(path))
    return info.value


# ------------------------------------------------------------------ package:// lookup

def test_package_uris_resolve_like_ros(tmp_path: Path) -> None:
    pkg = tmp_path / "ws" / "src" / "my_robot"
    (pkg / "meshes").mkdir(parents=True)
    renamed = tmp_path / "checkout"
    renamed.mkdir()
    (renamed / "package.xml").write_text("<package><name>other_pkg</name></package>")
    path = PackagePath.of(tmp_path, ["ws/src"], {"SRR_PACKAGE_PATH": str(renamed),
                                                 "ROS_PACKAGE_PATH": str(pkg)})
    assert path.dirs == (tmp_path / "ws/src", renamed, pkg)
    assert resolve_uri("package://my_robot/meshes/a.stl", tmp_path, path) == \
        pkg / "meshes" / "a.stl"
    assert resolve_uri("package://other_pkg/x.obj", tmp_path, path) == renamed / "x.obj"
    assert resolve_uri("meshes/a.stl", pkg, path) == pkg / "meshes" / "a.stl"
    assert resolve_uri("file:///abs/a.stl", pkg, path) == Path("/abs/a.stl")
    # the package itself on ROS_PACKAGE_PATH is found by its directory's name
    only = PackagePath.of(tmp_path, [], {"ROS_PACKAGE_PATH": str(pkg)})
    assert resolve_uri("package://my_robot/m.stl", tmp_path, only) == pkg / "m.stl"
    with pytest.raises(ModelPathError, match=r"package 'nope'.*package path: "):
        resolve_uri("package://nope/m.stl", tmp_path, path)
    with pytest.raises(ModelPathError, match="SRR_PACKAGE_PATH or ROS_PACKAGE_PATH"):
        resolve_uri("package://nope/m.stl", tmp_path, PackagePath(()))


def test_packages_deeper_in_a_workspace_are_found_as_rospack_finds_them(tmp_path: Path
                                                                        ) -> None:
    """A package two levels down, in a folder not named after it (a repository checked out
    in a workspace), is found by its package.xml's name; nothing is found below a package,
    in an ignored or a hidden folder; file:// URIs are percent-decoded."""
    ws = tmp_path / "ws"
    deep = ws / "src" / "some_repo" / "description"
    deep.mkdir(parents=True)
    (deep / "package.xml").write_text("<package><name>real_pkg</name></package>")
    inner = deep / "vendored" / "inner_pkg"  # below a package: not a package of the path
    inner.mkdir(parents=True)
    (inner / "package.xml").write_text("<package><name>inner_pkg</name></package>")
    for skipped, marker in (("ignored", "COLCON_IGNORE"), (".hidden", None)):
        pkg = ws / "src" / skipped / "hidden_pkg"
        pkg.mkdir(parents=True)
        (pkg / "package.xml").write_text("<package><name>hidden_pkg</name></package>")
        if marker:
            (ws / "src" / skipped / marker).write_text("")
    path = PackagePath.of(tmp_path, [], {"ROS_PACKAGE_PATH": str(ws)})
    assert resolve_uri("package://real_pkg/m.stl", tmp_path, path) == deep / "m.stl"
    for name in ("inner_pkg", "hidden_pkg"):
        with pytest.raises(ModelPathError, match=f"package '{name}'"):
            resolve_uri(f"package://{name}/m.stl", tmp_path, path)
    assert resolve_uri("file:///a%20b/c.stl", tmp_path, path) == Path("/a b/c.stl")


def test_meshes_found_through_the_environment(tmp_path: Path) -> None:
    """The URDF copied elsewhere, its package:// meshes found on SRR_PACKAGE_PATH."""
    urdf = tmp_path / "robot.urdf"
    shutil.copy(DIFFBOT, urdf)
    robot = diffbot()
    robot["model"] = {"urdf": "robot.urdf"}
    path = write(tmp_path, robot)
    sc = load_scenario(path)
    err = error_of(path)
    assert err.field == "robots[0].model.urdf" and "package 'srr_diffbot'" in err.message
    assert "SRR_PACKAGE_PATH" in err.message
    world = World.build(sc, str(path), environ={"SRR_PACKAGE_PATH": str(MODELS)})
    meshes = [world.model.mesh(i).name for i in range(world.model.nmesh)]
    assert sorted(meshes) == ["bot/chassis", "bot/wheel"]  # STL and OBJ, as MuJoCo reads them


def test_paths_are_relative_to_the_file_that_holds_the_robot(tmp_path: Path) -> None:
    """A robot written in an include finds its model next to the include."""
    (tmp_path / "robots" / "urdf").mkdir(parents=True)
    shutil.copy(DIFFBOT, tmp_path / "robots" / "urdf" / "bot.urdf")
    robot = diffbot()
    robot["model"] = {"urdf": "urdf/bot.urdf", "package_paths": [str(MODELS)]}
    (tmp_path / "robots" / "fleet.yaml").write_text(yaml.safe_dump({"robots": [robot]}))
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump({"format_version": 1, "name": "inc",
                                    "include": ["robots/fleet.yaml"]}))
    sc = load_scenario(path)
    assert set(World.build(sc, str(path)).robot("bot").links) == DIFFBOT_LINKS
    (tmp_path / "robots" / "urdf" / "bot.urdf").unlink()
    err = error_of(path)
    assert err.file == str(tmp_path / "robots" / "fleet.yaml")
    assert err.field == "robots[0].model.urdf" and "robots/urdf/bot.urdf: file not found" in \
        err.message


def test_urdf_mesh_paths_are_relative_to_the_urdf_file(tmp_path: Path) -> None:
    """``../meshes/chassis.stl`` in ``desc/urdf/bot.urdf`` is ``desc/meshes/chassis.stl``,
    wherever the scenario is; the path from the scenario file is not found (the docs said
    mesh paths were relative to the scenario file)."""
    (tmp_path / "desc" / "urdf").mkdir(parents=True)
    (tmp_path / "desc" / "meshes").mkdir()
    shutil.copy(MODELS / "srr_diffbot" / "meshes" / "chassis.stl", tmp_path / "desc" / "meshes")
    urdf = tmp_path / "desc" / "urdf" / "bot.urdf"
    chassis = "package://srr_diffbot/meshes/chassis.stl"
    urdf.write_text(DIFFBOT.read_text().replace(chassis, "../meshes/chassis.stl"))
    path = write(tmp_path, diffbot(model={"urdf": "desc/urdf/bot.urdf",
                                          "package_paths": [str(MODELS)]}))
    world = World.build(load_scenario(path), str(path))
    assert "bot/chassis" in [world.model.mesh(i).name for i in range(world.model.nmesh)]
    urdf.write_text(DIFFBOT.read_text().replace(chassis, "desc/meshes/chassis.stl"))
    err = error_of(path)
    assert err.message == (f"{urdf}: mesh 'desc/meshes/chassis.stl': file not found "
                           f"({tmp_path / 'desc' / 'urdf' / 'desc' / 'meshes' / 'chassis.stl'})")


@pytest.mark.parametrize(("uri", "words"), [
    ("file://desc/meshes/chassis.stl", "is not a file:// URI of an absolute path (write "
     "file:///abs/path, or the relative path without file://)"),
    ("model://desc/meshes/chassis.stl", "model:// URIs are not read (write a "
     "package://<package>/<path> or file:///abs/path URI, or a path)"),
])
def test_a_mesh_uri_is_never_looked_up_in_the_current_directory(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
        uri: str, words: str) -> None:
    """``file://desc/meshes/chassis.stl`` was read as the relative path
    ``desc/meshes/chassis.stl`` from the current directory: found from one directory, 'file
    not found' from another. Refused from anywhere, one line, exit 2; ``file://localhost/``
    is ``file:///``."""
    (tmp_path / "desc" / "urdf").mkdir(parents=True)
    (tmp_path / "desc" / "meshes").mkdir()
    shutil.copy(MODELS / "srr_diffbot" / "meshes" / "chassis.stl", tmp_path / "desc" / "meshes")
    urdf = tmp_path / "desc" / "urdf" / "bot.urdf"
    chassis = "package://srr_diffbot/meshes/chassis.stl"
    urdf.write_text(DIFFBOT.read_text().replace(chassis, uri))
    path = write(tmp_path, diffbot(model={"urdf": "desc/urdf/bot.urdf",
                                          "package_paths": [str(MODELS)]}))
    monkeypatch.chdir(tmp_path)  # where desc/meshes/chassis.stl is
    assert main(["validate", str(path)]) == 2
    assert capsys.readouterr().err.strip() == (
        f"srr validate: {path}: robots[0].model.urdf: {urdf}: mesh {uri!r} {words}"
        if uri.startswith("file") else
        f"srr validate: {path}: robots[0].model.urdf: {urdf}: mesh {uri!r}: {words}")
    mesh = tmp_path / "desc" / "meshes" / "chassis.stl"
    urdf.write_text(DIFFBOT.read_text().replace(chassis, f"file://localhost{mesh}"))
    world = World.build(load_scenario(path), str(path))
    assert "bot/chassis" in [world.model.mesh(i).name for i in range(world.model.nmesh)]


# ------------------------------------------------------------------ bad input

ASCII_STL = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n" \
            "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n"


@pytest.mark.parametrize(("make", "field", "words"), [
    (lambda t: diffbot(model={"urdf": "missing.urdf"}), "robots[0].model.urdf",
     ["missing.urdf: file not found"]),
    (lambda t: diffbot(model={"urdf": "broken.urdf"}), "robots[0].model.urdf",
     ["broken.urdf: not well-formed XML"]),
    (lambda t: pallet(model={"mjcf": "broken.xml"}), "robots[0].model.mjcf",
     ["broken.xml: MuJoCo cannot read it as MJCF", "unrecognized element"]),
    (lambda t: diffbot(model={"urdf": "ascii.urdf"}), "robots[0].model.urdf",
     ["ascii.urdf: MuJoCo cannot build it", "ASCII", "flat.stl'"]),  # the user's mesh
    (lambda t: diffbot(model={"urdf": "nomesh.urdf"}), "robots[0].model.urdf",
     ["nomesh.urdf: mesh 'package://srr_diffbot/meshes/nope.stl': file not found"]),
    (lambda t: pallet(model={"mjcf": "two.xml"}), "robots[0].model.mjcf",
     ["two.xml: has 2 top-level bodies ('a', 'b')"]),
    (lambda t: diffbot(control={**DIFF_CONTROL,
                                "joint_names": ["left_wheel_hinge", "right_wheel_hing"]}),
     "robots[0].control.joint_names[1]",
     ["srr_diffbot.urdf has no joint 'right_wheel_hing'", "did you mean 'right_wheel_hinge'"]),
    (lambda t: diffbot(control={**DIFF_CONTROL,
                                "joint_names": ["left_wheel_hinge", "lidar_joint"]}),
     "robots[0].control.joint_names[1]",
     ["joint 'lidar_joint' of", "srr_diffbot.urdf is fixed", "a wheel must turn freely"]),
    (lambda t: diffbot(control={**DIFF_CONTROL, "joint_names": ["left_wheel_hinge"]}),
     "robots[0].control.joint_names", ["needs two wheel joints"]),
    (lambda t: pallet(control={**PALLET_CONTROL, "drive_joint": "steer_hinge",
                               "swivel_joint": "load_wheel_left_axle"}),
     "robots[0].control.drive_joint", ["is limited hinge: a wheel must turn freely"]),
    (lambda t: pallet(control={**PALLET_CONTROL, "drive_joint": "load_wheel_left_axle",
                               "swivel_joint": "traction_motor"}),
     "robots[0].control.swivel_joint",
     ["has a velocity servo ('traction_servo')", "commands it by position"]),
    (lambda t: pallet(model={"drives": {"traction_motor": {"kv": 5.0}}}),
     "robots[0].model.drives.traction_motor", ["already has actuator 'traction_servo'"]),
    (lambda t: diffbot(model={"drives": {"left_wheel_hing": {"kv": 1.0}}}),
     "robots[0].model.drives.left_wheel_hing", ["did you mean 'left_wheel_hinge'"]),
    (lambda t: diffbot(model={"drives": {"lidar_joint": {}}}),
     "robots[0].model.drives.lidar_joint", ["is fixed: only a hinge or a slide joint"]),
    (lambda t: pallet(model={"drives": {"steer_hinge": {"mode": "velocity"}}},
                      control={**PALLET_CONTROL, "swivel_joint": "steer_hinge"}),
     "robots[0].model.drives.steer_hinge",
     ["already has actuator 'steer_servo'"]),
    (lambda t: diffbot(model={"drives": {"left_wheel_hinge": {"mode": "position"}}}),
     "robots[0].model.drives.left_wheel_hinge.mode",
     ["the control block commands joint 'left_wheel_hinge' by velocity, not position"]),
    (lambda t: diffbot(model={"frictionless_links": ["castor_link"]}),
     "robots[0].model.frictionless_links[0]", ["no link 'castor_link'",
                                               "did you mean 'caster_link'"]),
    (lambda t: diffbot(sensors={"lidar": {"link": "lidar_lnk"}}), "robots[0].sensors.lidar.link",
     ["srr_diffbot.urdf has no link 'lidar_lnk'", "did you mean 'lidar_link'"]),
    (lambda t: diffbot(control={"joint_names": ["a", "b"], "wheelbase": 1.0}),
     "robots[0].control.wheelbase",  # a field of the other drive: said of the drive
     ["belongs with drive 'swivel_drive', and robots[0].model.drive is 'diff_drive' (the "
      "default); a diff_drive control block takes enabled, cmd_vel_topic, joint_names, "]),
    (lambda t: pallet(control={**PALLET_CONTROL, "joint_names": ["a", "b"]}),
     "robots[0].control.joint_names",
     ["belongs with drive 'diff_drive', and robots[0].model.drive is 'swivel_drive'; a "
      "swivel_drive control block takes enabled, cmd_vel_topic, wheelbase, "]),
    (lambda t: {"name": "fl", "model": "forklift", "control": {"wheel_distance": 1.0}},
     "robots[0].control.wheel_distance",
     ["belongs with drive 'diff_drive', and robots[0].model is 'forklift', a swivel_drive "
      "robot"]),
    (lambda t: diffbot(control={**DIFF_CONTROL, "wheelbas": 1.0}),
     "robots[0].control.wheelbas", ["unknown field"]),  # of neither drive: a typo
    (lambda t: pallet(model={"urdf": "x.urdf"}), "robots[0].model",
     ["exactly one of 'urdf', 'mjcf' and 'xacro'"]),
])
def test_bad_models_name_scenario_field_and_model_file(tmp_path: Path, make: Any, field: str,
                                                       words: list[str]) -> None:
    (tmp_path / "broken.urdf").write_text("<robot name='x'><link name='a'></robot>")
    (tmp_path / "broken.xml").write_text("<mujoco><worldbody><body><bad/></body></worldbody>"
                                         "</mujoco>")
    (tmp_path / "flat.stl").write_text(ASCII_STL)
    (tmp_path / "nomesh.urdf").write_text(DIFFBOT.read_text().replace(
        "package://srr_diffbot/meshes/chassis.stl", "package://srr_diffbot/meshes/nope.stl"))
    (tmp_path / "two.xml").write_text(
        "<mujoco><worldbody><body name='a'><geom size='0.1'/></body>"
        "<body name='b'><geom size='0.1'/></body></worldbody></mujoco>")
    (tmp_path / "ascii.urdf").write_text(
        DIFFBOT.read_text().replace("package://srr_diffbot/meshes/chassis.stl", "flat.stl"))
    path = write(tmp_path, make(tmp_path))
    err = error_of(path)
    assert (err.file, err.field) == (str(path), field)
    for word in words:
        assert word in err.message
    assert "\n" not in str(err)


#: URDF mistakes MuJoCo reads without a word or words vaguely: (text of srr_diffbot.urdf,
#: what it becomes, what the message says after ``scene.yaml: robots[0].model.urdf: ...``).
URDF_MISTAKES = [
    ('<child link="caster_link"/>', '<child link="castor_link"/>',
     "joint 'caster_joint': child link 'castor_link' does not exist (did you mean "
     "'caster_link'?)"),
    ('<parent link="base_footprint"/>', '<parent link="chassis"/>',
     "joint 'base_joint': parent link 'chassis' does not exist"),
    ('<child link="lidar_link"/>', "", "joint 'lidar_joint' has no <child link=\"...\"/>"),
    # MuJoCo made a negative mass 0 kg and took NaN; a negative inertia it refused vaguely
    ('<mass value="2.0"/>', '<mass value="-5.0"/>',
     "link 'base_link': mass -5.0 is negative (MuJoCo would make it 0 kg)"),
    ('<mass value="2.0"/>', '<mass value="nan"/>', "link 'base_link': mass 'nan' is not a "
     "finite number"),
    ('<mass value="0.01"/>', '<mass value="0.01 kg"/>', "link 'caster_link': mass '0.01 kg' "
     "is not a number"),
    ('ixx="0.00913"', 'ixx="-0.00913"', "link 'base_link': inertia ixx -0.00913 is negative"),
    # MuJoCo said "repeated URDF name:" (no name), "URDF body has multiple parents:" and "URDF
    # body not found", and took a repeated joint name, leaving the second joint nameless
    ('<link name="caster_link">', '<link name="lidar_link">',
     "two <link> elements are named 'lidar_link': a URDF's link names must be unique"),
    ('<joint name="right_wheel_hinge"', '<joint name="left_wheel_hinge"',
     "two <joint> elements are named 'left_wheel_hinge': a URDF's joint names must be unique"),
    ('<child link="lidar_link"/>', '<child link="caster_link"/>',
     "link 'caster_link' is the child of two joints, 'caster_joint' and 'lidar_joint': a link "
     "has one parent"),
    ('<parent link="base_footprint"/>', '<parent link="lidar_link"/>',
     "links lidar_link → base_link → lidar_link form a cycle (joints 'base_joint', "
     "'lidar_joint'): a URDF is a tree"),
    # MuJoCo took a link named 'world' for the world and dropped it, geometry and all
    ('"lidar_link"', '"world"', "joint 'lidar_joint': child link 'world': MuJoCo reads a URDF "
     "link named 'world' as the world itself and drops it from the robot; rename the link"),
]


@pytest.mark.parametrize(("old", "new", "words"), URDF_MISTAKES)
def test_urdf_mistakes_are_named_before_mujoco_reads_the_file(tmp_path: Path, old: str,
                                                              new: str, words: str) -> None:
    text = DIFFBOT.read_text()
    assert old in text
    (tmp_path / "bot.urdf").write_text(text.replace(old, new))
    path = write(tmp_path, diffbot(model={"urdf": "bot.urdf"}))
    err = error_of(path)
    assert (err.file, err.field) == (str(path), "robots[0].model.urdf")
    assert err.message == f"{tmp_path / 'bot.urdf'}: {words}"


@pytest.mark.parametrize("command", ["validate", "run"])
def test_a_urdf_joint_to_a_missing_link_is_one_line_and_exit_2(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str) -> None:
    """Before: MuJoCo's ``XML Error: URDF joint parent or child missing; Element 'joint',
    line 31``, naming neither the joint nor the link."""
    (tmp_path / "bot.urdf").write_text(DIFFBOT.read_text().replace(
        '<child link="caster_link"/>', '<child link="castor_link"/>'))
    path = write(tmp_path, diffbot(model={"urdf": "bot.urdf"}))
    extra = ["--out", str(tmp_path / "out"), "-q"] if command == "run" else []
    assert main([command, str(path), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"srr {command}: {path}: robots[0].model.urdf: {tmp_path / 'bot.urdf'}: "
                   "joint 'caster_joint': child link 'castor_link' does not exist (did you "
                   "mean 'caster_link'?)")
    assert not (tmp_path / "out").exists()


def test_a_binary_stl_with_more_faces_than_mujoco_reads_is_named(tmp_path: Path) -> None:
    """MuJoCo said ``stl_decoder: number of faces should be between 1 and 200000 in STL file
    '...'; perhaps this is an ASCII file?`` of a good binary file that is only too big."""
    faces = 200_001
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "big.stl").write_bytes(
        b"\0" * 80 + faces.to_bytes(4, "little") + b"\0" * (50 * faces))
    (tmp_path / "bot.urdf").write_text(DIFFBOT.read_text().replace(
        "package://srr_diffbot/meshes/chassis.stl", "meshes/big.stl"))
    path = write(tmp_path, diffbot(model={"urdf": "bot.urdf"}))
    err = error_of(path)
    assert (err.file, err.field) == (str(path), "robots[0].model.urdf")
    assert err.message == (f"{tmp_path / 'bot.urdf'}: mesh 'meshes/big.stl' has 200001 "
                           "faces, more than the 200000 MuJoCo reads; decimate it (e.g. with "
                           "Blender or meshlab)")


def test_a_link_that_collides_but_weighs_nothing_is_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The chassis at 0 kg: MuJoCo builds a robot of the wheels' and caster's 0.21 kg without
    a word. URDF allows a mass of 0 (frame links), so srr warns (``srr validate``, the run's
    summary) instead of refusing; a 0 kg link without collision geometry is not warned of."""
    (tmp_path / "bot.urdf").write_text(DIFFBOT.read_text().replace(
        '<mass value="2.0"/>', '<mass value="0"/>').replace(
        '<link name="lidar_link">',
        '<link name="lidar_link"><inertial><mass value="0"/><inertia ixx="0" ixy="0" '
        'ixz="0" iyy="0" iyz="0" izz="0"/></inertial>'))
    path = write(tmp_path, diffbot(model={"urdf": "bot.urdf"}))
    path.write_text(yaml.safe_dump({**yaml.safe_load(path.read_text()),
                                    "scoring": {"record_only": True}}))
    warning = (f"{path}: robots[0].model.urdf: {tmp_path / 'bot.urdf'}: link 'base_link' has "
               "collision geometry but a mass of 0 kg (its <inertial>), so the whole robot "
               "weighs 0.21 kg; give the link its mass")
    warnings = api.validate(load_scenario(path), source=str(path))
    assert [w for w in warnings if "weighs" in w] == [warning]
    assert main(["validate", str(path)]) == 0
    assert f"warning: {warning}" in capsys.readouterr().err
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    assert warning in json.loads((out / "summary.json").read_text())["warnings"]


def test_srr_validate_answers_a_bad_joint_with_one_line_and_exit_2(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, diffbot(control={**DIFF_CONTROL,
                                            "joint_names": ["left_wheel", "right_wheel_hinge"]}))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert err.startswith(f"srr validate: {path}: robots[0].control.joint_names[0]: ")
    assert f"{DIFFBOT} has no joint 'left_wheel' (did you mean 'left_wheel_hinge'" in err


# ------------------------------------------------------------------ in the world

def test_instances_of_one_file_coexist_at_their_spawn_poses(tmp_path: Path) -> None:
    path = write(tmp_path,
                 diffbot("bot_a", spawn={"position": [1.0, 2.0, 0.0], "rpy_deg": [0, 0, 90]}),
                 diffbot("bot_b", spawn={"position": [-1.0, -2.0, 0.0]}),
                 pallet("truck", spawn={"position": [-4.0, 2.0, 0.0], "rpy_deg": [0, 0, 180]},
                        safety_indicator={"enabled": True, "indicator_prim":
                                          "/World/truck/chassis/safety_indicator"}),
                 {"name": "tb3", "model": "turtlebot3_waffle_pi",
                  "spawn": {"position": [3.0, -2.0, 0.0]}})
    sc = load_scenario(path)
    world = World.build(sc, str(path))
    for name, xy, yaw in (("bot_a", (1.0, 2.0), 90.0), ("bot_b", (-1.0, -2.0), 0.0),
                          ("truck", (-4.0, 2.0), 180.0)):
        pos, quat = world.prim_pose(world.base_prim(name))
        assert pos == pytest.approx((*xy, 0.0), abs=1e-9)
        assert math.degrees(rpy_from_quat_wxyz(quat)[2]) % 360 == pytest.approx(yaw % 360)
    a, b = world.robot("bot_a"), world.robot("bot_b")
    assert set(a.links) == set(b.links) == DIFFBOT_LINKS
    assert set(a.body_ids).isdisjoint(b.body_ids)
    assert a.base_prim == "/World/bot_a/base_footprint" and a.default_base_frame == \
        "base_footprint"
    assert tuple(a.joints) == ("left_wheel_hinge", "right_wheel_hinge")
    assert world.robot("truck").joints["steer_hinge"].mode is not None
    # the articulation root stands for every link, by parent link
    links = world.articulation_links("/World/bot_a/base_footprint")
    assert links is not None and {(p.rsplit("/", 1)[1], c.rsplit("/", 1)[1])
                                  for p, c in links} == {
        ("base_footprint", "base_link"), ("base_link", "left_wheel"),
        ("base_link", "right_wheel"), ("base_link", "caster_link"),
        ("base_link", "lidar_link")}
    assert world.articulation_links("/World/bot_a/base_link") is None  # not the root
    # the whole scene's wiring holds: four prefixed TF trees under one world
    api.validate(sc, source=str(path))
    assert world.prim_ref("/World/truck/chassis/safety_indicator").kind.value == "geom"
    # the file's own floor was not taken along; its mesh was
    names = [world.model.geom(i).name for i in range(world.model.ngeom)]
    assert "truck/mast" in names and "truck/floor" not in names


def test_a_parked_file_robot_needs_no_joint_names(tmp_path: Path) -> None:
    robot = diffbot(control={"enabled": False})
    path = write(tmp_path, robot)
    world = World.build(load_scenario(path), str(path))
    assert world.model.nu == 0 and set(world.robot("bot").joints) == {"left_wheel_hinge",
                                                                      "right_wheel_hinge"}


def test_drives_serve_any_named_joint_for_an_articulation_controller(tmp_path: Path) -> None:
    """With the control graph off, ``model.drives`` puts servos on named joints: the wheels
    (they turn freely: velocity; gains given, as a wheel's own inertia says nothing of the
    robot it pushes) and the pallet truck's load-wheel axle asked for by position (default
    gains); the file's own servos answer by their joints' names too."""
    path = write(tmp_path,
                 diffbot(control={"enabled": False},
                         model={"drives": {"left_wheel_hinge": {"kv": 0.2},
                                           "right_wheel_hinge": {"kv": 0.2}}}),
                 pallet(control={"enabled": False}, spawn={"position": [-4.0, 0.0, 0.0]},
                        model={"drives": {"load_wheel_left_axle": {"mode": "position"}}}))
    world = World.build(load_scenario(path), str(path))
    bot, truck = world.robot("bot"), world.robot("truck")
    assert {j: r.mode.value for j, r in bot.joints.items() if r.mode} == {
        "left_wheel_hinge": "velocity", "right_wheel_hinge": "velocity"}
    assert truck.joints["load_wheel_left_axle"].mode.value == "position"
    assert truck.joints["steer_hinge"].mode.value == "position"  # the file's steer_servo
    for _ in range(240):  # 1 s of 240 Hz steps
        world.apply_joint_commands("/World/bot", ["left_wheel_hinge", "right_wheel_hinge"],
                                   velocities=[4.0, 4.0])
        world.apply_joint_commands("/World/truck", ["steer_hinge", "load_wheel_left_axle"],
                                   positions=[0.4, 0.2])
        world.step(1)
    vel, _ = world.prim_velocity("/World/bot/base_footprint")
    assert vel[0] == pytest.approx(4.0 * 0.05, rel=0.05)  # wheel rate times radius
    qpos = world.data.qpos
    for joint, target in (("steer_hinge", 0.4), ("load_wheel_left_axle", 0.2)):
        assert qpos[truck.joints[joint].qposadr] == pytest.approx(target, abs=0.02)


def test_file_robot_rolls_forward_on_positive_wheel_rates(tmp_path: Path) -> None:
    path = write(tmp_path, diffbot())
    world = World.build(load_scenario(path), str(path))
    rate = 0.3 / 0.05  # 0.3 m/s
    for _ in range(120):  # 0.5 s of 240 Hz steps, commands held
        world.apply_joint_commands("/World/bot", ["left_wheel_hinge", "right_wheel_hinge"],
                                   velocities=[rate, rate])
        world.step(1)
    vel, _ = world.prim_velocity("/World/bot/base_footprint")
    assert vel[0] == pytest.approx(0.3, rel=0.05) and abs(vel[1]) < 0.01


# ------------------------------------------------------------------ built-in vs URDF

def odometry(run_dir: Path) -> np.ndarray:
    rows = []
    for topic, _, _, msg in decoded(run_dir):
        if topic == "/odom":
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            rows.append((p.x, p.y, yaw_from_quat_wxyz((q.w, q.x, q.y, q.z)),
                         msg.twist.twist.linear.x, msg.twist.twist.angular.z))
    return np.asarray(rows)


@pytest.mark.slow
def test_turtlebot3_from_urdf_drives_like_the_built_in(tmp_path: Path) -> None:
    """The same teleop script on the built-in TurtleBot3 and on its URDF twin: the same
    odometry (the models are the same bodies, masses, contacts and drives)."""
    path = SCENARIOS / "turtlebot3_urdf.yaml"
    runs = {}
    builtin = ["robots.turtlebot3.model=turtlebot3_waffle_pi"]
    for label, sets in (("urdf", []), ("builtin", builtin)):
        sc = api.load(path, overrides=sets)
        api.run_scenario(sc, source=str(path), out=tmp_path / label)
        runs[label] = odometry(tmp_path / label)
    urdf, ref = runs["urdf"], runs["builtin"]
    assert urdf.shape == ref.shape == (300, 5)
    assert np.abs(urdf - ref).max() < 1e-6
    x, y, yaw = ref[-1, :3]
    assert (x, y) == pytest.approx((0.29, 0.29), abs=0.02) and yaw == pytest.approx(
        math.pi / 2, abs=0.05)


def test_a_model_mujoco_cannot_build_names_the_robot_and_its_file(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A URDF whose only link has no inertia compiles in no scene: one line naming the
    scenario, the robot's model field and the file (exit 2), not the whole scene (exit 3)."""
    from harness.cli import main

    bare = tmp_path / "bare.urdf"
    bare.write_text('<robot name="m"><link name="base_link"/></robot>\n')
    scenario = Path(__file__).resolve().parents[2] / "scenarios" / "diffbot_urdf.yaml"
    sets = [f"robots.0.model.urdf={bare}", "robots.0.sensors={}",
            "robots.0.control.enabled=false", "robots.0.model.frictionless_links=[]",
            "scoring.control=null", "systems_under_test=[]"]
    assert main(["validate", str(scenario), *[a for s in sets for a in ("--set", s)]]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"srr validate: {scenario}: robots[0].model: {bare}: MuJoCo cannot "
                          "build the robot from it: Error: mass and inertia"), err


def test_a_robot_a_set_gives_finds_its_model_from_the_scenario_file(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A model path in a value ``--set`` gave is relative to the scenario file it was set
    on, as one written there, from any directory; an error in it is said of the flag."""
    shutil.copytree(MODELS / "srr_diffbot", tmp_path / "scene" / "srr_diffbot")
    path = write(tmp_path / "scene", pallet())
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    bot = diffbot(model={"urdf": "srr_diffbot/urdf/srr_diffbot.urdf", "package_paths": ["."]})
    sc = load_scenario(path, [("robots.0", bot)])
    api.validate(sc, source=str(path))  # found beside the scenario, not in the cwd
    bot["control"]["joint_names"] = ["left_wheel_hing", "right_wheel_hinge"]
    with pytest.raises(ScenarioError) as info:
        api.validate(load_scenario(path, [("robots.0", bot)]), source=str(path))
    assert (info.value.file, info.value.field) == ("--set", "robots[0].control.joint_names[0]")
