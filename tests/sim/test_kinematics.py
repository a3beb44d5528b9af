"""A robot's control block against its compiled model (harness.sim.kinematics): wheel radius,
wheel distance, wheelbase, left/right order and wheel axes, said by ``srr validate`` and
``srr run`` as one line each (a warning, or exit 2 for wheels listed right before left), and
nothing said of a block that agrees with its model. The robots are small URDF and MJCF files
written here."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
import yaml

from harness.cli import main
from harness.geometry import yaw_between
from harness.scenario import load_scenario
from harness.scenario.schema import DiffDriveControl
from harness.sim import World
from harness.sim.kinematics import TOLERANCE, base_axes, measure_wheel
from tests.conftest import SCENARIOS

#: The wheel's collision shape in a link (URDF), axle along the link's +Y.
CYLINDER = '<origin rpy="1.5707963267948966 0 0"/><geometry><cylinder radius="{r}" ' \
           'length="0.03"/></geometry>'
SPHERE = '<geometry><sphere radius="{r}"/></geometry>'
MESH = '<geometry><mesh filename="wheel.obj"/></geometry>'
INERTIA = '<inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/>'


def diff_urdf(*, radius: float = 0.05, half_track: float = 0.2, shape: str = CYLINDER,
              left_axis: str = "0 1 0", right_axis: str = "0 1 0", facing: int = 1) -> str:
    """A differential-drive robot, base_footprint on the floor: wheels ``wheel_left_joint``
    and ``wheel_right_joint`` ``half_track`` m either side of it on an axle ``radius`` up,
    a ball caster behind. ``facing -1``: the robot faces -X (its left wheel at -Y)."""
    def wheel(side: str, y: float, axis: str) -> str:
        return (f'<joint name="wheel_{side}_joint" type="continuous"><parent link="base_link"/>'
                f'<child link="wheel_{side}_link"/><origin xyz="0 {y} 0"/>'
                f'<axis xyz="{axis}"/></joint>'
                f'<link name="wheel_{side}_link"><inertial><mass value="0.2"/>{INERTIA}'
                f'</inertial><collision>{shape.format(r=radius)}</collision></link>')
    return (f'<robot name="bot"><link name="base_footprint"/>'
            f'<joint name="base_joint" type="fixed"><parent link="base_footprint"/>'
            f'<child link="base_link"/><origin xyz="0 0 {radius}"/></joint>'
            f'<link name="base_link"><inertial><mass value="3.0"/>'
            f'<inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial>'
            f'<collision><origin xyz="0 0 0.06"/><geometry><box size="0.3 0.3 0.06"/>'
            f'</geometry></collision></link>'
            + wheel("left", facing * half_track, left_axis)
            + wheel("right", -facing * half_track, right_axis)
            + f'<joint name="caster_joint" type="fixed"><parent link="base_link"/>'
              f'<child link="caster_link"/><origin xyz="{-facing * 0.12} 0 {0.02 - radius}"/>'
              f'</joint><link name="caster_link"><inertial><mass value="0.05"/>{INERTIA}'
              f'</inertial><collision><geometry><sphere radius="0.02"/></geometry>'
              f'</collision></link></robot>')


def wheel_obj(radius: float, sides: int = 24) -> str:
    """A wheel mesh (OBJ): a ``sides``-gon prism of circumradius ``radius``, 3 cm wide,
    axle along +Y."""
    rim = [(radius * math.cos(2 * math.pi * k / sides), radius * math.sin(2 * math.pi * k / sides))
           for k in range(sides)]
    verts = [f"v {x:.6f} {y:g} {z:.6f}" for y in (-0.015, 0.015) for x, z in rim]
    faces = [f"f {a + 1} {b + 1} {c + 1}" for k in range(sides)
             for a, b, c in ((k, (k + 1) % sides, sides + k),
                             ((k + 1) % sides, sides + (k + 1) % sides, sides + k))]
    return "\n".join(verts + faces) + "\n"


def scene(tmp: Path, robot: dict[str, Any], urdf: str | None = None, *,
          driven: bool = True) -> Path:
    """A scenario of ``robot`` (``driven``: a teleop drives it, so the wiring has nothing to
    say), with ``urdf`` written as ``bot.urdf`` beside it."""
    if urdf is not None:
        (tmp / "bot.urdf").write_text(urdf)
    teleop = {"name": "teleop", "plugin": "harness.sut.teleop:ScriptedTeleop", "robot": "bot",
              "params": {"segments": [{"duration": 0.5, "linear": 0.1}]}}
    path = tmp / "scene.yaml"
    path.write_text(yaml.safe_dump({
        "format_version": 1, "name": "kin", "duration": 0.5,
        "world": {"size": [8.0, 6.0], "shelves": [], "dock": {"enabled": False}},
        "robots": [{"name": "bot", **robot}],
        "systems_under_test": [teleop] if driven else [],
        "scoring": {"record_only": True}}))
    return path


def file_robot(**control: Any) -> dict[str, Any]:
    return {"model": {"urdf": "bot.urdf", "frictionless_links": ["caster_link"]},
            **({"control": control} if control else {})}


MATCHING = {"joint_names": ["wheel_left_joint", "wheel_right_joint"], "wheel_radius": 0.05,
            "wheel_distance": 0.4}


def validate(capsys: pytest.CaptureFixture[str], path: Path) -> tuple[int, list[str]]:
    code = main(["validate", str(path)])
    return code, capsys.readouterr().err.splitlines()


# ------------------------------------------------------------------ differential drive

@pytest.mark.parametrize("shape", [CYLINDER, SPHERE, MESH], ids=["cylinder", "sphere", "mesh"])
def test_a_block_within_5_percent_of_its_urdf_says_nothing_and_beyond_it_warns(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], shape: str) -> None:
    (tmp_path / "wheel.obj").write_text(wheel_obj(0.05))
    path = scene(tmp_path, file_robot(**MATCHING), diff_urdf(shape=shape))
    assert validate(capsys, path) == (0, [])
    # within 5 % (a calibrated rolling radius, a rounded track): still nothing
    near = scene(tmp_path, file_robot(**{**MATCHING, "wheel_radius": 0.048,
                                         "wheel_distance": 0.41}))
    assert validate(capsys, near) == (0, [])
    kind = {CYLINDER: "cylinder", SPHERE: "sphere", MESH: "mesh"}[shape]
    beyond = scene(tmp_path, file_robot(**{**MATCHING, "wheel_radius": 0.053}))
    assert validate(capsys, beyond) == (0, [
        f"srr validate: warning: {beyond}: robots[0].control.wheel_radius: 0.053 m, but the "
        f"model's wheel_left_joint wheel is 0.050 m (collision {kind} of link "
        "wheel_left_link), so the robot drives and turns at 0.94× what cmd_vel asks for"])


def test_wheels_are_placed_by_their_shapes_not_their_joints_anchors(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # both wheel joints at the chassis origin, each wheel's cylinder set off to its side in
    # its link: a hinge turns its wheel alike wherever it sits along its own axis
    urdf = diff_urdf()
    for side, y in (("left", 0.2), ("right", -0.2)):
        urdf = urdf.replace(f'<child link="wheel_{side}_link"/><origin xyz="0 {y} 0"/>',
                            f'<child link="wheel_{side}_link"/><origin xyz="0 0 0"/>')
        urdf = urdf.replace(
            f'<link name="wheel_{side}_link"><inertial><mass value="0.2"/>{INERTIA}</inertial>'
            '<collision><origin rpy="1.5707963267948966 0 0"/>',
            f'<link name="wheel_{side}_link"><inertial><mass value="0.2"/>{INERTIA}</inertial>'
            f'<collision><origin xyz="0 {y} 0" rpy="1.5707963267948966 0 0"/>')
    assert urdf.count('<origin xyz="0 0 0"/>') == 2 and urdf.count('xyz="0 0.2 0" rpy') == 1
    path = scene(tmp_path, file_robot(**MATCHING), urdf)
    assert validate(capsys, path) == (0, [])
    swapped = scene(tmp_path, file_robot(**{**MATCHING, "joint_names": [
        "wheel_right_joint", "wheel_left_joint"]}))
    code, err = validate(capsys, swapped)
    assert code == 2 and "names the right wheel first" in err[0], err


def test_the_turtlebot3_defaults_under_a_bigger_urdf_robot_are_warned_of(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The story: wheels 0.05 m in radius 0.40 m apart, the control block left at the
    TurtleBot3's 0.033 m and 0.287 m. The robot drove at 1.52 times the speed asked and
    turned at 1.09 times the rate (1.52 × 0.72), without a word."""
    path = scene(tmp_path, file_robot(), diff_urdf())
    code, err = validate(capsys, path)
    assert code == 0
    assert err == [
        f"srr validate: warning: {path}: robots[0].control.wheel_radius: 0.033 m (the "
        "default), but the model's wheel_left_joint wheel is 0.050 m (collision cylinder of "
        "link wheel_left_link), so the robot drives and turns at 1.52× what cmd_vel asks for",
        f"srr validate: warning: {path}: robots[0].control.wheel_distance: 0.287 m (the "
        "default), but the model's wheels wheel_left_joint and wheel_right_joint are 0.400 m "
        "apart (their centres, across the robot), which alone makes the robot turn at "
        "0.72× the rate cmd_vel asks for",
    ]


