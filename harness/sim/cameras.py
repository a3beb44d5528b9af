"""Cameras: the axes convention of camera prims and the MuJoCo cameras behind them.

Scenario camera orientations (and every camera pose :class:`~harness.sim.world.World` returns)
use the *world* axes convention of Isaac Sim's ``Camera`` class: the camera looks along its +X,
+Z is up and +Y is to the left. A MuJoCo camera looks along its -Z with +Y up and +X to the
right. The fixed rotation between the two is ``Q_MJ_IN_WORLD_CONVENTION``::

    q_mujoco_camera = q_world_convention ⊗ Q_MJ_IN_WORLD_CONVENTION
    q_world_convention = q_mujoco_camera ⊗ conj(Q_MJ_IN_WORLD_CONVENTION)

(ROS optical frames — +Z forward, +X right, +Y down — are a further fixed rotation, applied by
whoever publishes them: ``q_optical = q_world_convention ⊗ Q_OPTICAL_IN_WORLD_CONVENTION``.)
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from harness.geometry import FloatArray, quat_wxyz_conj
from harness.scenario.schema import CameraSpec
from harness.sim.mjquat import quat_wxyz_from_mat_mj, quat_wxyz_from_rpy_deg_mj, quat_wxyz_mul_mj
from harness.sim.prims import PrimKind, PrimTable

__all__ = [
    "Q_MJ_IN_WORLD_CONVENTION",
    "Q_OPTICAL_IN_WORLD_CONVENTION",
    "add_fixed_camera",
    "add_mounted_camera",
    "mj_camera_quat",
    "optical_quat",
    "world_convention_quat",
]

# Columns: the MuJoCo camera's x (right), y (up), z (backwards) axes written in the world-
# convention camera frame (+X forward, +Y left, +Z up).
Q_MJ_IN_WORLD_CONVENTION: FloatArray = quat_wxyz_from_mat_mj(
    np.array([[0.0, 0.0, -1.0],
              [-1.0, 0.0, 0.0],
              [0.0, 1.0, 0.0]])
)

# Columns: the ROS optical frame's x (right), y (down), z (forward) axes written in the world-
# convention camera frame. Its inverse, (w, x, y, z) = (0.5, 0.5, -0.5, 0.5), is seed 001's
# static <camera> → <camera>_world rotation (quatd [0.5, -0.5, 0.5, 0.5] in IJKR order).
Q_OPTICAL_IN_WORLD_CONVENTION: FloatArray = quat_wxyz_from_mat_mj(
    np.array([[0.0, 0.0, 1.0],
              [-1.0, 0.0, 0.0],
              [0.0, -1.0, 0.0]])
)


def optical_quat(q_world_convention: Sequence[float] | FloatArray) -> FloatArray:
    """ROS optical-frame orientation (+Z forward, +X right, +Y down) of a camera prim."""
    return quat_wxyz_mul_mj(q_world_convention, Q_OPTICAL_IN_WORLD_CONVENTION)


def mj_camera_quat(q_world_convention: Sequence[float] | FloatArray) -> FloatArray:
    """MuJoCo camera orientation for a world-convention camera orientation."""
    return quat_wxyz_mul_mj(q_world_convention, Q_MJ_IN_WORLD_CONVENTION)


def world_convention_quat(q_mj_camera: Sequence[float] | FloatArray) -> FloatArray:
    """World-convention orientation (+X forward, +Z up) of a MuJoCo camera orientation."""
    return quat_wxyz_mul_mj(q_mj_camera, quat_wxyz_conj(Q_MJ_IN_WORLD_CONVENTION))


def add_fixed_camera(spec: mujoco.MjSpec, camera: CameraSpec, prims: PrimTable) -> str:
    """Add a world-fixed camera at ``camera.spawn``; returns its MuJoCo name."""
    name = f"camera/{camera.name}"
    spec.worldbody.add_camera(
        name=name,
        pos=[float(v) for v in camera.spawn.position],
        quat=list(mj_camera_quat(quat_wxyz_from_rpy_deg_mj(camera.spawn.rpy_deg))),
        fovy=float(camera.fovy_deg),
        resolution=[float(camera.resolution[0]), float(camera.resolution[1])],
    )
    prims.declare(camera.prim, PrimKind.CAMERA, name)
    return name


def add_mounted_camera(body: mujoco.MjsBody, mj_name: str, fovy_deg: float,
                       resolution: tuple[int, int], prim: str, prims: PrimTable,
                       pos: Sequence[float] = (0.0, 0.0, 0.0),
                       quat: Sequence[float] = (1.0, 0.0, 0.0, 0.0)) -> str:
    """Add a camera on a robot link at ``pos``/``quat`` (wxyz) in the link, looking along
    that mount's +X (REP-103 ``camera_link``)."""
    body.add_camera(
        name=mj_name,
        pos=[float(v) for v in pos],
        quat=[float(v) for v in quat_wxyz_mul_mj(quat, Q_MJ_IN_WORLD_CONVENTION)],
        fovy=float(fovy_deg),
        resolution=[float(resolution[0]), float(resolution[1])],
    )
    prims.declare(prim, PrimKind.CAMERA, mj_name)
    return mj_name
