"""Lidar graph nodes and the per-robot lidar graph: rate gate, message contents, both node
styles (RTX helper, PhysX ReadLidarBeams + PublishLaserScan), namespaces, seeded noise."""

from __future__ import annotations

import math
from collections import defaultdict
from typing import Any

import numpy as np
import pytest

import harness.graph as og
from harness.builders.robot_sensors import gate_step, lidar_graph_path
from harness.bus import Bus, Envelope
from harness.engine import EvalContext, Simulation
from harness.graph.errors import GraphError
from harness.scenario.schema import (
    ClockSpec,
    DiffDriveControl,
    DockSpec,
    LidarSpec,
    OdometrySpec,
    Pose,
    RobotSpec,
    Scenario,
    SensorsSpec,
    TfTreeSpec,
    WorldSpec,
)
from harness.serde.messages import deserialize, serialize
from harness.sim import World
from harness.sim.lidar import Lidar, LidarConfig

HALF = 3.0
ROOM = WorldSpec(size=(2 * HALF, 2 * HALF), wall_height=1.0, shelves=(),
                 dock=DockSpec(enabled=False))
LIDAR_PRIM = "/World/tb3/base_scan/lidar"


def robot(lidar: LidarSpec, *, namespace: str = "", x: float = 0.0) -> RobotSpec:
    return RobotSpec(name="tb3", model="turtlebot3_waffle_pi", namespace=namespace,
                     spawn=Pose(position=(x, 0.0, 0.0)),
                     control=DiffDriveControl(enabled=False),
                     odometry=OdometrySpec(enabled=False), tf_tree=TfTreeSpec(enabled=False),
                     sensors=SensorsSpec(lidar=lidar))


def scenario(lidar: LidarSpec, *, seed: int = 0, **kw: Any) -> Scenario:
    return Scenario(format_version=1, name="lidar", seed=seed, world=ROOM,
                    clock=ClockSpec(enabled=False), robots=(robot(lidar, **kw),))


def run(sc: Scenario, ticks: int) -> tuple[Simulation, dict[str, list[Envelope]]]:
    sim = Simulation(sc)
    got: dict[str, list[Envelope]] = defaultdict(list)
    sim.add_tap(lambda env: got[env.topic].append(env))
    sim.run(ticks)
    return sim, got


def test_builder_wires_a_gated_lidar_helper() -> None:
    sim = Simulation(scenario(LidarSpec(fps=5.0)))
    path = lidar_graph_path(sim.scenario.robots[0])
    assert path == "/World/tb3_LidarGraph" and path in sim.graph_paths
    graph = sim.stage.graph(path)
    nodes = {n.name: n for n in graph.nodes}
    assert nodes["LidarHelper"].type_name == "isaacsim.ros2.bridge.ROS2RtxLidarHelper"
    assert nodes["SimulationGate"].values["inputs:step"] == 12
    assert nodes["CreateRenderProduct"].values["inputs:cameraPrim"] == (LIDAR_PRIM,)
    assert {(c.src, c.dst) for c in graph.connections} >= {
        ("OnPlaybackTick.outputs:tick", "SimulationGate.inputs:execIn"),
        ("SimulationGate.outputs:execOut", "CreateRenderProduct.inputs:execIn"),
        ("CreateRenderProduct.outputs:renderProductPath", "LidarHelper.inputs:renderProductPath"),
        ("ReadSimTime.outputs:simulationTime", "LidarHelper.inputs:timeStamp")}
    assert gate_step(60, 30.0) == 2 and gate_step(60, 7.0) == 9 and gate_step(60, 120.0) == 1


