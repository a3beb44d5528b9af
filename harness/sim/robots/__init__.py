"""Robot models built into a MuJoCo spec: one module per built-in model, and robots read from
model files (URDF, MJCF) in :mod:`.imported`."""

from __future__ import annotations

import mujoco

from harness.errors import SimulationError
from harness.geometry import FloatArray
from harness.scenario.schema import DiffDriveControl, ForkliftControl, RobotSpec
from harness.sim.prims import PrimTable
from harness.sim.robots.common import ActuatorMode, RobotBuild
from harness.sim.robots.forklift import add_forklift
from harness.sim.robots.imported import ModelSource, add_model_robot
from harness.sim.robots.turtlebot3 import add_turtlebot3

__all__ = ["ActuatorMode", "ModelSource", "RobotBuild", "add_robot", "control_for"]


def control_for(robot: RobotSpec) -> ForkliftControl | DiffDriveControl:
    """The robot's control block, or its model's default; a mismatched block is refused."""
    expected: type[ForkliftControl] | type[DiffDriveControl]
    if robot.model_file is not None:
        expected = ForkliftControl if robot.swivel_drive else DiffDriveControl
    elif robot.model == "forklift":
        expected = ForkliftControl
    elif robot.model == "turtlebot3_waffle_pi":
        expected = DiffDriveControl
    else:
        raise SimulationError(f"robots.{robot.name}.model: unknown robot model {robot.model!r}")
    if robot.control is None:
        return expected()
    if not isinstance(robot.control, expected):
        raise SimulationError(
            f"robots.{robot.name}.control: a {type(robot.control).__name__} block does not fit "
            f"model {robot.model_name!r} (expected {expected.__name__})")
    return robot.control


def add_robot(spec: mujoco.MjSpec, robot: RobotSpec, pos: tuple[float, float, float],
              quat: FloatArray, prims: PrimTable, source: ModelSource) -> RobotBuild:
    """Add ``robot`` with its root frame at ``pos``/``quat`` (built-in models: on the floor;
    ``source`` says where a model file's paths start and what errors name)."""
    control = control_for(robot)
    if robot.model_file is not None:
        return add_model_robot(spec, robot, control, pos, quat, prims, source)
    if isinstance(control, ForkliftControl):
        return add_forklift(spec, robot, control, pos, quat, prims)
    return add_turtlebot3(spec, robot, control, pos, quat, prims)
