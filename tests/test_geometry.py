"""harness.geometry: the conversions held to each other (round trips, both component orders),
to MuJoCo's ``mju_`` functions (harness.sim.mjquat is them bit for bit, for the quaternions
that go into a model or come out of its poses), and to scipy's ``Rotation`` as an independent
reference. The float-tuple helpers give the numpy
versions' values bit for bit (the per-tick odometry and ground truth use them)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from harness.geometry import (
    axis_label,
    mat_from_quat_wxyz,
    quat_wxyz_conj,
    quat_wxyz_conj_floats,
    quat_wxyz_from_rpy,
    quat_wxyz_from_rpy_deg,
    quat_wxyz_from_yaw,
    quat_wxyz_mul,
    quat_wxyz_mul_floats,
    quat_wxyz_rotate,
    quat_wxyz_rotate_floats,
    quat_xyzw_mul_columns,
    quat_xyzw_rotate_columns,
    rpy_from_quat_wxyz,
    wxyz_to_xyzw,
    xyzw_to_wxyz,
    yaw_from_quat_wxyz,
    yaw_from_quat_xyzw_columns,
)
from harness.sim.mjquat import (
    quat_wxyz_from_mat_mj,
    quat_wxyz_from_rpy_deg_mj,
    quat_wxyz_mul_mj,
    quat_wxyz_rotate_mj,
)

_SPECIAL = np.array([0.0, -0.0, 1.0, -1.0, 1e-308, 5e-324, 0.5])


def _unit_quats(n: int, seed: int) -> np.ndarray:
    q = np.random.default_rng(seed).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _bits(a: object) -> bytes:
    return np.asarray(a, dtype=np.float64).tobytes()


@pytest.mark.slow
def test_tuple_quaternions_are_the_numpy_ones_bit_for_bit() -> None:
    rng = np.random.default_rng(3)
    for i in range(20_000):
        q = rng.normal(size=4) if i % 3 else rng.choice(_SPECIAL, size=4)
        v = rng.normal(size=3) * 10 if i % 4 else rng.choice(_SPECIAL, size=3)
        w = rng.normal(size=4)
        assert _bits(quat_wxyz_rotate_floats(q.tolist(), v.tolist())) == _bits(
            quat_wxyz_rotate(q, v))
        assert _bits(quat_wxyz_mul_floats(q.tolist(), w.tolist())) == _bits(quat_wxyz_mul(q, w))
        assert _bits(quat_wxyz_conj_floats(q.tolist())) == _bits(quat_wxyz_conj(q))


def test_rotation_of_sequences_is_the_rotation_of_arrays_bit_for_bit() -> None:
    rng = np.random.default_rng(4)
    for i in range(2_000):
        q = rng.normal(size=4) if i % 3 else rng.choice(_SPECIAL, size=4)
        v = rng.normal(size=3)
        assert _bits(quat_wxyz_rotate(q.tolist(), v.tolist())) == _bits(quat_wxyz_rotate(q, v))


@pytest.mark.slow
def test_mujocos_conversions_agree_with_the_pure_ones() -> None:
    """harness.sim.mjquat is MuJoCo's arithmetic, bit for bit, and the same rotations as
    harness.geometry's (to rounding)."""
    rng = np.random.default_rng(5)
    out4, out3, out9 = np.zeros(4), np.zeros(3), np.zeros(9)
    for i in range(5_000):
        a = rng.normal(size=4) if i % 3 else rng.choice(_SPECIAL, size=4)
        b = rng.normal(size=4) if i % 5 else rng.choice(_SPECIAL, size=4)
        mujoco.mju_mulQuat(out4, a, b)
        assert _bits(quat_wxyz_mul_mj(a, b)) == _bits(out4)
        assert _bits(quat_wxyz_mul_mj(a.tolist(), b.tolist())) == _bits(out4)
        np.testing.assert_allclose(quat_wxyz_mul(a, b), out4, rtol=1e-12, atol=1e-12)
    for q in _unit_quats(5_000, 6):
        v = rng.normal(size=3) * 10
        mujoco.mju_rotVecQuat(out3, v, q)
        assert _bits(quat_wxyz_rotate_mj(q, v)) == _bits(out3)
        np.testing.assert_allclose(quat_wxyz_rotate(q, v), out3, rtol=0, atol=1e-12)
        mujoco.mju_quat2Mat(out9, q)
        np.testing.assert_allclose(mat_from_quat_wxyz(q).reshape(9), out9, rtol=0, atol=1e-15)
        mujoco.mju_mat2Quat(out4, out9)
        assert _bits(quat_wxyz_from_mat_mj(out9.reshape(3, 3))) == _bits(out4)
        back = quat_wxyz_from_mat_mj(mat_from_quat_wxyz(q))
        np.testing.assert_allclose(back * np.sign(back @ q), q, atol=1e-12)


