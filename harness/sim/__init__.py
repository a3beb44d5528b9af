"""The MuJoCo world built from a scenario: warehouse, robots, cameras, sensor attach points."""

from harness.sim.prims import PrimKind, PrimRef
from harness.sim.world import ImuReading, JointRef, RobotInfo, World

__all__ = ["ImuReading", "JointRef", "PrimKind", "PrimRef", "RobotInfo", "World"]
