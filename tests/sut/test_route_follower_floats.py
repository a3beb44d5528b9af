"""The route follower computes on Python floats what it computed on small numpy arrays; these
tests hold it to the numpy version (kept here as the reference) bit for bit, through the real
bus, scenario and messages, over poses along, off and past the bundled route. The reference
sums its dot products elementwise (``np.sum(a * b)``), not with ``@``: BLAS's kernel, and so
its last bit, depends on the CPU, and the follower's outputs must not
(``tests/e2e/test_cross_cpu.py``)."""

from __future__ import annotations

import math
import random
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness import api
from harness.bus import Bus
from harness.geometry import (
    quat_wxyz_from_yaw,
    quat_wxyz_mul,
    quat_wxyz_rotate,
    xyzw_to_wxyz,
    yaw_from_quat_wxyz,
)
from harness.serde.messages import Pose, odometry, tf_message_of
from harness.sut.base import SutContext
from harness.sut.route_follower import (
    RouteFollower,
    _point_at,
    _project,
    _Route,
    clip,
    pure_pursuit,
)

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"


# -- the numpy reference (the follower's code before it moved to Python floats) -------------

def ref_dot(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sum(a * b))


def ref_norm(v: np.ndarray) -> float:
    return math.sqrt(ref_dot(v, v))


def ref_project(path: np.ndarray, cum: np.ndarray, p: np.ndarray, start: int) -> tuple[Any, int]:
    best = (math.inf, cum[start], start)
    for i in range(start, len(path) - 1):
        a, b = path[i], path[i + 1]
        seg = b - a
        length2 = ref_dot(seg, seg)
        t = 0.0 if length2 == 0 else float(np.clip(ref_dot(p - a, seg) / length2, 0.0, 1.0))
        d = ref_norm(a + t * seg - p)
        if d < best[0] - 1e-12:
            best = (d, cum[i] + t * math.sqrt(length2), i)
    return best[1], best[2]


def ref_point_at(path: np.ndarray, cum: np.ndarray, s: float) -> np.ndarray:
    s = min(max(s, 0.0), float(cum[-1]))
    i = int(np.searchsorted(cum, s, side="right") - 1)
    i = min(i, len(path) - 2)
    seg = cum[i + 1] - cum[i]
    t = 0.0 if seg == 0 else (s - cum[i]) / seg
    out: np.ndarray = path[i] + t * (path[i + 1] - path[i])
    return out


def ref_command(f: RouteFollower, pose: tuple[float, float, float],
                segment: int) -> tuple[float, float, int, bool]:
    """(v, w, segment, done) as the numpy follower computed them (no alarm)."""
    p, path, cum = f.p, f.path, f.cum
    x, y, yaw = pose
    here = np.array([x, y])
    goal_dist = ref_norm(path[-1] - here)
    s, segment = ref_project(path, cum, here, segment)
    remaining = float(cum[-1]) - s
    if goal_dist < p.goal_tolerance or (remaining < p.goal_tolerance
                                        and goal_dist < 2 * p.goal_tolerance):
        return 0.0, 0.0, segment, True
    target = ref_point_at(path, cum, s + p.lookahead)
    if s + p.lookahead > cum[-1]:
        direction = path[-1] - path[-2]
        direction = direction / max(ref_norm(direction), 1e-9)
        target = path[-1] + direction * (s + p.lookahead - cum[-1])
    v = p.speed * min(1.0, max(0.15, remaining / p.slow_radius))
    w = float(np.clip(pure_pursuit(x, y, yaw, target) * v, -p.max_angular, p.max_angular))
    return float(v), w, segment, False


def ref_pose(t0: np.ndarray, q0: np.ndarray, odom: Any) -> tuple[float, float, float]:
    p, q = odom.pose.pose.position, odom.pose.pose.orientation
    pos = t0 + quat_wxyz_rotate(q0, [p.x, p.y, p.z])
    yaw = yaw_from_quat_wxyz(quat_wxyz_mul(q0, xyzw_to_wxyz([q.x, q.y, q.z, q.w])))
    return float(pos[0]), float(pos[1]), yaw


def bits(values: tuple[float, ...]) -> tuple[str, ...]:
    return tuple(float(v).hex() for v in values)


