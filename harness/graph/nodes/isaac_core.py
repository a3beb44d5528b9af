"""Simulation-side nodes: odometry, articulation and wheel controllers.

They read and drive the MuJoCo world through ``ctx.world`` (see :class:`harness.sim.World`),
with Isaac Sim's node names as aliases. Quaternion attributes (``quatd[4]``) are in Isaac's
IJKR order (x, y, z, w).
"""

from __future__ import annotations

import math
from typing import Any

from harness.geometry import (
    QuatTuple,
    quat_wxyz_conj_floats,
    quat_wxyz_from_yaw,
    quat_wxyz_mul_floats,
    quat_wxyz_rotate_floats,
    yaw_between,
)
from harness.graph import Attr, NodeType, register
from harness.graph.errors import GraphError

__all__ = ["ArticulationController", "ComputeOdometry", "DifferentialController", "robot_root"]


def _core(name: str) -> tuple[str, ...]:
    return (f"omni.isaac.core_nodes.{name}", f"isaacsim.core.nodes.{name}")


def _first(value: Any) -> str:
    if isinstance(value, str):
        return value
    return str(value[0]) if value else ""


def robot_root(world: Any, prim: str, node_path: str) -> str:
    """The robot prim that ``prim`` (the articulation root or one of its links) belongs to."""
    for robot in world.scenario.robots:
        root = robot.prim
        if prim == root or prim.startswith(root + "/"):
            return str(root)
    raise GraphError(f"{node_path}: {prim!r} is not part of any robot")


@register("srr.ComputeOdometry", aliases=_core("IsaacComputeOdometry"))
class ComputeOdometry(NodeType):
    """Pose and velocity of ``chassisPrim`` relative to where it was on the first tick.

    ``robotFront`` is the chassis axis that points forward (the forklift asset's is -X); the
    reported base frame turns it onto +X, so heading and velocity follow the travel direction.
    Velocities are in the base frame, as in ``nav_msgs/Odometry``'s twist.
    """

    kind = "action"
    inputs = (
        Attr("execIn", "execution"),
        Attr("chassisPrim", "target", ()),
        Attr("robotFront", "double[3]", (1.0, 0.0, 0.0)),
    )
    outputs = (
        Attr("execOut", "execution"),
        Attr("position", "double[3]", (0.0, 0.0, 0.0)),
        Attr("orientation", "quatd[4]", (0.0, 0.0, 0.0, 1.0)),
        Attr("linearVelocity", "double[3]", (0.0, 0.0, 0.0)),
        Attr("angularVelocity", "double[3]", (0.0, 0.0, 0.0)),
        Attr("globalLinearVelocity", "double[3]", (0.0, 0.0, 0.0)),
    )

    def initialize(self, db: Any, ctx: Any) -> None:
        self._prim = _first(db.inputs.chassisPrim)
        if not self._prim or not ctx.world.has_prim(self._prim):
            raise GraphError(f"{db.node_path}.inputs:chassisPrim: no prim {self._prim!r}")
        front = quat_wxyz_from_yaw(yaw_between(db.inputs.robotFront))
        self._front: QuatTuple = tuple(front.tolist())
        self._origin: tuple[list[float], QuatTuple] | None = None

    def compute(self, db: Any, ctx: Any) -> bool:
        # Python floats throughout (see harness.geometry): the same values as numpy's. The
        # base frame's world pose: the chassis's, turned so that robotFront points along +X.
        world = ctx.world
        pos_a, quat_a = world.prim_pose(self._prim)
        pos: list[float] = pos_a.tolist()
        quat = quat_wxyz_mul_floats(quat_a.tolist(), self._front)
        if self._origin is None:
            self._origin = (pos, quat)
        p0, q0 = self._origin
        inv0 = quat_wxyz_conj_floats(q0)
        lin_a, ang_a = world.prim_velocity(self._prim)
        lin_w, ang_w = lin_a.tolist(), ang_a.tolist()
        inv = quat_wxyz_conj_floats(quat)
        w, x, y, z = quat_wxyz_mul_floats(inv0, quat)
        # Tuples of Python floats, the stored form of double[3] and quatd[4]: written
        # straight into the output values (db.stored), without db.outputs' checks.
        stored = db.stored
        stored["outputs:position"] = quat_wxyz_rotate_floats(
            inv0, (pos[0] - p0[0], pos[1] - p0[1], pos[2] - p0[2]))
        stored["outputs:orientation"] = (x, y, z, w)
        stored["outputs:linearVelocity"] = quat_wxyz_rotate_floats(inv, lin_w)
        stored["outputs:angularVelocity"] = quat_wxyz_rotate_floats(inv, ang_w)
        stored["outputs:globalLinearVelocity"] = tuple(lin_w)
        return True

    def reset(self) -> None:
        self._origin = None


