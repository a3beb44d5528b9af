"""The MuJoCo world built from a scenario: warehouse, robots, cameras, sensor attach points.

Names are imported from their submodules on first use (:mod:`harness._lazy`), so a
submodule that needs no MuJoCo (:mod:`~harness.sim.world_file`) imports without it."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.sim.prims import PrimKind, PrimRef
    from harness.sim.world import ImuReading, JointRef, RobotInfo, World

__all__ = [
    "ImuReading",
    "JointRef",
    "PrimKind",
    "PrimRef",
    "RobotInfo",
    "World",
]

_WHERE = {
    "PrimKind": "prims",
    "PrimRef": "prims",
    "ImuReading": "world",
    "JointRef": "world",
    "RobotInfo": "world",
    "World": "world",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
