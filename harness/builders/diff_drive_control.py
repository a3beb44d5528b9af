"""Differential-drive control graph (/World/<name>_ControlGraph), the TurtleBot3 teleop graph.

OnPlaybackTick ─▶ ROS2SubscribeTwist ─▶ DifferentialController
      │             linear ─▶ ScaleToFromStageUnit ─▶ BreakVector3.x ─┘   │ velocityCommand
      │             angular ─▶ BreakVector3.z ───────────────────────────┘   ▼
      └──────────────────────────────────────────────────────────▶ ArticulationController
"""

from __future__ import annotations

from harness.builders.base import BuildContext, fresh_graph
from harness.graph import Controller
from harness.scenario import DiffDriveControl, RobotSpec

__all__ = ["build", "graph_path"]


def graph_path(robot: RobotSpec) -> str:
    return f"/World/{robot.name}_ControlGraph"


def build(bc: BuildContext, robot: RobotSpec) -> str | None:
    c = robot.control_spec
    if not isinstance(c, DiffDriveControl) or not c.enabled:
        return None
    path = graph_path(robot)
    keys = Controller.Keys
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: [
            ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
            ("ROS2Context", "isaacsim.ros2.bridge.ROS2Context"),
            ("SubscribeTwistDiff", "isaacsim.ros2.bridge.ROS2SubscribeTwist"),
            ("ScaleWheel", "isaacsim.core.nodes.OgnIsaacScaleToFromStageUnit"),
            ("Break3_VectorAngVel", "omni.graph.nodes.BreakVector3"),
            ("Break3_VectorLinVel", "omni.graph.nodes.BreakVector3"),
            ("DiffController", "isaacsim.robot.wheeled_robots.DifferentialController"),
            ("ArticulationController", "isaacsim.core.nodes.IsaacArticulationController"),
        ],
        keys.CONNECT: [
            ("OnPlaybackTick.outputs:tick", "SubscribeTwistDiff.inputs:execIn"),
            ("OnPlaybackTick.outputs:tick", "ArticulationController.inputs:execIn"),
            ("ROS2Context.outputs:context", "SubscribeTwistDiff.inputs:context"),
            ("SubscribeTwistDiff.outputs:execOut", "DiffController.inputs:execIn"),
            ("SubscribeTwistDiff.outputs:angularVelocity", "Break3_VectorAngVel.inputs:tuple"),
            ("SubscribeTwistDiff.outputs:linearVelocity", "ScaleWheel.inputs:value"),
            ("ScaleWheel.outputs:result", "Break3_VectorLinVel.inputs:tuple"),
            ("Break3_VectorAngVel.outputs:z", "DiffController.inputs:angularVelocity"),
            ("Break3_VectorLinVel.outputs:x", "DiffController.inputs:linearVelocity"),
            ("DiffController.outputs:velocityCommand",
             "ArticulationController.inputs:velocityCommand"),
        ],
        keys.SET_VALUES: [
            ("SubscribeTwistDiff.inputs:topicName", c.cmd_vel_topic),
            ("SubscribeTwistDiff.inputs:nodeNamespace", robot.ns),
            ("DiffController.inputs:maxLinearSpeed", c.max_linear_speed),
            ("DiffController.inputs:maxAngularSpeed", c.max_angular_speed),
            ("DiffController.inputs:wheelDistance", c.wheel_distance),
            ("DiffController.inputs:wheelRadius", c.wheel_radius),
            ("ArticulationController.inputs:usePath", True),
            ("ArticulationController.inputs:robotPath", bc.world.base_prim(robot.name)),
            ("ArticulationController.inputs:jointNames", list(c.joint_names)),
        ],
    })
    bc.annotate(path, "SubscribeTwistDiff", bc.robot_field(robot, "control"),
                topicName="cmd_vel_topic")
    return path
