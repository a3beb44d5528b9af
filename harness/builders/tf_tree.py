"""TF tree graph (/World/<name>_TfGraph): world → odom, and the robot's hand-built link tree.

Both publish in the root namespace (``/tf_static``, ``/tf``, as tf2_ros broadcasters do) with
the robot's frame prefix on its own frames (never on the world frame), so several robots form
one tree under ``world``.

* ``world → odom`` on ``/tf_static``: where odometry starts (the base pose on the first tick,
  with ``robot_front`` turned onto +X), so odometry and ground truth share one tree.
* The TurtleBot3 tree of the seed, built by hand rather than from the articulation root so
  the root is ``base_footprint`` and not ``world``: ``base_footprint → base_link`` and
  ``base_link → camera_link, casters, imu_link, base_scan`` on ``/tf_static``;
  ``base_link → wheels`` on ``/tf``.
* A robot from a model file: one ``ROS2PublishTransformTree`` given the articulation root
  (the root link's prim) as target and as parent, as Isaac Sim publishes a whole robot from
  its root: every link relative to its parent link, named as in the model, on ``/tf``; the
  root's own pose is odometry's ``odom → <root link>``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from harness.builders.base import BuildContext, fresh_graph
from harness.builders.odometry import robot_front
from harness.geometry import quat_wxyz_from_yaw, quat_wxyz_mul, wxyz_to_xyzw, yaw_between
from harness.graph import Controller
from harness.scenario import RobotSpec

__all__ = ["LINK_TREES", "build", "graph_path"]

# model → [(node name, parent link, child links, static?)]
LINK_TREES: dict[str, list[tuple[str, str, tuple[str, ...], bool]]] = {
    "turtlebot3_waffle_pi": [
        ("PubTFBaseStatic", "base_footprint", ("base_link",), True),
        ("PubTFStatic", "base_link", ("camera_link", "caster_back_left_link",
                                      "caster_back_right_link", "imu_link", "base_scan"), True),
        ("PubTFWheels", "base_link", ("wheel_left_link", "wheel_right_link"), False),
    ],
    "forklift": [],
}


def graph_path(robot: RobotSpec) -> str:
    return f"/World/{robot.name}_TfGraph"


def odom_origin(bc: BuildContext, robot: RobotSpec) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Translation and (x, y, z, w) rotation of the odom frame in the world frame."""
    pos, quat = bc.world.prim_pose(bc.world.base_prim(robot.name))
    q = quat_wxyz_mul(quat, quat_wxyz_from_yaw(yaw_between(robot_front(bc, robot))))
    return tuple(float(v) for v in pos), tuple(float(v) for v in wxyz_to_xyzw(q))


def build(bc: BuildContext, robot: RobotSpec) -> str | None:
    spec = robot.tf_tree
    if not spec.enabled:
        return None
    path = graph_path(robot)
    keys = Controller.Keys
    nodes: list[tuple[str, str]] = [
        ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
        ("ReadSimTime", "isaacsim.core.nodes.IsaacReadSimulationTime"),
    ]
    connect: list[tuple[str, str]] = []
    values: list[tuple[str, Any]] = []

    def add(name: str, type_name: str, settings: Sequence[tuple[str, Any]]) -> None:
        nodes.append((name, type_name))
        connect.append(("OnPlaybackTick.outputs:tick", f"{name}.inputs:execIn"))
        connect.append(("ReadSimTime.outputs:simulationTime", f"{name}.inputs:timeStamp"))
        values.extend((f"{name}.inputs:{k}", v) for k, v in settings)

    where = bc.robot_field(robot)
    if robot.odometry.enabled:
        translation, rotation = odom_origin(bc, robot)
        add("PubWorldToOdom", "isaacsim.ros2.bridge.ROS2PublishRawTransformTree", [
            ("topicName", spec.static_topic),
            ("staticPublisher", True),
            ("parentFrameId", spec.world_frame),
            ("childFrameId", robot.frame(robot.odometry.odom_frame)),
            ("translation", translation),
            ("rotation", rotation),
        ])
        bc.annotate(path, "PubWorldToOdom", where, topicName="tf_tree.static_topic",
                    parentFrameId="tf_tree.world_frame", childFrameId="odometry.odom_frame")
    if robot.model_file is not None:
        root = bc.world.base_prim(robot.name)
        add("PubTFArticulation", "isaacsim.ros2.bridge.ROS2PublishTransformTree", [
            ("topicName", spec.dynamic_topic),
            ("parentPrim", [root]),
            ("targetPrims", [root]),
            ("frameIdPrefix", robot.frame_prefix or ""),
        ])
        bc.annotate(path, "PubTFArticulation", f"{where}.tf_tree", topicName="dynamic_topic")
    links = LINK_TREES.get(robot.model, []) if isinstance(robot.model, str) else []
    for name, parent, children, static in links:
        add(name, "isaacsim.ros2.bridge.ROS2PublishTransformTree", [
            ("topicName", spec.static_topic if static else spec.dynamic_topic),
            ("staticPublisher", static),
            ("parentPrim", [f"{robot.prim}/{parent}"]),
            ("targetPrims", [f"{robot.prim}/{c}" for c in children]),
            ("frameIdPrefix", robot.frame_prefix or ""),
        ])
        bc.annotate(path, name, f"{where}.tf_tree",
                    topicName="static_topic" if static else "dynamic_topic")
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: nodes,
        keys.CONNECT: connect,
        keys.SET_VALUES: values,
    })
    return path