def test_scan_message_reads_the_walls_and_survives_cdr() -> None:
    sc = scenario(LidarSpec(beams=360, range_max=3.5, frame_id="base_scan", fps=60.0), x=1.0)
    _, got = run(sc, 2)
    (first, second) = got["/scan"]
    assert first.msgtype == "sensor_msgs/msg/LaserScan"
    msg = deserialize(serialize(first.msg, first.msgtype), first.msgtype)
    assert msg.header.frame_id == "base_scan"
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 0)
    assert second.msg.header.stamp.nanosec == 1_000_000_000 // 60
    assert msg.angle_min == 0.0
    assert msg.angle_increment == pytest.approx(2 * math.pi / 360, rel=1e-6)
    assert msg.angle_max == pytest.approx(2 * math.pi * 359 / 360, rel=1e-6)
    assert (msg.range_min, msg.range_max) == pytest.approx((0.12, 3.5))
    assert msg.time_increment == 0.0 and msg.scan_time == pytest.approx(1 / 60)
    ranges = np.asarray(msg.ranges)
    sx = 1.0 - 0.064
    assert ranges[0] == pytest.approx(HALF - sx, abs=1e-5)  # east wall ahead
    assert ranges[90] == pytest.approx(HALF, abs=1e-5)  # north wall
    assert ranges[180] == np.inf  # west wall 3.936 m behind, beyond range_max
    assert np.asarray(msg.intensities)[180] == 0.0 and np.asarray(msg.intensities)[0] == 1.0


