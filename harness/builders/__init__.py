"""Graph builders: one module per action graph, each at a predictable /World/<Name>Graph path.

Builders are idempotent (building twice leaves one graph: an existing graph at the path is
replaced) and return ``None`` when their block is disabled. :func:`build_all` runs them in
the seed's order: clock first (with ground truth, camera TF and, when ``rtsp.enabled``, the
RTSP multi-camera graph), then each enabled robot's control, odometry and TF graphs, then one
graph per enabled fixed camera, and last the scenario's own ``graphs:`` builders
(:mod:`harness.builders.custom`).
"""

from __future__ import annotations

from collections.abc import Callable

from harness.builders import (
    camera_tf,
    cameras,
    clock,
    custom,
    diff_drive_control,
    forklift_control,
    ground_truth,
    odometry,
    robot_camera,
    robot_sensors,
    rtsp_cameras,
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
    rtsp_cameras.build,  # only with rtsp.enabled
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


def _kind(builder: Callable[..., str | None]) -> str:
    return builder.__module__.rsplit(".", 1)[-1].replace("_", " ")


def build_all(bc: BuildContext) -> list[str]:
    """Build every enabled graph on the current stage; returns their paths in build order."""
    taken: dict[str, str] = {}
    for b in GLOBAL_BUILDERS:
        if p := b(bc):
            taken[p] = f"the built-in {_kind(b)} graph"
    for i, robot in enumerate(bc.scenario.robots):
        if robot.enabled:
            for rb in ROBOT_BUILDERS:
                if p := rb(bc, robot):
                    taken[p] = f"the built-in {_kind(rb)} graph of robots[{i}] ({robot.name})"
    for i, camera in enumerate(bc.scenario.cameras):
        if camera.enabled:
            for cb in CAMERA_BUILDERS:
                if p := cb(bc, camera):
                    taken[p] = f"the built-in camera graph of cameras[{i}] ({camera.name})"
    builtin = list(taken)
    return builtin + custom.build_custom(bc, taken)