def test_a_mesh_wheel_is_measured_by_its_farthest_vertex_from_the_axle(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "wheel.obj").write_text(wheel_obj(0.08))
    path = scene(tmp_path, file_robot(**MATCHING), diff_urdf(radius=0.08, shape=MESH))
    code, err = validate(capsys, path)
    assert code == 0
    assert err == [f"srr validate: warning: {path}: robots[0].control.wheel_radius: 0.05 m, "
                   "but the model's wheel_left_joint wheel is 0.080 m (collision mesh of link "
                   "wheel_left_link), so the robot drives and turns at 1.60× what cmd_vel asks for"]


@pytest.mark.parametrize("command", ["validate", "run"])
def test_wheels_listed_right_before_left_are_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str) -> None:
    path = scene(tmp_path, file_robot(**{**MATCHING, "joint_names": [
        "wheel_right_joint", "wheel_left_joint"]}), diff_urdf())
    out = tmp_path / "out"
    extra = ["--out", str(out), "-q"] if command == "run" else []
    assert main([command, str(path), *extra]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"srr {command}: {path}: robots[0].control.joint_names: [wheel_right_joint, "
        "wheel_left_joint] names the right wheel first: wheel_right_joint is 0.200 m right "
        "and wheel_left_joint is 0.200 m left of base_footprint's origin (left +Y, forward "
        "+X); the controller drives the first joint as the left wheel, so the robot would "
        "turn against cmd_vel: write [wheel_left_joint, wheel_right_joint]"]
    assert not out.exists()