def test_model_rotations_compose_with_mujocos_product() -> None:
    """Spawn, mount and camera orientations: roll/pitch/yaw composed by ``mju_mulQuat``."""
    out, tmp = np.zeros(4), np.zeros(4)
    rng = np.random.default_rng(13)
    for _ in range(2_000):
        rpy = rng.uniform(-180.0, 180.0, size=3).tolist()
        roll, pitch, yaw = (math.radians(a) for a in rpy)
        qx = np.array([math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0])
        qy = np.array([math.cos(pitch / 2), 0.0, math.sin(pitch / 2), 0.0])
        mujoco.mju_mulQuat(tmp, qy, qx)
        mujoco.mju_mulQuat(out, quat_wxyz_from_yaw(yaw), tmp)
        assert _bits(quat_wxyz_from_rpy_deg_mj(rpy)) == _bits(out)
        np.testing.assert_allclose(quat_wxyz_from_rpy_deg(rpy), out, rtol=0, atol=1e-15)


@pytest.mark.slow
def test_conversions_agree_with_scipy_in_both_component_orders() -> None:
    rng = np.random.default_rng(8)
    for q in _unit_quats(2_000, 9):
        ref = Rotation.from_quat(wxyz_to_xyzw(q))  # scipy: scalar last
        np.testing.assert_allclose(mat_from_quat_wxyz(q), ref.as_matrix(), atol=1e-12)
        v = rng.normal(size=3)
        np.testing.assert_allclose(quat_wxyz_rotate(q, v), ref.apply(v), atol=1e-12)
        p = _unit_quats(1, int(rng.integers(1 << 30)))[0]
        prod = ref * Rotation.from_quat(wxyz_to_xyzw(p))
        got = quat_wxyz_mul(q, p)
        assert abs(abs(float(np.dot(got, xyzw_to_wxyz(prod.as_quat())))) - 1.0) < 1e-12
        inv = Rotation.from_quat(wxyz_to_xyzw(quat_wxyz_conj(q)))
        assert (inv * ref).magnitude() < 1e-7
        roll, pitch, yaw = rng.uniform(-math.pi, math.pi), rng.uniform(-1.5, 1.5), \
            rng.uniform(-math.pi, math.pi)
        ours = quat_wxyz_from_rpy(roll, pitch, yaw)
        theirs = Rotation.from_euler("xyz", [roll, pitch, yaw]).as_quat()  # extrinsic
        assert abs(abs(float(np.dot(ours, xyzw_to_wxyz(theirs)))) - 1.0) < 1e-12
        np.testing.assert_allclose(rpy_from_quat_wxyz(ours), [roll, pitch, yaw], atol=1e-9)
        ref_yaw = Rotation.from_quat(wxyz_to_xyzw(ours)).as_euler("xyz")[2]
        assert math.remainder(yaw_from_quat_wxyz(quat_wxyz_from_yaw(yaw)) - yaw, math.tau) \
            == pytest.approx(0.0, abs=1e-12)
        assert math.remainder(rpy_from_quat_wxyz(ours)[2] - ref_yaw, math.tau) \
            == pytest.approx(0.0, abs=1e-9)


