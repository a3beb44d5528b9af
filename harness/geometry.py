"""Small rigid-body helpers. Quaternions are numpy arrays; the order is in each name.

MuJoCo uses (w, x, y, z); ROS messages and Isaac's ``quatd`` attributes use (x, y, z, w).

``qmul``, ``qconj`` and ``qrotate`` do the same arithmetic, in the same order, on tuples of
Python floats, for code that runs every tick: Python floats are IEEE doubles, so the results
are bit for bit those of ``quat_mul``, ``quat_conj`` and ``quat_rotate`` on float64 arrays,
without building arrays.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

__all__ = [
    "Quat",
    "Vec3",
    "qconj",
    "qmul",
    "qrotate",
    "quat_conj",
    "quat_from_rpy",
    "quat_from_yaw",
    "quat_mul",
    "quat_rotate",
    "quat_to_yaw",
    "wxyz_to_xyzw",
    "xyzw_to_wxyz",
    "yaw_between",
]

FloatArray = npt.NDArray[np.float64]
# Quaternions and vectors come in as plain sequences or as numpy arrays.
FloatVec = Sequence[float] | FloatArray
_FLOAT64 = np.dtype(np.float64)
#: A quaternion (order given where used) and a vector as tuples of Python floats.
Quat = tuple[float, float, float, float]
Vec3 = tuple[float, float, float]


def wxyz_to_xyzw(q: FloatVec) -> FloatArray:
    return np.array([q[1], q[2], q[3], q[0]], dtype=np.float64)


def xyzw_to_wxyz(q: FloatVec) -> FloatArray:
    return np.array([q[3], q[0], q[1], q[2]], dtype=np.float64)


def _as_floats(q: FloatVec) -> Sequence[float] | FloatArray:
    """A 1-d float64 array as a list of Python floats (exactly its values), else ``q`` as is.

    Arithmetic on Python floats is the same IEEE double arithmetic as on numpy float64 scalars,
    bit for bit, and several times cheaper; other inputs keep numpy's own promotion rules.
    """
    if type(q) is np.ndarray and q.dtype == _FLOAT64 and q.ndim == 1:
        values: list[float] = q.tolist()
        return values
    return q


def qmul(a: Sequence[float], b: Sequence[float]) -> Quat:
    """Hamilton product of two (w, x, y, z) quaternions of Python floats."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def qconj(q: Sequence[float]) -> Quat:
    """Conjugate of a (w, x, y, z) quaternion of Python floats."""
    return (q[0], -q[1], -q[2], -q[3])


def qrotate(q: Sequence[float], v: Sequence[float]) -> Vec3:
    """Rotate ``v`` by the (w, x, y, z) quaternion ``q`` (Python floats): the products
    ``q * (0, v) * conj(q)`` of :func:`quat_rotate`, term for term (so signed zeros and
    rounding come out the same), written out to save the calls."""
    aw, ax, ay, az = q
    bw, bx, by, bz = 0.0, float(v[0]), float(v[1]), float(v[2])
    tw = aw * bw - ax * bx - ay * by - az * bz
    tx = aw * bx + ax * bw + ay * bz - az * by
    ty = aw * by - ax * bz + ay * bw + az * bx
    tz = aw * bz + ax * by - ay * bx + az * bw
    cw, cx, cy, cz = aw, -ax, -ay, -az
    return (
        tw * cx + tx * cw + ty * cz - tz * cy,
        tw * cy - tx * cz + ty * cw + tz * cx,
        tw * cz + tx * cy - ty * cx + tz * cw,
    )


def quat_mul(a: FloatVec, b: FloatVec) -> FloatArray:
    """Hamilton product of two (w, x, y, z) quaternions."""
    aw, ax, ay, az = _as_floats(a)
    bw, bx, by, bz = _as_floats(b)
    return np.array([
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ], dtype=np.float64)


def quat_conj(q: FloatVec) -> FloatArray:
    return np.array([q[0], -q[1], -q[2], -q[3]], dtype=np.float64)


def quat_rotate(q: FloatVec, v: FloatVec) -> FloatArray:
    """Rotate vector ``v`` by the (w, x, y, z) quaternion ``q``."""
    p = np.array([0.0, v[0], v[1], v[2]])
    return quat_mul(quat_mul(q, p), quat_conj(q))[1:]


def quat_from_yaw(yaw: float) -> FloatArray:
    return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> FloatArray:
    """(w, x, y, z) for extrinsic X-Y-Z rotations (roll, then pitch, then yaw), radians."""
    qx = np.array([math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0])
    qy = np.array([math.cos(pitch / 2), 0.0, math.sin(pitch / 2), 0.0])
    qz = quat_from_yaw(yaw)
    return quat_mul(qz, quat_mul(qy, qx))


def quat_to_yaw(q: FloatVec) -> float:
    w, x, y, z = q
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def yaw_between(front: FloatVec) -> float:
    """Yaw that turns the body +X axis onto ``front`` (projected on the XY plane)."""
    return math.atan2(front[1], front[0])
