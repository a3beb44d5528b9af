"""Quaternion conversions computed by MuJoCo itself, for the quaternions srr puts into a MuJoCo
model or reads from its poses.

The maths lives in :mod:`harness.geometry` (pure numpy, component order in every name); these
are the few conversions whose results must be MuJoCo's to the last bit: its compiled
``mju_mulQuat``, ``mju_mat2Quat`` and ``mju_rotVecQuat`` round differently from the same
formulas evaluated in Python for some inputs, and the models (and the recordings made with
them) were built with MuJoCo's. Quaternions are (w, x, y, z), MuJoCo's order.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from harness.geometry import FloatArray, FloatVec, quat_wxyz_from_rpy_deg

__all__ = [
    "quat_wxyz_from_mat_mj",
    "quat_wxyz_from_rpy_deg_mj",
    "quat_wxyz_mul_mj",
    "quat_wxyz_rotate_mj",
]


def quat_wxyz_mul_mj(a: FloatVec, b: FloatVec) -> FloatArray:
    """Hamilton product ``a ⊗ b`` (apply ``b``, then ``a``), by ``mju_mulQuat``."""
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    return out


def quat_wxyz_from_mat_mj(mat: FloatVec) -> FloatArray:
    """Unit quaternion of a 3x3 rotation matrix (any shape holding 9 row-major values), by
    ``mju_mat2Quat``."""
    out = np.zeros(4)
    mujoco.mju_mat2Quat(out, np.asarray(mat, dtype=np.float64).reshape(9))
    return out


def quat_wxyz_rotate_mj(q: FloatVec, v: FloatVec) -> FloatArray:
    """Vector ``v`` rotated by the unit quaternion ``q``, by ``mju_rotVecQuat``."""
    out = np.zeros(3)
    mujoco.mju_rotVecQuat(out, np.asarray(v, dtype=np.float64), np.asarray(q, dtype=np.float64))
    return out


def quat_wxyz_from_rpy_deg_mj(rpy_deg: Sequence[float]) -> FloatArray:
    """:func:`harness.geometry.quat_wxyz_from_rpy_deg` composed with :func:`quat_wxyz_mul_mj`."""
    return quat_wxyz_from_rpy_deg(rpy_deg, quat_wxyz_mul_mj)