@pytest.mark.slow
def test_round_trips() -> None:
    for q in _unit_quats(2_000, 10):
        assert _bits(xyzw_to_wxyz(wxyz_to_xyzw(q))) == _bits(q)
        assert _bits(wxyz_to_xyzw(xyzw_to_wxyz(q))) == _bits(q)
        back = quat_wxyz_from_rpy(*rpy_from_quat_wxyz(q))
        np.testing.assert_allclose(back * np.sign(back @ q), q, atol=1e-9)
        np.testing.assert_allclose(quat_wxyz_mul(q, quat_wxyz_conj(q)), [1.0, 0.0, 0.0, 0.0],
                                   atol=1e-12)
        v = q[1:] * 3
        np.testing.assert_allclose(quat_wxyz_rotate(quat_wxyz_conj(q), quat_wxyz_rotate(q, v)),
                                   v, atol=1e-12)
    rpy = [10.0, -20.0, 135.0]
    assert _bits(quat_wxyz_from_rpy_deg(rpy)) == _bits(
        quat_wxyz_from_rpy(*(math.radians(a) for a in rpy)))


def test_yaw_of_columns_is_the_yaw_of_each_quaternion() -> None:
    qs = _unit_quats(5_000, 11)
    xyzw = np.stack([wxyz_to_xyzw(q) for q in qs])
    cols = yaw_from_quat_xyzw_columns(xyzw[:, 0], xyzw[:, 1], xyzw[:, 2], xyzw[:, 3])
    one_by_one = np.array([yaw_from_quat_wxyz(q.tolist()) for q in qs])
    np.testing.assert_allclose(cols, one_by_one, rtol=0, atol=1e-15)
    yaws = np.random.default_rng(12).uniform(-math.pi, math.pi, size=1_000)
    flat = np.stack([wxyz_to_xyzw(quat_wxyz_from_yaw(float(y))) for y in yaws])
    np.testing.assert_allclose(
        yaw_from_quat_xyzw_columns(flat[:, 0], flat[:, 1], flat[:, 2], flat[:, 3]), yaws,
        atol=1e-12)


def test_columns_are_the_one_quaternion_functions_row_by_row() -> None:
    """The tables' (x, y, z, w) columns: the product is the tuple product's, bit for bit, in
    the other component order; the rotation is the same rotation (to rounding) and scipy's."""
    rng = np.random.default_rng(14)
    a, b = _unit_quats(3_000, 15), _unit_quats(3_000, 16)
    a[::50] = rng.choice(_SPECIAL, size=a[::50].shape)
    v = rng.normal(size=(3_000, 3)) * 5
    xyzw_a = np.stack([wxyz_to_xyzw(q) for q in a])
    xyzw_b = np.stack([wxyz_to_xyzw(q) for q in b])
    prod = quat_xyzw_mul_columns(xyzw_a, xyzw_b)
    rot = quat_xyzw_rotate_columns(xyzw_b, v)
    for i in range(len(a)):
        assert _bits(xyzw_to_wxyz(prod[i])) == _bits(quat_wxyz_mul_floats(a[i].tolist(),
                                                                          b[i].tolist()))
        np.testing.assert_allclose(rot[i], quat_wxyz_rotate(b[i], v[i]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(rot, Rotation.from_quat(xyzw_b).apply(v), rtol=0, atol=1e-12)
    one = quat_xyzw_rotate_columns(xyzw_b[0], v)  # one rotation broadcast over many vectors
    np.testing.assert_allclose(one, Rotation.from_quat(xyzw_b[0]).apply(v), rtol=0, atol=1e-12)


def test_axis_label_names_axes_and_gives_other_directions_as_unit_vectors() -> None:
    assert axis_label((0.0, 2.0)) == "+y"
    assert axis_label((-3.0, 0.0, 0.0), upper=True) == "-X"
    assert axis_label((0.0, 0.0, 1e-9 + 1.0)) == "+z"
    assert axis_label((1.0, 1.0)) == "[0.71, 0.71]"
    assert axis_label((0.0, -0.6, 0.8), upper=True) == "[0.00, -0.60, 0.80]"