def test_left_and_right_follow_odometry_robot_front(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A robot built facing -X (its left wheel at -Y, axles along -Y so a positive rate rolls
    it towards -X): right as it is with ``robot_front: [-1, 0, 0]``, wheels swapped without."""
    urdf = diff_urdf(facing=-1, left_axis="0 -1 0", right_axis="0 -1 0")
    path = scene(tmp_path, {**file_robot(**MATCHING),
                            "odometry": {"robot_front": [-1.0, 0.0, 0.0]}}, urdf)
    assert validate(capsys, path) == (0, [])
    path = scene(tmp_path, file_robot(**MATCHING))
    code, err = validate(capsys, path)
    assert code == 2 and err[0].startswith(
        f"srr validate: {path}: robots[0].control.joint_names: [wheel_left_joint, "
        "wheel_right_joint] names the right wheel first: ")


@pytest.mark.parametrize("front", [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
def test_a_robot_front_with_no_horizontal_part_is_refused(
        front: list[float], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Odometry turns ``robot_front`` onto +X as a yaw, so an upright or zero one names no
    forward direction (odometry took it as +X, the control-block check skipped the robot)."""
    path = scene(tmp_path, {**file_robot(**MATCHING), "odometry": {"robot_front": front}},
                 diff_urdf())
    code, err = validate(capsys, path)
    assert code == 2 and err == [
        f"srr validate: {path}: robots[0].odometry.robot_front: {front} has no part along "
        "the floor: it is the chassis axis that points forward (as [1, 0, 0], or [-1, 0, 0] "
        "for a model that faces -x); odometry turns it onto +x as a yaw"]


def test_the_check_s_forward_axis_is_odometry_s_yaw() -> None:
    """A front with an upward part points where its horizontal part does, as odometry's yaw
    (``yaw_between``) has it."""
    path = SCENARIOS / "turtlebot3_room.yaml"
    sc = load_scenario(path)
    world = World.build(sc, str(path))
    info = world.robot(sc.robots[0].name)
    body = world.prim_ref(info.base_prim).id
    for front in ((1.0, 1.0, 5.0), (-2.0, 0.0, -1.0), (0.0, -0.5, 0.3)):
        yaw = yaw_between(front)
        base = base_axes(world.model, world.data, body, front, "")
        assert base.front == pytest.approx((math.cos(yaw), math.sin(yaw), 0.0), abs=1e-12)
        assert base.left == pytest.approx((-math.sin(yaw), math.cos(yaw), 0.0), abs=1e-12)


def test_wheel_axes_off_the_lateral_axis_or_rolling_backward_are_warned_of(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The left wheel turns about the vertical (a turntable, not a wheel), the right one
    about -Y (a positive rate rolls it backward, so cmd_vel spins the robot)."""
    path = scene(tmp_path, file_robot(**MATCHING),
                 diff_urdf(shape=SPHERE, left_axis="0 0 1", right_axis="0 -1 0"))
    code, err = validate(capsys, path)
    assert code == 0
    assert err == [
        f"srr validate: warning: {path}: robots[0].control.joint_names[0]: joint "
        "'wheel_left_joint' turns about +Z in base_footprint's frame, 90.0° off the robot's "
        "lateral axis (left +Y, forward +X): a wheel's axle must run across the robot, or it "
        "does not roll where cmd_vel asks",
        f"srr validate: warning: {path}: robots[0].control.joint_names[1]: joint "
        "'wheel_right_joint' turns about -Y in base_footprint's frame, the robot's right "
        "(left +Y, forward +X), so a positive wheel rate rolls it backward; the controller "
        "needs both wheels to roll forward on positive rates: turn the joint's axis round in "
        "the model",
    ]


def test_a_cylinder_across_the_axle_is_not_measured(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A URDF cylinder without the turn onto the axle stands upright: it is no round wheel
    about the joint's axis, and no radius is claimed from it (turned, it is measured)."""
    upright = '<geometry><cylinder radius="{r}" length="0.03"/></geometry>'
    control = {**MATCHING, "wheel_radius": 0.2}
    path = scene(tmp_path, file_robot(**control), diff_urdf(shape=upright))
    assert validate(capsys, path) == (0, [])
    path = scene(tmp_path, file_robot(**control), diff_urdf(shape=CYLINDER))
    code, err = validate(capsys, path)
    assert code == 0 and [line.split(": ")[3] for line in err] == [
        "robots[0].control.wheel_radius"]


def test_the_built_in_turtlebot3_is_checked_too(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    robot = {"model": "turtlebot3_waffle_pi", "control": {"wheel_radius": 0.066}}
    path = scene(tmp_path, robot)
    assert validate(capsys, path) == (0, [
        f"srr validate: warning: {path}: robots[0].control.wheel_radius: 0.066 m, but the "
        "model's wheel_left_joint wheel is 0.033 m (collision sphere of link wheel_left_link), "
        "so the robot drives and turns at 0.50× what cmd_vel asks for"])
    path = scene(tmp_path, {"model": "turtlebot3_waffle_pi", "control": {
        "joint_names": ["wheel_right_joint", "wheel_left_joint"]}})
    code, err = validate(capsys, path)
    assert code == 2 and "robots[0].control.joint_names: [wheel_right_joint, " \
        "wheel_left_joint] names the right wheel first: wheel_right_joint is 0.144 m right" \
        in err[0]


def test_a_parked_robot_s_block_is_not_checked(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``control.enabled: false``: no graph turns cmd_vel into wheel rates with the block."""
    swapped = {"joint_names": ["wheel_right_joint", "wheel_left_joint"]}
    path = scene(tmp_path, file_robot(enabled=False, **swapped), diff_urdf(), driven=False)
    assert validate(capsys, path) == (0, [])
    path = scene(tmp_path, file_robot(**swapped))
    assert validate(capsys, path)[0] == 2


# ------------------------------------------------------------------ swivel drive

TRUCK = """<mujoco model="truck">
  <worldbody>
    <body name="chassis">
      <inertial pos="0 0 0.4" mass="400" diaginertia="60 100 110"/>
      <geom name="frame" type="box" size="0.8 0.45 0.2" pos="0 0 0.45"/>
      <body name="axle_left" pos="0.5 0.35 0.1">
        <inertial pos="0 0 0" mass="10" diaginertia="0.05 0.08 0.05"/>
        <joint name="axle_left_hinge" type="hinge" axis="0 1 0"/>
        <geom type="sphere" size="0.1"/>
      </body>
      <body name="axle_right" pos="0.5 -0.35 0.1">
        <inertial pos="0 0 0" mass="10" diaginertia="0.05 0.08 0.05"/>
        <joint name="axle_right_hinge" type="hinge" axis="0 1 0"/>
        <geom type="sphere" size="0.1"/>
      </body>
      <body name="steer_link" pos="-0.5 0 0.1">
        <inertial pos="0 0 0" mass="5" diaginertia="0.1 0.1 0.1"/>
        <joint name="steer" type="hinge" axis="0 0 1" range="-50 50"/>
        <body name="drive_wheel">
          <inertial pos="0 0 0" mass="10" diaginertia="0.05 0.08 0.05"/>
          <joint name="traction" type="hinge" axis="0 {drive_y} 0"/>
          <geom type="cylinder" size="0.1 0.04" euler="90 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
  <contact><exclude body1="chassis" body2="drive_wheel"/></contact>
</mujoco>
"""
TRUCK_CONTROL = {"drive_joint": "traction", "swivel_joint": "steer", "wheelbase": 1.0,
                 "wheel_radius": 0.1,
                 "reverse_logic": {"flip_linear_x": False, "flip_angular_z": False}}


def truck(tmp: Path, drive_y: int = 1, **control: Any) -> Path:
    (tmp / "truck.xml").write_text(TRUCK.replace("{drive_y}", str(drive_y)))
    return scene(tmp, {"model": {"mjcf": "truck.xml", "drive": "swivel_drive"},
                       "control": {**TRUCK_CONTROL, **control}})


def test_a_swivel_drive_block_that_agrees_with_its_model_says_nothing(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert validate(capsys, truck(tmp_path)) == (0, [])
    # the drive axle the other way round, and the block says so
    flipped = {"flip_linear_x": True, "flip_angular_z": False}
    assert validate(capsys, truck(tmp_path, drive_y=-1, reverse_logic=flipped)) == (0, [])
    # ... or does not
    path = truck(tmp_path, drive_y=-1)
    assert validate(capsys, path) == (0, [
        f"srr validate: warning: {path}: robots[0].control.reverse_logic.flip_linear_x: "
        "false, but joint 'traction' turns about -Y in chassis's frame (left +Y, forward +X), "
        "so a positive wheel rate rolls the robot backward and a positive cmd_vel.linear.x "
        "drives it backward: set it to true"])


def test_the_forklift_defaults_under_another_swivel_drive_are_warned_of(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The forklift's block (wheelbase 1.49 m, wheel 0.15 m, linear x flipped) on a truck
    with a 1.0 m wheelbase, 0.1 m wheels and a drive that rolls forward on positive rates."""
    (tmp_path / "truck.xml").write_text(TRUCK.replace("{drive_y}", "1"))
    path = scene(tmp_path, {"model": {"mjcf": "truck.xml", "drive": "swivel_drive"},
                            "control": {"drive_joint": "traction", "swivel_joint": "steer"}})
    code, err = validate(capsys, path)
    assert code == 0
    assert err == [
        f"srr validate: warning: {path}: robots[0].control.wheel_radius: 0.15 m (the "
        "default), but the model's traction wheel is 0.100 m (collision cylinder of link "
        "drive_wheel), so the robot drives and turns at 0.67× what cmd_vel asks for",
        f"srr validate: warning: {path}: robots[0].control.wheelbase: 1.49 m (the default), "
        "but the model's drive wheel traction is 1.000 m from the axle of axle_left_hinge and "
        "axle_right_hinge (along the robot), which alone makes the robot turn at 1.49× the "
        "rate cmd_vel asks for",
        f"srr validate: warning: {path}: robots[0].control.reverse_logic.flip_linear_x: true, "
        "but joint 'traction' turns about +Y in chassis's frame (left +Y, forward +X), so a "
        "positive wheel rate rolls the robot forward and a positive cmd_vel.linear.x drives "
        "it backward: set it to false",
    ]


def test_without_an_axle_of_passive_wheels_the_wheelbase_is_not_claimed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Load wheels welded to the chassis (no joints): nothing says where the axle is. On
    hinges, they are the axle."""
    path = truck(tmp_path, wheelbase=3.0)
    code, err = validate(capsys, path)
    assert code == 0 and [line.split(": ")[3] for line in err] == ["robots[0].control.wheelbase"]
    text = (tmp_path / "truck.xml").read_text()
    for side in ("left", "right"):
        text = text.replace(f'<joint name="axle_{side}_hinge" type="hinge" axis="0 1 0"/>', "")
    (tmp_path / "truck.xml").write_text(text)
    assert validate(capsys, path) == (0, [])


# ------------------------------------------------------------------ bundled and run

def test_the_bundled_robots_agree_with_their_control_blocks() -> None:
    """Every bundled scenario's robots (built-in and from model files) build without a word,
    and not for want of something to measure: each one's driven wheel has a radius, within
    5 % of its block's (the built-in models' defaults agree with the models)."""
    paths = sorted(SCENARIOS.glob("*.yaml")) + sorted(SCENARIOS.glob("regressions/*.yaml")) \
        + sorted(SCENARIOS.glob("planted/*.yaml"))
    assert len(paths) > 10
    for path in paths:
        sc = load_scenario(path)
        world = World.build(sc, str(path))
        assert world.warnings == (), path
        for robot in (r for r in sc.robots if r.enabled):
            info, control = world.robot(robot.name), robot.control_spec
            front = robot.odometry.robot_front or info.robot_front
            base = base_axes(world.model, world.data, world.prim_ref(info.base_prim).id,
                             front, f"{robot.name}/")
            joint = (control.joint_names[0] if isinstance(control, DiffDriveControl)
                     else control.drive_joint)
            wheel = measure_wheel(world.model, world.data, info.joints[joint].joint_id, base,
                                  f"{robot.name}/")
            assert wheel.radius == pytest.approx(control.wheel_radius, rel=TOLERANCE), path


@pytest.mark.slow
def test_srr_run_says_it_and_keeps_it_in_the_summary(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = scene(tmp_path, file_robot(**{**MATCHING, "wheel_radius": 0.04}), diff_urdf())
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "-q"]) == 0
    warning = (f"{path}: robots[0].control.wheel_radius: 0.04 m, but the model's "
               "wheel_left_joint wheel is 0.050 m (collision cylinder of link "
               "wheel_left_link), so the robot drives and turns at 1.25× what cmd_vel asks for")
    assert f"srr run: warning: {warning}" in capsys.readouterr().err.splitlines()
    assert json.loads((out / "summary.json").read_text())["warnings"] == [warning]