# -- tests -----------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", [1, 2])
def test_follower_commands_are_the_numpy_ones_bit_for_bit(seed: int) -> None:
    sc = api.load(SCENARIO)
    bus = Bus(lambda: 0)
    follower = RouteFollower()
    follower.setup(SutContext.for_spec(sc.systems_under_test[0], sc, bus,
                                       "systems_under_test[0]"))
    rng = random.Random(seed)
    # world -> odom: a turned and shifted odometry frame, so the chain's arithmetic shows
    t0 = np.array([rng.uniform(-13, -11), rng.uniform(-4, -2), 0.0])
    q0 = quat_wxyz_from_yaw(rng.uniform(-0.3, 0.3))
    bus.publish("/tf_static", "tf2_msgs/msg/TFMessage", tf_message_of(
        0, [Pose("world", "odom", t0, (q0[1], q0[2], q0[3], q0[0]))]))
    route = follower.path
    segment, done, compared, past_end = 0, False, 0, 0
    for k in range(400):
        # walk along the route (progress only grows), with lateral noise and random headings
        s = min(k / 399 * 1.08, 1.0) * float(follower.cum[-1]) + rng.uniform(-0.5, 0.5)
        wx, wy = ref_point_at(route, follower.cum, s).tolist()
        wx, wy = wx + rng.gauss(0, 0.6), wy + rng.gauss(0, 0.6)
        if k % 50 == 49:  # now and then exactly on a waypoint
            wx, wy = route[rng.randrange(len(route))].tolist()
        yaw = rng.uniform(-math.pi, math.pi)
        # the odometry that puts the robot there: inverse of world -> odom
        inv = np.array([q0[0], -q0[1], -q0[2], -q0[3]])
        local = quat_wxyz_rotate(inv, np.array([wx, wy, 0.0]) - t0)
        qo = quat_wxyz_mul(inv, quat_wxyz_from_yaw(yaw))
        msg = odometry(0, "odom", "base_link", local, (qo[1], qo[2], qo[3], qo[0]),
                       (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        bus.publish("/odom", "nav_msgs/msg/Odometry", msg)
        bus.spin()
        pose = follower.pose()
        assert pose is not None
        assert bits(pose) == bits(ref_pose(t0, q0, msg))
        v, w = follower.command()
        if done:
            assert (v, w) == (0.0, 0.0)
            follower.done = done = False  # keep comparing past the goal
            continue
        rv, rw, segment, done = ref_command(follower, pose, segment)
        assert bits((v, w)) == bits((rv, rw)), k
        assert follower.segment == segment and follower.done == done
        compared += 1
        past_end += pose is not None and segment == len(route) - 2
    assert compared > 300 and past_end > 20


def test_clip_is_numpy_clip_on_floats() -> None:
    special = [0.0, -0.0, 1.0, -1.0, 0.5, math.inf, -math.inf, math.nan, 1e-300, -1e-300]
    rng = random.Random(3)
    values = special + [rng.uniform(-2, 2) for _ in range(2000)]
    for lo, hi in [(0.0, 1.0), (-0.8, 0.8), (-0.0, 0.0), (0.0, -0.0)]:
        for x in values:
            want = float(np.clip(np.float64(x), lo, hi))
            got = clip(x, lo, hi)
            assert math.isnan(got) if math.isnan(want) else got.hex() == want.hex(), (x, lo, hi)


@pytest.mark.slow
@pytest.mark.parametrize("waypoints", [
    [[-12.0, -3.0], [-3.0, -3.0], [3.0, 0.0], [15.0, 0.0], [21.0, 0.0]],  # forklift_warehouse
    [[0.0, 0.0], [0.0, 0.0], [2.5, 1.7], [-1.3, 4.1], [-1.3, 4.1], [7.7, -2.9]],  # repeats
])
def test_projection_and_lookahead_point_are_the_numpy_ones(waypoints: list[list[float]]) -> None:
    """The arc length of the closest point and the point further along, for points all over
    the route's box and every start segment (the follower's commands only show these when a
    last bit changes the command)."""
    route = _Route(waypoints)
    rng = random.Random(4)
    for _ in range(3000):
        here = np.array([rng.uniform(-14, 23), rng.uniform(-6, 6)])
        for start in range(len(waypoints) - 1):
            s, i = _project(route, float(here[0]), float(here[1]), start)
            rs, ri = ref_project(route.path, route.cum, here, start)
            assert (float(s).hex(), i) == (float(rs).hex(), ri)
        s = rng.uniform(-1.0, float(route.cum[-1]) + 2.0)
        assert bits(_point_at(route, s)) == bits(tuple(ref_point_at(route.path, route.cum, s)))
