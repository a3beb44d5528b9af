"""IMU graph nodes and the per-robot IMU graph: specific force at rest, gyro while spinning in
place (driven by the scripted teleop through cmd_vel), gravity removal, publish flags, rate."""

from __future__ import annotations

import math
from collections import defaultdict
from typing import Any

import numpy as np
import pytest

import harness.graph as og
from harness.builders.robot_sensors import imu_graph_path
from harness.bus import Bus, Envelope
from harness.engine import EvalContext, Simulation
from harness.graph.errors import GraphError
from harness.scenario.schema import (
    ClockSpec,
    DiffDriveControl,
    DockSpec,
    ImuSpec,
    OdometrySpec,
    Pose,
    RobotSpec,
    Scenario,
    SensorsSpec,
    SutSpec,
    TfTreeSpec,
    WorldSpec,
)
from harness.serde.messages import deserialize, serialize
from harness.sim import World

ROOM = WorldSpec(size=(6.0, 6.0), wall_height=1.0, shelves=(), dock=DockSpec(enabled=False))
IMU_PRIM = "/World/tb3/imu_link/imu"
IMU_X = -0.032  # imu_link sits 32 mm behind the wheel axle (TurtleBot3 URDF)
G = 9.81


def scenario(imu: ImuSpec, *, yaw_deg: float = 0.0,
             segments: list[dict[str, float]] | None = None) -> Scenario:
    suts = ()
    if segments is not None:
        suts = (SutSpec(name="teleop", plugin="harness.sut.teleop:ScriptedTeleop",
                        params={"segments": segments, "rate_hz": 30.0}),)
    robot = RobotSpec(name="tb3", model="turtlebot3_waffle_pi",
                      spawn=Pose(position=(0.5, 0.5, 0.0), rpy_deg=(0.0, 0.0, yaw_deg)),
                      control=DiffDriveControl(enabled=segments is not None),
                      odometry=OdometrySpec(enabled=False), tf_tree=TfTreeSpec(enabled=False),
                      sensors=SensorsSpec(imu=imu))
    return Scenario(format_version=1, name="imu", world=ROOM, clock=ClockSpec(enabled=False),
                    robots=(robot,), systems_under_test=suts)


def run(sc: Scenario, ticks: int) -> tuple[Simulation, dict[str, list[Envelope]]]:
    sim = Simulation(sc)
    got: dict[str, list[Envelope]] = defaultdict(list)
    sim.add_tap(lambda env: got[env.topic].append(env))
    sim.run(ticks)
    return sim, got


def vec(v: Any) -> np.ndarray:
    return np.array([v.x, v.y, v.z])


def test_at_rest_reads_plus_g_up_zero_gyro_and_the_spawn_heading() -> None:
    sim, got = run(scenario(ImuSpec(frame_id="imu_link"), yaw_deg=60.0), 60)
    assert imu_graph_path(sim.scenario.robots[0]) in sim.graph_paths
    imu = got["/imu"]
    assert len(imu) == 60
    env = imu[-1]
    assert env.msgtype == "sensor_msgs/msg/Imu"
    msg = deserialize(serialize(env.msg, env.msgtype), env.msgtype)
    assert msg.header.frame_id == "imu_link"
    assert msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec == 59 * 10**9 // 60
    np.testing.assert_allclose(vec(msg.linear_acceleration), [0, 0, G], atol=0.05)
    np.testing.assert_allclose(vec(msg.angular_velocity), [0, 0, 0], atol=1e-3)
    q = msg.orientation  # world frame, x y z w: a 60° yaw
    np.testing.assert_allclose([q.x, q.y, q.z, q.w],
                               [0, 0, math.sin(math.pi / 6), math.cos(math.pi / 6)], atol=2e-3)
    for cov in (msg.orientation_covariance, msg.angular_velocity_covariance,
                msg.linear_acceleration_covariance):
        assert not np.asarray(cov).any()


def test_spinning_in_place_reads_the_turn_rate_and_the_centripetal_pull() -> None:
    """cmd_vel ω = 1 rad/s for 3 s: the gyro reads the chassis turn rate (≈ ω), and the
    accelerometer 32 mm behind the axle feels ω²·r towards the axle (+x)."""
    w = 1.0
    sc = scenario(ImuSpec(), segments=[{"duration": 1.0}, {"duration": 3.0, "angular": w}])
    sim = Simulation(sc)
    rows: list[tuple[float, float, float, float]] = []

    def tap(env: Envelope) -> None:
        if env.topic == "/imu":  # ground truth of the same state the IMU sampled
            _, ang = sim.world.prim_velocity("/World/tb3/imu_link")
            m = env.msg
            rows.append((env.stamp_ns / 1e9, m.angular_velocity.z, float(ang[2]),
                         m.linear_acceleration.x))

    sim.add_tap(tap)
    sim.run(4 * 60)
    t, gyro, truth, acc_x = (np.array(c) for c in zip(*rows, strict=True))
    rest = (t > 0.5) & (t < 1.0)
    spin = (t > 2.0) & (t < 4.0)
    np.testing.assert_allclose(gyro, truth, atol=1e-4)  # IMU frame vs world: tiny tilt
    assert np.mean(gyro[spin]) == pytest.approx(w, rel=0.03)
    assert np.ptp(gyro[spin]) < 0.01
    assert np.abs(gyro[rest]).max() < 1e-3
    pull = np.mean(acc_x[spin]) - np.mean(acc_x[rest])  # removes the resting tilt
    assert pull == pytest.approx(np.mean(gyro[spin]) ** 2 * -IMU_X, rel=0.1)


