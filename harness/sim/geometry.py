"""Small rigid-transform helpers shared by the world builders.

Quaternions are ``(w, x, y, z)`` like MuJoCo's. Scenario orientations are roll/pitch/yaw in
degrees, extrinsic X-Y-Z (``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``), the REP-103 convention.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np
import numpy.typing as npt

__all__ = [
    "FloatArray",
    "mat_from_quat",
    "quat_conj",
    "quat_from_mat",
    "quat_from_rpy_deg",
    "quat_from_yaw",
    "quat_mul",
    "rotate",
    "rpy_from_quat",
]

FloatArray = npt.NDArray[np.float64]


def quat_from_yaw(yaw_rad: float) -> FloatArray:
    """Quaternion of a rotation by ``yaw_rad`` about +Z."""
    half = 0.5 * yaw_rad
    return np.array([math.cos(half), 0.0, 0.0, math.sin(half)])


def quat_from_rpy_deg(rpy_deg: Sequence[float]) -> FloatArray:
    """Quaternion of roll/pitch/yaw in degrees, extrinsic X-Y-Z."""
    roll, pitch, yaw = (math.radians(float(a)) for a in rpy_deg)
    qx = np.array([math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0])
    qy = np.array([math.cos(pitch / 2), 0.0, math.sin(pitch / 2), 0.0])
    qz = np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
    return quat_mul(qz, quat_mul(qy, qx))


def quat_mul(a: Sequence[float] | FloatArray, b: Sequence[float] | FloatArray) -> FloatArray:
    """Hamilton product ``a ⊗ b`` (apply ``b`` first, then ``a``)."""
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    return out


def quat_conj(q: Sequence[float] | FloatArray) -> FloatArray:
    """Conjugate (the inverse of a unit quaternion)."""
    w, x, y, z = (float(v) for v in q)
    return np.array([w, -x, -y, -z])


def quat_from_mat(mat: Sequence[float] | FloatArray) -> FloatArray:
    """Unit quaternion of a 3x3 rotation matrix (any shape holding 9 row-major values)."""
    out = np.zeros(4)
    mujoco.mju_mat2Quat(out, np.asarray(mat, dtype=np.float64).reshape(9))
    return out


def mat_from_quat(q: Sequence[float] | FloatArray) -> FloatArray:
    """3x3 rotation matrix of a unit quaternion."""
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, np.asarray(q, dtype=np.float64))
    return out.reshape(3, 3)


def rotate(q: Sequence[float] | FloatArray, v: Sequence[float] | FloatArray) -> FloatArray:
    """Rotate vector ``v`` by unit quaternion ``q``."""
    out = np.zeros(3)
    mujoco.mju_rotVecQuat(out, np.asarray(v, dtype=np.float64), np.asarray(q, dtype=np.float64))
    return out


def rpy_from_quat(q: Sequence[float] | FloatArray) -> FloatArray:
    """Roll, pitch, yaw in radians (extrinsic X-Y-Z) of a unit quaternion."""
    r = mat_from_quat(q)
    pitch = math.asin(max(-1.0, min(1.0, -float(r[2, 0]))))
    roll = math.atan2(float(r[2, 1]), float(r[2, 2]))
    yaw = math.atan2(float(r[1, 0]), float(r[0, 0]))
    return np.array([roll, pitch, yaw])
