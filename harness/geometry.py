"""Rotations: the one module srr does its quaternion, roll/pitch/yaw and rotation-matrix maths
in; and the side of a directed line (:func:`side_of_line`, which the safety monitor and the
scenario checks share). Pure numpy and Python floats, no MuJoCo.

Component order is part of every name that takes or gives a quaternion:

* ``wxyz`` — scalar first, MuJoCo's order, the one the functions here compute in.
* ``xyzw`` — scalar last, the order of ROS ``geometry_msgs/Quaternion`` fields and of Isaac's
  ``quatd`` attributes (IJKR), and of the recorded tables' columns (``*_xyzw_columns``).
  Convert at the edge with :func:`wxyz_to_xyzw` and :func:`xyzw_to_wxyz`.

Angles are radians unless the name ends in ``_deg``. Roll/pitch/yaw are extrinsic X-Y-Z
(``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``), the REP-103 convention. Products are Hamilton
products: ``quat_wxyz_mul(a, b)`` applies ``b`` first, then ``a``.

Three kinds of values: numpy float64 arrays (``quat_wxyz_*``); tuples of Python floats
(``*_floats``) for code that runs every tick; columns of tables (``*_columns``). Python floats
are IEEE doubles and numpy works elementwise, so the three give the same values bit for bit:
they share one expression per formula.

Recorded data depends on the exact order of each floating-point operation, so each formula is
written once, in the order its results were first recorded in. :func:`yaw_from_quat_wxyz`
(``math.atan2``, one quaternion, as the systems under test use it) and
:func:`yaw_from_quat_xyzw_columns` (``numpy.arctan2``, table columns, as the metrics use it)
share one expression; the two ``atan2`` may differ in the last bit. The tables rotate in the
cross-product form they were first computed in (:func:`quat_xyzw_rotate_columns`), the rest
by Hamilton products. MuJoCo's compiled
``mju_mulQuat``, ``mju_mat2Quat`` and ``mju_rotVecQuat`` round differently from the same
formulas in Python for some inputs, so quaternions that go into a MuJoCo model or come out
of its poses are computed by MuJoCo itself, in :mod:`harness.sim.mjquat` (which passes
MuJoCo's product as the ``mul`` of :func:`quat_wxyz_from_rpy_deg`).

Nothing here, and nothing else on a recording's path, multiplies vectors or matrices through
numpy's ``@``, ``dot`` or ``linalg.norm`` of a vector: those call BLAS, and OpenBLAS picks its
kernel by CPU (a 2-element dot product is fused multiply-add on AVX-512 kernels and not on
others, a 3x3 product differs between AVX2 and older kernels), so the same run recorded
different bytes on different machines. :func:`dot_floats` and :func:`rotate_rows` write the
sums out, one IEEE operation at a time, in a fixed order.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = [
    "FloatArray",
    "FloatVec",
    "QuatProduct",
    "QuatTuple",
    "Vec3",
    "axis_label",
    "cross_2d",
    "dot_floats",
    "mat_from_quat_wxyz",
    "quat_wxyz_conj",
    "quat_wxyz_conj_floats",
    "quat_wxyz_from_rpy",
    "quat_wxyz_from_rpy_deg",
    "quat_wxyz_from_yaw",
    "quat_wxyz_mul",
    "quat_wxyz_mul_floats",
    "quat_wxyz_rotate",
    "quat_wxyz_rotate_floats",
    "quat_xyzw_mul_columns",
    "quat_xyzw_rotate_columns",
    "rotate_rows",
    "rpy_from_quat_wxyz",
    "side_of_line",
    "signed_area",
    "wxyz_to_xyzw",
    "xyzw_to_wxyz",
    "yaw_between",
    "yaw_from_quat_wxyz",
    "yaw_from_quat_xyzw_columns",
]

FloatArray = npt.NDArray[np.float64]
#: Quaternions and vectors come in as plain sequences or as numpy arrays.
FloatVec = Sequence[float] | FloatArray
_FLOAT64 = np.dtype(np.float64)
#: A (w, x, y, z) quaternion and a vector as tuples of Python floats.
QuatTuple = tuple[float, float, float, float]
Vec3 = tuple[float, float, float]
#: A product of two (w, x, y, z) quaternions, such as :func:`quat_wxyz_mul`.
QuatProduct = Callable[[FloatVec, FloatVec], FloatArray]



# --------------------------------------------------------------------------- component order


def wxyz_to_xyzw(q: FloatVec) -> FloatArray:
    """A (w, x, y, z) quaternion as (x, y, z, w)."""
    return np.array([q[1], q[2], q[3], q[0]], dtype=np.float64)


def xyzw_to_wxyz(q: FloatVec) -> FloatArray:
    """An (x, y, z, w) quaternion as (w, x, y, z)."""
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


# --------------------------------------------------------------------------- products


def _hamilton(a: Any, b: Any) -> tuple[Any, Any, Any, Any]:
    """Hamilton product ``a ⊗ b`` of (w, x, y, z) components: numbers, or numpy arrays of
    them (elementwise, the same IEEE operations in the same order)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def quat_wxyz_mul_floats(a: FloatVec, b: FloatVec) -> QuatTuple:
    """Hamilton product ``a ⊗ b`` of two (w, x, y, z) quaternions (apply ``b``, then ``a``)."""
    return _hamilton(a, b)