@pytest.mark.parametrize(("fps", "expected"), [(60.0, 60), (30.0, 30), (5.0, 5)])
def test_gate_step_sets_the_scan_rate(fps: float, expected: int) -> None:
    _, got = run(scenario(LidarSpec(beams=8, fps=fps)), 60)
    scans = got["/scan"]
    assert len(scans) == expected  # step 2 halves the count of step 1
    stamps = [e.msg.header.stamp.sec * 10**9 + e.msg.header.stamp.nanosec for e in scans]
    step = gate_step(60, fps)
    assert stamps == [i * step * 10**9 // 60 for i in range(expected)]  # ticks 0, step, ...


def test_namespace_applies_to_the_topic() -> None:
    _, got = run(scenario(LidarSpec(beams=8), namespace="robot1"), 1)
    assert list(got) == ["/robot1/scan"]
    _, got = run(scenario(LidarSpec(beams=8, topic="/front_scan"), namespace="robot1"), 1)
    assert list(got) == ["/front_scan"]


def test_point_cloud_type_publishes_xyz_float32_in_the_lidar_frame() -> None:
    sc = scenario(LidarSpec(beams=36, type="point_cloud", range_max=10.0, topic="cloud",
                            frame_id="base_scan"))
    _, got = run(sc, 1)
    (env,) = got["/cloud"]
    assert env.msgtype == "sensor_msgs/msg/PointCloud2"
    msg = deserialize(serialize(env.msg, env.msgtype), env.msgtype)
    assert [(f.name, f.offset, f.datatype, f.count) for f in msg.fields] == [
        ("x", 0, 7, 1), ("y", 4, 7, 1), ("z", 8, 7, 1)]
    assert (msg.height, msg.width, msg.point_step, msg.row_step) == (1, 36, 12, 36 * 12)
    assert not msg.is_bigendian and msg.is_dense and msg.header.frame_id == "base_scan"
    pts = np.frombuffer(bytes(msg.data), dtype="<f4").reshape(-1, 3)
    assert pts[0] == pytest.approx([HALF + 0.064, 0.0, 0.0], abs=1e-5)  # east wall, 0°
    assert pts[9] == pytest.approx([0.0, HALF, 0.0], abs=1e-5)  # north wall, 90°


def _stage_ctx(sc: Scenario) -> tuple[og.GraphStage, EvalContext]:
    world = World.build(sc)
    ctx = EvalContext(0, 0, world, Bus(lambda: ctx.time_ns), seed=sc.seed)
    return og.GraphStage(), ctx


def test_physx_pair_from_the_seed_matches_the_rtx_helper() -> None:
    """The seed's PhysX snippet, ported by changing imports, publishes the same scan as the
    RTX helper reading the same lidar."""
    sc = scenario(LidarSpec(beams=180, range_max=3.5, fps=10.0), x=0.7)
    stage, ctx = _stage_ctx(sc)
    keys = og.Controller.Keys
    with stage:
        og.Controller.edit({"graph_path": "/ActionGraph", "evaluator_name": "execution"}, {
            keys.CREATE_NODES: [
                ("ReadSimTime", "omni.isaac.core_nodes.IsaacReadSimulationTime"),
                ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
                ("ReadLidar", "omni.isaac.range_sensor.IsaacReadLidarBeams"),
                ("PublishLidar", "omni.isaac.ros_bridge.ROS1PublishLaserScan"),
                ("Helper", "omni.isaac.ros_bridge.ROS1RtxLidarHelper"),
            ],
            keys.CONNECT: [
                ("OnPlaybackTick.outputs:tick", "ReadLidar.inputs:execIn"),
                ("ReadSimTime.outputs:simulationTime", "PublishLidar.inputs:timeStamp"),
                ("ReadLidar.outputs:execOut", "PublishLidar.inputs:execIn"),
                ("ReadLidar.outputs:azimuthRange", "PublishLidar.inputs:azimuthRange"),
                ("ReadLidar.outputs:depthRange", "PublishLidar.inputs:depthRange"),
                ("ReadLidar.outputs:horizontalFov", "PublishLidar.inputs:horizontalFov"),
                ("ReadLidar.outputs:horizontalResolution",
                 "PublishLidar.inputs:horizontalResolution"),
                ("ReadLidar.outputs:intensitiesData", "PublishLidar.inputs:intensitiesData"),
                ("ReadLidar.outputs:linearDepthData", "PublishLidar.inputs:linearDepthData"),
                ("ReadLidar.outputs:numCols", "PublishLidar.inputs:numCols"),
                ("ReadLidar.outputs:numRows", "PublishLidar.inputs:numRows"),
                ("ReadLidar.outputs:rotationRate", "PublishLidar.inputs:rotationRate"),
                ("OnPlaybackTick.outputs:tick", "Helper.inputs:execIn"),
            ],
            keys.SET_VALUES: [
                ("ReadLidar.inputs:lidarPrim", LIDAR_PRIM),
                ("PublishLidar.inputs:frameId", "laser"),
                ("PublishLidar.inputs:topicName", "scan"),
                ("Helper.inputs:lidarPrim", [og.usdrt.Sdf.Path(LIDAR_PRIM)]),
                ("Helper.inputs:frameId", "laser"),
                ("Helper.inputs:topicName", "scan_rtx"),
            ],
        })
    got: dict[str, list[Any]] = defaultdict(list)
    ctx.bus.add_tap(lambda env: got[env.topic].append(env.msg))
    stage.evaluate(ctx)
    (physx,), (rtx,) = got["/scan"], got["/scan_rtx"]
    assert np.asarray(physx.ranges).tobytes() == np.asarray(rtx.ranges).tobytes()
    assert np.asarray(physx.intensities).tobytes() == np.asarray(rtx.intensities).tobytes()
    for field in ("angle_min", "angle_max", "angle_increment", "range_min", "range_max",
                  "scan_time", "time_increment"):
        assert getattr(physx, field) == pytest.approx(getattr(rtx, field), abs=1e-12), field
    assert physx.header == rtx.header
    assert np.asarray(physx.ranges)[0] == pytest.approx(HALF - 0.636, abs=1e-5)
    outputs = stage.graph("/ActionGraph").node("ReadLidar")
    assert outputs.output_value("outputs:azimuthRange") == pytest.approx((0.0, 358.0))
    assert outputs.output_value("outputs:horizontalResolution") == pytest.approx(2.0)
    assert outputs.output_value("outputs:numCols") == 180
    assert outputs.output_value("outputs:rotationRate") == 10.0


def test_noise_is_seeded_from_the_scenario_seed_and_node_path() -> None:
    spec = LidarSpec(beams=90, noise_std=0.02, fps=60.0, range_max=10.0)

    def scan_bytes(seed: int) -> bytes:
        _, got = run(scenario(spec, seed=seed), 3)
        return b"".join(np.asarray(e.msg.ranges).tobytes() for e in got["/scan"])

    a, b, c = scan_bytes(11), scan_bytes(11), scan_bytes(12)
    assert a == b
    assert a != c
    world = World.build(scenario(spec))
    true, _ = Lidar(world, LIDAR_PRIM, LidarConfig(beams=90, range_max=10.0)).true_ranges()
    first = np.frombuffer(a, dtype=np.float32)[:90]
    assert 0.005 < float(np.std(first - true)) < 0.05  # noisy, but around the truth


def test_frame_skip_count_and_enabled() -> None:
    sc = scenario(LidarSpec(beams=8, fps=60.0))
    sim = Simulation(sc)
    graph = sim.stage.graph("/World/tb3_LidarGraph")
    graph.node("LidarHelper").get_attribute("inputs:frameSkipCount").set(2)
    got: list[Envelope] = []
    sim.add_tap(got.append)
    sim.run(12)
    assert len(got) == 4
    graph.node("LidarHelper").get_attribute("inputs:enabled").set(False)
    sim.run(12)
    assert len(got) == 4


def _helper_graph(values: list[tuple[str, Any]]) -> tuple[og.GraphStage, EvalContext]:
    stage, ctx = _stage_ctx(scenario(LidarSpec(beams=8)))
    keys = og.Controller.Keys
    with stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", "omni.graph.action.OnPlaybackTick"),
                                ("Helper", "isaacsim.ros2.bridge.ROS2RtxLidarHelper")],
            keys.CONNECT: [("Tick.outputs:tick", "Helper.inputs:execIn")],
            keys.SET_VALUES: values,
        })
    return stage, ctx


