"""Driving the robots through their joints, with the reference IK written out by hand.

The forklift IK is the swivel-drive script node of the forklift seed (reverse_logic flips on);
the diff-drive IK is the plain two-wheel inverse kinematics. These tests pin the joint axis
signs: positive cmd linear.x must move each robot along its own forward axis and positive
angular.z must turn it counter-clockwise seen from above.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from harness.geometry import quat_wxyz_rotate, rpy_from_quat_wxyz
from harness.scenario.schema import (
    DiffDriveControl,
    ForkliftControl,
    PhysicsSpec,
    Pose,
    RobotSpec,
    Scenario,
)
from harness.sim import World

FORKLIFT = "/World/forklift"
TB3 = "/World/tb3"


def swivel_ik(lin_x: float, ang_z: float, c: ForkliftControl) -> tuple[list[str], list[float],
                                                                         list[float]]:
    """The forklift seed's SwivelIK ScriptNode, constants taken from the control block."""
    flip_linear_x = c.reverse_logic.flip_linear_x
    flip_angular_z = c.reverse_logic.flip_angular_z
    max_steer = math.radians(c.max_steer_deg)
    min_cos, min_speed = 1e-3, 1e-4
    linear_x = -lin_x if flip_linear_x else lin_x
    angular_z = -ang_z if flip_angular_z else ang_z
    heading_speed = max(abs(linear_x), min_speed)
    steer = math.atan2(angular_z * c.wheelbase, heading_speed)
    steer = max(min(steer, max_steer), -max_steer)
    if linear_x < 0.0:
        steer = 0.0 if abs(angular_z) < min_speed else -steer
        drive = -heading_speed / max(math.cos(steer), min_cos)
    else:
        drive = heading_speed / max(math.cos(steer), min_cos)
    wheel_ang = drive / c.wheel_radius
    return [c.drive_joint, c.swivel_joint], [0.0, steer], [wheel_ang, 0.0]


def diff_ik(lin_x: float, ang_z: float, c: DiffDriveControl) -> list[float]:
    """Left/right wheel rates (rad/s) for a unicycle command."""
    half = c.wheel_distance / 2
    return [(lin_x - ang_z * half) / c.wheel_radius, (lin_x + ang_z * half) / c.wheel_radius]


def forklift_world(physics: PhysicsSpec | None = None) -> World:
    robot = RobotSpec(name="forklift", model="forklift",
                      spawn=Pose(position=(-10.0, 0.0, 0.0), rpy_deg=(0.0, 0.0, 180.0)))
    return World.build(Scenario(format_version=1, name="t", robots=(robot,),
                                physics=physics or PhysicsSpec()))


def tb3_world() -> World:
    robot = RobotSpec(name="tb3", model="turtlebot3_waffle_pi",
                      spawn=Pose(position=(0.0, -3.0, 0.0), rpy_deg=(0.0, 0.0, 90.0)))
    return World.build(Scenario(format_version=1, name="t", robots=(robot,)))


def drive_forklift(world: World, v: float, w: float, seconds: float) -> None:
    names, pos, vel = swivel_ik(v, w, ForkliftControl())
    world.apply_joint_commands(FORKLIFT, names, pos, vel)
    world.step(round(seconds / world.timestep))


def drive_tb3(world: World, v: float, w: float, seconds: float) -> None:
    c = DiffDriveControl()
    world.apply_joint_commands(f"{TB3}/base_footprint", c.joint_names, None, diff_ik(v, w, c))
    world.step(round(seconds / world.timestep))


def planar_motion(world: World, base: str, front: tuple[float, float, float],
                  p0: np.ndarray, q0: np.ndarray) -> tuple[float, float]:
    """(along forward, lateral) displacement of ``base`` since (p0, q0)."""
    p1, _ = world.prim_pose(base)
    fwd = quat_wxyz_rotate(q0, front)[:2]
    fwd /= np.linalg.norm(fwd)
    d = (p1 - p0)[:2]
    return float(d @ fwd), float(abs(d[0] * fwd[1] - d[1] * fwd[0]))


def yaw_rate(world: World, base: str, seconds: float) -> float:
    """Mean yaw rate over ``seconds`` from the unwrapped yaw at 10 Hz samples."""
    yaws = [float(rpy_from_quat_wxyz(world.prim_pose(base)[1])[2])]
    n = round(seconds * 10)
    for _ in range(n):
        world.step(round(0.1 / world.timestep))
        yaws.append(float(rpy_from_quat_wxyz(world.prim_pose(base)[1])[2]))
    return float(np.unwrap(yaws)[-1] - yaws[0]) / seconds


def test_forklift_forward_is_minus_x_and_points_along_world_x_when_yawed_180() -> None:
    world = forklift_world()
    _, q = world.prim_pose(f"{FORKLIFT}/body")
    assert world.robot_front("forklift") == (-1.0, 0.0, 0.0)
    np.testing.assert_allclose(quat_wxyz_rotate(q, world.robot_front("forklift")), [1, 0, 0],
                               atol=1e-9)