def quat_wxyz_conj_floats(q: FloatVec) -> QuatTuple:
    """Conjugate of a (w, x, y, z) quaternion (its inverse when it is a unit one)."""
    return (q[0], -q[1], -q[2], -q[3])


def quat_wxyz_rotate_floats(q: FloatVec, v: FloatVec) -> Vec3:
    """Rotate ``v`` by the (w, x, y, z) quaternion ``q``: the products
    ``q ⊗ (0, v) ⊗ conj(q)``."""
    _, x, y, z = _hamilton(_hamilton(q, (0.0, float(v[0]), float(v[1]), float(v[2]))),
                           quat_wxyz_conj_floats(q))
    return (x, y, z)


def quat_wxyz_mul(a: FloatVec, b: FloatVec) -> FloatArray:
    """:func:`quat_wxyz_mul_floats` on arrays or sequences."""
    return np.array(quat_wxyz_mul_floats(_as_floats(a), _as_floats(b)), dtype=np.float64)


def quat_wxyz_conj(q: FloatVec) -> FloatArray:
    """:func:`quat_wxyz_conj_floats` on an array or a sequence."""
    return np.array(quat_wxyz_conj_floats(q), dtype=np.float64)


def quat_wxyz_rotate(q: FloatVec, v: FloatVec) -> FloatArray:
    """Rotate vector ``v`` by the (w, x, y, z) quaternion ``q``:
    :func:`quat_wxyz_rotate_floats` on arrays or sequences."""
    qf = _as_floats(q)
    if qf is q:  # not a 1-d float64 array: numpy's promotion rules, on arrays
        p = np.array([0.0, v[0], v[1], v[2]])
        return quat_wxyz_mul(quat_wxyz_mul(q, p), quat_wxyz_conj(q))[1:]
    return np.array(quat_wxyz_rotate_floats(qf, v), dtype=np.float64)


def quat_xyzw_mul_columns(a: FloatArray, b: FloatArray) -> FloatArray:
    """:func:`quat_wxyz_mul_floats` of (x, y, z, w) quaternions along the last axis of ``a`` and
    ``b`` (broadcasting over the leading axes)."""
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    w, x, y, z = _hamilton((aw, ax, ay, az), (bw, bx, by, bz))
    return np.stack([x, y, z, w], axis=-1)


def quat_xyzw_rotate_columns(q: FloatArray, v: FloatArray) -> FloatArray:
    """Vectors ``v`` (..., 3) rotated by (x, y, z, w) quaternions ``q`` (..., 4), in the
    cross-product form ``v + w t + q⃗ × t`` with ``t = 2 q⃗ × v`` (the tables' arithmetic; the
    same rotation as :func:`quat_wxyz_rotate` to rounding)."""
    u = q[..., :3]
    w = q[..., 3:4]
    t = 2.0 * np.cross(u, v)
    out: FloatArray = v + w * t + np.cross(u, t)
    return out


# --------------------------------------------------------------------------- angles


def quat_wxyz_from_yaw(yaw: float) -> FloatArray:
    """(w, x, y, z) of a rotation by ``yaw`` about +Z."""
    return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


def quat_wxyz_from_rpy(roll: float, pitch: float, yaw: float,
                       mul: QuatProduct | None = None) -> FloatArray:
    """(w, x, y, z) of extrinsic X-Y-Z rotations (roll, then pitch, then yaw), composed with
    ``mul`` (default :func:`quat_wxyz_mul`)."""
    mul = mul or quat_wxyz_mul
    qx = np.array([math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0])
    qy = np.array([math.cos(pitch / 2), 0.0, math.sin(pitch / 2), 0.0])
    qz = quat_wxyz_from_yaw(yaw)
    return mul(qz, mul(qy, qx))


def quat_wxyz_from_rpy_deg(rpy_deg: Sequence[float],
                           mul: QuatProduct | None = None) -> FloatArray:
    """:func:`quat_wxyz_from_rpy` of (roll, pitch, yaw) in degrees."""
    roll, pitch, yaw = (math.radians(float(a)) for a in rpy_deg)
    return quat_wxyz_from_rpy(roll, pitch, yaw, mul)


def _yaw_terms(w: Any, x: Any, y: Any, z: Any) -> tuple[Any, Any]:
    """The ``atan2`` arguments of the yaw of (w, x, y, z): scalars or arrays."""
    return 2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)