@pytest.mark.parametrize(("values", "match"), [
    ([], "renderProductPath.*lidarPrim"),
    ([("Helper.inputs:lidarPrim", "/World/tb3/base_scan/lidar"),
      ("Helper.inputs:type", "depth")], "inputs:type"),
    ([("Helper.inputs:lidarPrim", "/World/tb3/base_link")], "not a mounted lidar"),
    ([("Helper.inputs:renderProductPath", "/Render/RenderProduct_missing")],
     "no render product"),
])
def test_bad_helper_settings_name_the_node(values: list[tuple[str, Any]], match: str) -> None:
    stage, ctx = _helper_graph(values)
    with pytest.raises(GraphError, match=match) as err:
        stage.evaluate(ctx)
    assert "/G/Helper" in str(err.value)


def test_lidar_link_prim_is_accepted_for_the_lidar() -> None:
    stage, ctx = _helper_graph([("Helper.inputs:lidarPrim", "/World/tb3/base_scan")])
    got: list[Envelope] = []
    ctx.bus.add_tap(got.append)
    stage.evaluate(ctx)
    assert len(got) == 1 and got[0].topic == "/scan"


def test_publish_laser_scan_refuses_mismatched_arrays() -> None:
    stage, ctx = _stage_ctx(scenario(LidarSpec(beams=8)))
    keys = og.Controller.Keys
    with stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", "omni.graph.action.OnPlaybackTick"),
                                ("Pub", "isaacsim.ros2.bridge.ROS2PublishLaserScan")],
            keys.CONNECT: [("Tick.outputs:tick", "Pub.inputs:execIn")],
            keys.SET_VALUES: [("Pub.inputs:numCols", 3), ("Pub.inputs:numRows", 1),
                              ("Pub.inputs:linearDepthData", [1.0, 2.0])],
        })
    with pytest.raises(GraphError, match="linearDepthData: 2 values for numCols=3"):
        stage.evaluate(ctx)
