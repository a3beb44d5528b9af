"""Graph builders: one module per action graph, each at a predictable /World/<Name>Graph path.

Builders are idempotent (building twice leaves one graph: an existing graph at the path is
replaced) and return ``None`` when their block is disabled. :func:`build_all` runs them in
the seed's order: clock first, then each enabled robot's control, odometry and TF graphs.
"""

from __future__ import annotations

from collections.abc import Callable

from harness.builders import (
    clock,
    diff_drive_control,
    forklift_control,
    odometry,
    robot_sensors,
    tf_tree,
)
from harness.builders.base import BuildContext, fresh_graph
from harness.scenario import RobotSpec

__all__ = ["GLOBAL_BUILDERS", "ROBOT_BUILDERS", "BuildContext", "build_all", "fresh_graph"]

GLOBAL_BUILDERS: tuple[Callable[[BuildContext], str | None], ...] = (clock.build,)
ROBOT_BUILDERS: tuple[Callable[[BuildContext, RobotSpec], str | None], ...] = (
    forklift_control.build,
    diff_drive_control.build,
    odometry.build,
    tf_tree.build,
    robot_sensors.build_lidar,
    robot_sensors.build_imu,
)


def build_all(bc: BuildContext) -> list[str]:
    """Build every enabled graph on the current stage; returns their paths in build order."""
    paths = [p for b in GLOBAL_BUILDERS if (p := b(bc))]
    for robot in bc.scenario.robots:
        if robot.enabled:
            paths.extend(p for b in ROBOT_BUILDERS if (p := b(bc, robot)))
    return paths