def test_forklift_drives_straight_forward() -> None:
    world = forklift_world()
    base = world.base_prim("forklift")
    p0, q0 = world.prim_pose(base)
    drive_forklift(world, 1.0, 0.0, 4.0)
    along, lateral = planar_motion(world, base, world.robot_front("forklift"), p0, q0)
    assert along == pytest.approx(4.0, rel=0.15)
    assert lateral < 0.2
    p1, q1 = world.prim_pose(base)
    assert abs(p1[2] - p0[2]) < 0.1
    roll, pitch, _ = np.degrees(rpy_from_quat_wxyz(q1))
    assert abs(roll) < 5 and abs(pitch) < 5
    assert p1[0] > p0[0]  # yaw 180°: forward is world +X


def test_forklift_turns_counter_clockwise_for_positive_angular_z() -> None:
    world = forklift_world()
    base = world.base_prim("forklift")
    drive_forklift(world, 1.0, 0.3, 1.0)  # transient
    rate = yaw_rate(world, base, 2.0)
    assert rate == pytest.approx(0.3, rel=0.2)
    _, q = world.prim_pose(base)
    roll, pitch, _ = np.degrees(rpy_from_quat_wxyz(q))
    assert abs(roll) < 5 and abs(pitch) < 5


def test_forklift_reverses_and_tracks_steering() -> None:
    world = forklift_world()
    base = world.base_prim("forklift")
    p0, q0 = world.prim_pose(base)
    drive_forklift(world, -0.5, 0.0, 2.0)
    along, lateral = planar_motion(world, base, world.robot_front("forklift"), p0, q0)
    assert along == pytest.approx(-1.0, rel=0.2)
    assert lateral < 0.1
    names, pos, vel = swivel_ik(1.0, 0.3, ForkliftControl())
    world.apply_joint_commands(FORKLIFT, names, pos, vel)
    world.step(round(0.5 / world.timestep))
    steer, _ = world.joint_state(FORKLIFT, "back_wheel_swivel")
    assert steer == pytest.approx(pos[1], abs=math.radians(3))


@pytest.mark.parametrize("integrator", ["euler", "rk4"])
def test_forklift_drives_with_other_integrators(integrator: str) -> None:
    world = forklift_world(PhysicsSpec(integrator=integrator))  # type: ignore[arg-type]
    base = world.base_prim("forklift")
    p0, q0 = world.prim_pose(base)
    drive_forklift(world, 1.0, 0.0, 2.0)
    along, _ = planar_motion(world, base, world.robot_front("forklift"), p0, q0)
    assert along == pytest.approx(2.0, rel=0.2)


def test_turtlebot_drives_straight_forward() -> None:
    world = tb3_world()
    base = world.base_prim("tb3")
    p0, q0 = world.prim_pose(base)
    drive_tb3(world, 0.2, 0.0, 3.0)
    along, lateral = planar_motion(world, base, world.robot_front("tb3"), p0, q0)
    assert along == pytest.approx(0.6, rel=0.15)
    assert lateral < 0.05
    p1, q1 = world.prim_pose(base)
    assert p1[1] > p0[1]  # yaw 90°: forward is world +Y
    assert abs(p1[2] - p0[2]) < 0.01
    roll, pitch, _ = np.degrees(rpy_from_quat_wxyz(q1))
    assert abs(roll) < 2 and abs(pitch) < 2


def test_turtlebot_turns_counter_clockwise_for_positive_angular_z() -> None:
    world = tb3_world()
    base = world.base_prim("tb3")
    drive_tb3(world, 0.0, 1.0, 0.5)
    assert yaw_rate(world, base, 1.5) == pytest.approx(1.0, rel=0.2)
    lin, ang = world.prim_velocity(base)
    assert np.linalg.norm(lin[:2]) < 0.05  # spinning in place
    assert ang[2] == pytest.approx(1.0, rel=0.2)


def _rollout(world: World, turn: float = 0.4) -> bytes:
    c = ForkliftControl()
    for k in range(120):
        names, pos, vel = swivel_ik(0.5 + 0.01 * k, turn * math.sin(k / 10), c)
        world.apply_joint_commands(FORKLIFT, names, pos, vel)
        world.step(4)
    return bytes(world.data.qpos.tobytes() + world.data.qvel.tobytes())


def test_two_builds_and_a_reset_give_bit_identical_states() -> None:
    first = forklift_world()
    a = _rollout(first)
    b = _rollout(forklift_world())
    assert a == b
    first.reset()
    assert _rollout(first) == a
    assert a != _rollout(forklift_world(), turn=0.4 + 1e-9)  # the comparison can fail


def test_report_physics_only_real_time_factor() -> None:
    world = forklift_world()
    names, pos, vel = swivel_ik(1.0, 0.2, ForkliftControl())
    world.apply_joint_commands(FORKLIFT, names, pos, vel)
    ticks = 240  # 4 s of sim time at 60 Hz, 4 substeps each
    start = time.perf_counter()
    for _ in range(ticks):
        world.step(4)
    wall = time.perf_counter() - start
    sim = ticks * 4 * world.timestep
    print(f"\nforklift scene, physics only: {sim / wall:.0f} sim s per wall s "
          f"({sim:.1f} s in {wall * 1000:.0f} ms)")
