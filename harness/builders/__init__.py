"""Graph builders: one module per action graph, each at a predictable /World/<Name>Graph path.

Builders are idempotent (building twice leaves one graph: an existing graph at the path is
replaced) and return ``None`` when their block is disabled. :func:`build_all` runs them in
the seed's order: clock first, then each enabled robot's control, odometry and TF graphs,
then one graph per enabled fixed camera.
"""

from __future__ import annotations

from collections.abc import Callable

from harness.builders import (
    camera_tf,
    cameras,
    clock,
    diff_drive_control,
    forklift_control,
    ground_truth,
    odometry,
    robot_camera,
    robot_sensors,
    safety_indicator,
    tf_tree,
)
from harness.builders.base import BuildContext, fresh_graph
from harness.scenario import CameraSpec, RobotSpec

__all__ = ["CAMERA_BUILDERS", "GLOBAL_BUILDERS", "ROBOT_BUILDERS", "BuildContext", "build_all",
           "fresh_graph"]

GLOBAL_BUILDERS: tuple[Callable[[BuildContext], str | None], ...] = (
    clock.build,
    ground_truth.build,  # only with srr_gt
    camera_tf.build,  # every enabled fixed camera's TF
)
ROBOT_BUILDERS: tuple[Callable[[BuildContext, RobotSpec], str | None], ...] = (
    forklift_control.build,
    diff_drive_control.build,
    odometry.build,
    tf_tree.build,
    robot_sensors.build_lidar,
    robot_sensors.build_imu,
    safety_indicator.build,
    robot_camera.build,
)
CAMERA_BUILDERS: tuple[Callable[[BuildContext, CameraSpec], str | None], ...] = (
    cameras.build,
)


def build_all(bc: BuildContext) -> list[str]:
    """Build every enabled graph on the current stage; returns their paths in build order."""
    paths = [p for b in GLOBAL_BUILDERS if (p := b(bc))]
    for robot in bc.scenario.robots:
        if robot.enabled:
            paths.extend(p for b in ROBOT_BUILDERS if (p := b(bc, robot)))
    for camera in bc.scenario.cameras:
        if camera.enabled:
            paths.extend(p for b in CAMERA_BUILDERS if (p := b(bc, camera)))
    return paths
