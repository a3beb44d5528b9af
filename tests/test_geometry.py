"""The float-tuple quaternion helpers give the numpy versions' values bit for bit (the
per-tick odometry and ground truth use them; their messages must not change by a bit)."""

from __future__ import annotations

import numpy as np

from harness.geometry import qconj, qmul, qrotate, quat_conj, quat_mul, quat_rotate


def test_tuple_quaternions_are_the_numpy_ones_bit_for_bit() -> None:
    rng = np.random.default_rng(3)
    special = np.array([0.0, -0.0, 1.0, -1.0, 1e-308, 5e-324, 0.5])
    for i in range(20_000):
        q = rng.normal(size=4) if i % 3 else rng.choice(special, size=4)
        v = rng.normal(size=3) * 10 if i % 4 else rng.choice(special, size=3)
        w = rng.normal(size=4)
        assert np.array(qrotate(q.tolist(), v.tolist())).tobytes() == quat_rotate(q, v).tobytes()
        assert np.array(qmul(q.tolist(), w.tolist())).tobytes() == quat_mul(q, w).tobytes()
        assert np.array(qconj(q.tolist())).tobytes() == quat_conj(q).tobytes()
