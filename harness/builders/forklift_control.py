"""Forklift control graph (/World/<name>_ControlGraph).

OnPlaybackTick ─▶ ROS2SubscribeTwist (cmd_vel) ─▶ SwivelIK (ScriptNode) ─▶ ArticulationController

The swivel-drive IK is one script node; the builder prepends its constants from the robot's
``control:`` block. A rear steered wheel at ``WHEELBASE`` behind the front axle turns the
vehicle at ``ω = v·tan(steer)/L``, so ``steer = atan2(ω·L, v)``; the wheel's own speed is
``v / cos(steer)`` and the drive joint takes it in rad/s.
"""

from __future__ import annotations

import math

from harness.builders.base import BuildContext, fresh_graph
from harness.graph import Controller
from harness.scenario import ForkliftControl, RobotSpec

__all__ = ["SWIVEL_IK", "build", "graph_path", "swivel_ik_source"]

SWIVEL_IK = '''
import math

MIN_COS = 1e-3
MIN_SPEED = 1e-4


def compute(db):
    lin = db.inputs.linearVelocity
    ang = db.inputs.angularVelocity
    # cmd_vel is in the ROS body frame; the vehicle's joints may count the other way round.
    v = -lin[0] if FLIP_LINEAR_X else lin[0]
    w = -ang[2] if FLIP_ANGULAR_Z else ang[2]

    speed = max(abs(v), MIN_SPEED)
    steer = math.atan2(w * WHEELBASE, speed)
    steer = min(max(steer, -MAX_STEER), MAX_STEER)
    if v < 0.0:  # driving backwards: mirror the steering, unless there is no turn at all
        steer = 0.0 if abs(w) < MIN_SPEED else -steer
        wheel_speed = -speed / max(math.cos(steer), MIN_COS)
    else:
        wheel_speed = speed / max(math.cos(steer), MIN_COS)

    db.outputs.jointNames = [DRIVE_JOINT, SWIVEL_JOINT]
    db.outputs.positionCommand = [0.0, steer]
    db.outputs.velocityCommand = [wheel_speed / WHEEL_RADIUS, 0.0]
    return True
'''


def graph_path(robot: RobotSpec) -> str:
    return f"/World/{robot.name}_ControlGraph"


def swivel_ik_source(c: ForkliftControl) -> str:
    """The IK script with the robot's constants prepended, as the seed's builder does."""
    header = "\n".join([
        f"DRIVE_JOINT = {c.drive_joint!r}",
        f"SWIVEL_JOINT = {c.swivel_joint!r}",
        f"WHEELBASE = {c.wheelbase!r}",
        f"WHEEL_RADIUS = {c.wheel_radius!r}",
        f"MAX_STEER = {math.radians(c.max_steer_deg)!r}",
        f"FLIP_LINEAR_X = {c.reverse_logic.flip_linear_x!r}",
        f"FLIP_ANGULAR_Z = {c.reverse_logic.flip_angular_z!r}",
    ])
    return header + "\n" + SWIVEL_IK


def build(bc: BuildContext, robot: RobotSpec) -> str | None:
    c = robot.control_spec
    if not isinstance(c, ForkliftControl) or not c.enabled:
        return None
    path = graph_path(robot)
    keys = Controller.Keys
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: [
            ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
            ("ROS2Context", "isaacsim.ros2.bridge.ROS2Context"),
            ("SubscribeTwist", "isaacsim.ros2.bridge.ROS2SubscribeTwist"),
            ("SwivelIK", "omni.graph.scriptnode.ScriptNode"),
            ("ArticulationController", "isaacsim.core.nodes.IsaacArticulationController"),
        ],
        keys.CREATE_ATTRIBUTES: [
            ("SwivelIK.inputs:linearVelocity", "double[3]"),
            ("SwivelIK.inputs:angularVelocity", "double[3]"),
            ("SwivelIK.outputs:jointNames", "token[]"),
            ("SwivelIK.outputs:positionCommand", "double[]"),
            ("SwivelIK.outputs:velocityCommand", "double[]"),
        ],
        keys.CONNECT: [
            ("OnPlaybackTick.outputs:tick", "SubscribeTwist.inputs:execIn"),
            ("ROS2Context.outputs:context", "SubscribeTwist.inputs:context"),
            ("SubscribeTwist.outputs:execOut", "SwivelIK.inputs:execIn"),
            ("SubscribeTwist.outputs:linearVelocity", "SwivelIK.inputs:linearVelocity"),
            ("SubscribeTwist.outputs:angularVelocity", "SwivelIK.inputs:angularVelocity"),
            ("SwivelIK.outputs:execOut", "ArticulationController.inputs:execIn"),
            ("SwivelIK.outputs:jointNames", "ArticulationController.inputs:jointNames"),
            ("SwivelIK.outputs:positionCommand", "ArticulationController.inputs:positionCommand"),
            ("SwivelIK.outputs:velocityCommand", "ArticulationController.inputs:velocityCommand"),
        ],
        keys.SET_VALUES: [
            ("SubscribeTwist.inputs:topicName", c.cmd_vel_topic),
            ("SubscribeTwist.inputs:nodeNamespace", robot.ns),
            ("SwivelIK.inputs:script", swivel_ik_source(c)),
            ("ArticulationController.inputs:targetPrim", [robot.prim]),
        ],
    })
    bc.annotate(path, "SubscribeTwist", bc.robot_field(robot, "control"),
                topicName="cmd_vel_topic")
    return path