def test_gate_step_sets_the_imu_rate() -> None:
    _, got = run(scenario(ImuSpec(fps=30.0)), 60)
    assert len(got["/imu"]) == 30
    _, got = run(scenario(ImuSpec(fps=20.0, topic="imu/data")), 60)
    assert len(got["/imu/data"]) == 20


def _graph(values: list[tuple[str, Any]]) -> tuple[og.GraphStage, EvalContext]:
    world = World.build(scenario(ImuSpec()))
    world.step(240)  # one second at rest
    ctx = EvalContext(0, 10**9, world, Bus(lambda: ctx.time_ns))
    stage = og.GraphStage()
    keys = og.Controller.Keys
    with stage:  # the seed's add_imu, ported
        og.Controller.edit("/ActionGraph", {
            keys.CREATE_NODES: [
                ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
                ("ReadSimTime", "omni.isaac.core_nodes.IsaacReadSimulationTime"),
                ("ReadIMU", "omni.isaac.sensor.IsaacReadIMU"),
                ("PublishIMU", "omni.isaac.ros_bridge.ROS1PublishImu"),
            ],
            keys.CONNECT: [
                ("OnPlaybackTick.outputs:tick", "ReadIMU.inputs:execIn"),
                ("ReadSimTime.outputs:simulationTime", "PublishIMU.inputs:timeStamp"),
                ("ReadIMU.outputs:execOut", "PublishIMU.inputs:execIn"),
                ("ReadIMU.outputs:linAcc", "PublishIMU.inputs:linearAcceleration"),
                ("ReadIMU.outputs:angVel", "PublishIMU.inputs:angularVelocity"),
                ("ReadIMU.outputs:orientation", "PublishIMU.inputs:orientation"),
            ],
            keys.SET_VALUES: [("PublishIMU.inputs:frameId", "IMU"),
                              ("PublishIMU.inputs:topicName", "imu"), *values],
        })
    return stage, ctx


def _publish_once(values: list[tuple[str, Any]]) -> tuple[og.GraphStage, Any]:
    stage, ctx = _graph(values)
    got: list[Any] = []
    ctx.bus.add_tap(lambda env: got.append(env.msg))
    stage.evaluate(ctx)
    (msg,) = got
    return stage, msg


def test_seed_imu_graph_with_the_link_prim_and_gravity_removed() -> None:
    stage, msg = _publish_once([("ReadIMU.inputs:imuPrim", [og.usdrt.Sdf.Path(IMU_PRIM)])])
    assert msg.header.frame_id == "IMU" and msg.header.stamp.sec == 1
    assert msg.linear_acceleration.z == pytest.approx(G, abs=0.05)
    read = stage.graph("/ActionGraph").node("ReadIMU")
    assert read.output_value("outputs:sensorTime") == 1.0
    assert read.output_value("outputs:orientation")[3] == pytest.approx(1.0, abs=1e-4)

    _, msg = _publish_once([("ReadIMU.inputs:imuPrim", "/World/tb3/imu_link"),
                            ("ReadIMU.inputs:readGravity", False)])
    np.testing.assert_allclose(vec(msg.linear_acceleration), [0, 0, 0], atol=0.05)


def test_publish_flags_mark_missing_parts_with_covariance_minus_one() -> None:
    _, msg = _publish_once([("ReadIMU.inputs:imuPrim", IMU_PRIM),
                            ("PublishIMU.inputs:publishOrientation", False),
                            ("PublishIMU.inputs:publishLinearAcceleration", False)])
    assert msg.orientation_covariance[0] == -1.0
    assert msg.linear_acceleration_covariance[0] == -1.0
    assert not np.asarray(msg.angular_velocity_covariance).any()
    assert (msg.orientation.x, msg.orientation.w) == (0.0, 1.0)
    assert vec(msg.linear_acceleration).tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize(("prim", "match"), [
    ("", "imuPrim: not set"),
    ("/World/tb3/base_link", "not a mounted imu"),
])
def test_bad_imu_prim_names_the_node(prim: str, match: str) -> None:
    stage, ctx = _graph([("ReadIMU.inputs:imuPrim", prim)] if prim else [])
    with pytest.raises(GraphError, match=match) as err:
        stage.evaluate(ctx)
    assert "/ActionGraph/ReadIMU" in str(err.value)