def yaw_from_quat_wxyz(q: FloatVec) -> float:
    """Yaw of a (w, x, y, z) quaternion (the rotation about +Z of its extrinsic X-Y-Z
    roll/pitch/yaw, exact for the pure yaw rotations of ground vehicles)."""
    w, x, y, z = q
    return math.atan2(*_yaw_terms(w, x, y, z))


def yaw_from_quat_xyzw_columns(qx: Any, qy: Any, qz: Any, qw: Any) -> Any:
    """:func:`yaw_from_quat_wxyz` of columns of (x, y, z, w) components (numpy arrays, pandas
    columns or scalars), with ``numpy.arctan2``."""
    return np.arctan2(*_yaw_terms(qw, qx, qy, qz))


def axis_label(v: Sequence[float], *, upper: bool = False) -> str:
    """The direction of ``v`` (2 or 3 numbers, not all zero) in words for a message: ``+y``
    (``+Y`` with ``upper``, for a body's own axes) where it is an axis, else its unit vector
    as ``[0.71, 0.71]``."""
    norm = math.sqrt(sum(c * c for c in v))
    unit = [c / norm for c in v] if norm > 0.0 else [float(c) for c in v]
    for i, c in enumerate(unit):
        if abs(abs(c) - 1.0) < 1e-6:
            name = "XYZ"[i] if upper else "xyz"[i]
            return f"{'+' if c > 0 else '-'}{name}"
    return "[" + ", ".join(f"{c:.2f}" for c in unit) + "]"


def yaw_between(front: FloatVec) -> float:
    """Yaw that turns the body +X axis onto ``front`` (projected on the XY plane)."""
    return math.atan2(front[1], front[0])


# --------------------------------------------------------------------------- matrices


def dot_floats(a: Sequence[float], b: Sequence[float]) -> float:
    """``a · b`` of two short vectors of Python floats, summed left to right without fused
    multiply-adds (``a[0] * b[0] + a[1] * b[1] + ...``): the same value on every CPU, where
    numpy's ``a @ b`` is BLAS's, which is not."""
    products = [x * y for x, y in zip(a, b, strict=True)]
    total = products[0]
    for p in products[1:]:
        total += p
    return total


def rotate_rows(v: FloatArray, rot: FloatArray) -> FloatArray:
    """``v @ rot.T``: each row of ``v`` (n x 3) rotated by the 3x3 ``rot``, written out as
    ``x * r[i, 0] + y * r[i, 1] + z * r[i, 2]`` per output column, summed in that order, so
    that the result does not depend on the CPU's BLAS kernel (column by column: 2-4x faster
    than broadcasting over rows of three; BLAS is faster still)."""
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    out: FloatArray = np.empty((len(v), 3))
    for i in range(3):
        a, b, c = (float(e) for e in rot[i])
        out[:, i] = x * a + y * b + z * c
    return out


def mat_from_quat_wxyz(q: FloatVec) -> FloatArray:
    """3x3 rotation matrix of a unit (w, x, y, z) quaternion (columns: its rotated axes)."""
    w, x, y, z = (float(c) for c in q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def rpy_from_quat_wxyz(q: FloatVec) -> FloatArray:
    """Roll, pitch, yaw (extrinsic X-Y-Z) of a unit (w, x, y, z) quaternion."""
    r = mat_from_quat_wxyz(q)
    pitch = math.asin(max(-1.0, min(1.0, -float(r[2, 0]))))
    roll = math.atan2(float(r[2, 1]), float(r[2, 2]))
    yaw = math.atan2(float(r[1, 0]), float(r[0, 0]))
    return np.array([roll, pitch, yaw])


def cross_2d(a: Sequence[float], b: Sequence[float], p: Sequence[float]) -> float:
    """Twice the signed area of the triangle a, b, p (x and y only): positive when ``p`` is
    left of the directed line a → b (seen from above, +Z), negative right, 0 on it."""
    return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])


def signed_area(polygon: Sequence[Sequence[float]]) -> float:
    """The area of a simple polygon (x and y), positive when its points go counter-clockwise
    (the shoelace formula); 0 for fewer than three points."""
    ring = list(polygon)
    return sum(x0 * y1 - x1 * y0 for (x0, y0, *_), (x1, y1, *_)
               in zip(ring, ring[1:] + ring[:1], strict=True)) / 2 if len(ring) >= 3 else 0.0


def side_of_line(x: float, y: float, a: Sequence[float], b: Sequence[float]) -> str:
    """``"left"`` or ``"right"`` of the directed line a → b (on the line counts as right).
    Left is seen from above (+Z), walking from ``a`` to ``b``: the side ``b - a`` turned +90°
    (counter-clockwise) points to; for a → b along +x, left is +y."""
    return "left" if cross_2d(a, b, (x, y)) > 0 else "right"
