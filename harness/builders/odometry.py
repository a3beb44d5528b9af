"""Odometry graph (/World/<name>_OdometryGraph): ``odom`` plus the odom → base TF.

OnPlaybackTick ─▶ IsaacComputeOdometry ─┬▶ ROS2PublishOdometry (odom)
ReadSimulationTime (timeStamp) ─────────┴▶ ROS2PublishRawTransformTree (tf)

``odom`` resolves in the robot's namespace; the TF goes to the root namespace's ``tf`` (as
tf2_ros broadcasters publish on ``/tf`` whatever their node's namespace), with the robot's
frame prefix on both frame ids, so several robots share one TF tree.
"""

from __future__ import annotations

from typing import cast

from harness.builders.base import BuildContext, fresh_graph
from harness.graph import Controller
from harness.scenario import RobotSpec

__all__ = ["base_frame", "build", "graph_path", "robot_front"]


def graph_path(robot: RobotSpec) -> str:
    return f"/World/{robot.name}_OdometryGraph"


def robot_front(bc: BuildContext, robot: RobotSpec) -> tuple[float, float, float]:
    front = robot.odometry.robot_front
    # tuple() only normalises the container; both sources hold three floats (Vec3).
    return cast("tuple[float, float, float]",
                tuple(front) if front is not None else tuple(bc.world.robot_front(robot.name)))


def base_frame(bc: BuildContext, robot: RobotSpec) -> str:
    """The robot's base frame id (prefixed): ``odometry.base_frame`` or the model's."""
    return robot.frame(robot.odometry.base_frame or str(bc.world.default_base_frame(robot.name)))


def build(bc: BuildContext, robot: RobotSpec) -> str | None:
    spec = robot.odometry
    if not spec.enabled:
        return None
    path = graph_path(robot)
    keys = Controller.Keys
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: [
            ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
            ("ROS2Context", "isaacsim.ros2.bridge.ROS2Context"),
            ("ReadSimTime", "isaacsim.core.nodes.IsaacReadSimulationTime"),
            ("ComputeOdometry", "isaacsim.core.nodes.IsaacComputeOdometry"),
            ("PublishOdometry", "isaacsim.ros2.bridge.ROS2PublishOdometry"),
            ("PublishRawTFTree", "isaacsim.ros2.bridge.ROS2PublishRawTransformTree"),
        ],
        keys.CONNECT: [
            ("OnPlaybackTick.outputs:tick", "ComputeOdometry.inputs:execIn"),
            ("ComputeOdometry.outputs:execOut", "PublishOdometry.inputs:execIn"),
            ("ComputeOdometry.outputs:execOut", "PublishRawTFTree.inputs:execIn"),
            ("ROS2Context.outputs:context", "PublishOdometry.inputs:context"),
            ("ROS2Context.outputs:context", "PublishRawTFTree.inputs:context"),
            ("ReadSimTime.outputs:simulationTime", "PublishOdometry.inputs:timeStamp"),
            ("ReadSimTime.outputs:simulationTime", "PublishRawTFTree.inputs:timeStamp"),
            ("ComputeOdometry.outputs:position", "PublishOdometry.inputs:position"),
            ("ComputeOdometry.outputs:orientation", "PublishOdometry.inputs:orientation"),
            ("ComputeOdometry.outputs:linearVelocity", "PublishOdometry.inputs:linearVelocity"),
            ("ComputeOdometry.outputs:angularVelocity",
             "PublishOdometry.inputs:angularVelocity"),
            ("ComputeOdometry.outputs:position", "PublishRawTFTree.inputs:translation"),
            ("ComputeOdometry.outputs:orientation", "PublishRawTFTree.inputs:rotation"),
        ],
        keys.SET_VALUES: [
            ("ComputeOdometry.inputs:chassisPrim", [bc.world.base_prim(robot.name)]),
            ("ComputeOdometry.inputs:robotFront", robot_front(bc, robot)),
            ("PublishOdometry.inputs:topicName", spec.odom_topic),
            ("PublishOdometry.inputs:nodeNamespace", robot.ns),
            ("PublishOdometry.inputs:odomFrameId", robot.frame(spec.odom_frame)),
            ("PublishOdometry.inputs:chassisFrameId", base_frame(bc, robot)),
            ("PublishRawTFTree.inputs:topicName", spec.tf_topic),
            ("PublishRawTFTree.inputs:parentFrameId", robot.frame(spec.odom_frame)),
            ("PublishRawTFTree.inputs:childFrameId", base_frame(bc, robot)),
        ],
    })
    where = bc.robot_field(robot, "odometry")
    bc.annotate(path, "PublishOdometry", where, topicName="odom_topic",
                odomFrameId="odom_frame", chassisFrameId="base_frame")
    bc.annotate(path, "PublishRawTFTree", where, topicName="tf_topic",
                parentFrameId="odom_frame", childFrameId="base_frame")
    return path