@register("srr.ArticulationController", aliases=_core("IsaacArticulationController"))
class ArticulationController(NodeType):
    """Joint commands to the robot: position targets and/or velocity targets by joint name."""

    kind = "action"
    inputs = (
        Attr("execIn", "execution"),
        Attr("targetPrim", "target", ()),
        Attr("robotPath", "string", ""),
        Attr("usePath", "bool", False),
        Attr("jointNames", "token[]", ()),
        Attr("positionCommand", "double[]", ()),
        Attr("velocityCommand", "double[]", ()),
        Attr("effortCommand", "double[]", ()),
    )
    outputs = (Attr("execOut", "execution"),)

    def initialize(self, db: Any, ctx: Any) -> None:
        prim = db.inputs.robotPath if db.inputs.usePath else _first(db.inputs.targetPrim)
        if not prim:
            raise GraphError(f"{db.node_path}: set inputs:targetPrim (or robotPath with usePath)")
        self._robot = robot_root(ctx.world, prim, db.node_path)

    def compute(self, db: Any, ctx: Any) -> bool:
        names = list(db.inputs.jointNames)
        pos = list(db.inputs.positionCommand) or None
        vel = list(db.inputs.velocityCommand) or None
        if db.inputs.effortCommand:
            raise GraphError(f"{db.node_path}.inputs:effortCommand: effort control is not "
                             "supported; use position or velocity commands")
        for label, values in (("positionCommand", pos), ("velocityCommand", vel)):
            if values is not None and len(values) != len(names):
                raise GraphError(f"{db.node_path}.inputs:{label}: {len(values)} values for "
                                 f"{len(names)} joints")
        if names and (pos or vel):
            ctx.world.apply_joint_commands(self._robot, names, pos, vel)
        return True


@register("srr.DifferentialController", aliases=(
    "omni.isaac.wheeled_robots.DifferentialController",
    "isaacsim.robot.wheeled_robots.DifferentialController",
))
class DifferentialController(NodeType):
    """Unicycle (v, ω) → wheel angular velocities (left, right) in rad/s, with limits."""

    kind = "action"
    inputs = (
        Attr("execIn", "execution"),
        Attr("linearVelocity", "double", 0.0),
        Attr("angularVelocity", "double", 0.0),
        Attr("wheelDistance", "double", 0.0),
        Attr("wheelRadius", "double", 0.0),
        Attr("maxLinearSpeed", "double", 0.0),
        Attr("maxAngularSpeed", "double", 0.0),
        Attr("maxWheelSpeed", "double", 0.0),
    )
    outputs = (Attr("execOut", "execution"), Attr("velocityCommand", "double[]", (0.0, 0.0)))

    def compute(self, db: Any, ctx: Any) -> bool:
        i = db.inputs
        if i.wheelRadius <= 0 or i.wheelDistance <= 0:
            raise GraphError(f"{db.node_path}: wheelRadius and wheelDistance must be > 0")
        v = _clamp(float(i.linearVelocity), float(i.maxLinearSpeed))
        w = _clamp(float(i.angularVelocity), float(i.maxAngularSpeed))
        left = (v - w * i.wheelDistance / 2.0) / i.wheelRadius
        right = (v + w * i.wheelDistance / 2.0) / i.wheelRadius
        if i.maxWheelSpeed > 0:
            left, right = _clamp(left, i.maxWheelSpeed), _clamp(right, i.maxWheelSpeed)
        db.outputs.velocityCommand = (left, right)
        return True


def _clamp(x: float, limit: float) -> float:
    if limit <= 0 or math.isnan(x):
        return x
    return max(-limit, min(limit, x))
