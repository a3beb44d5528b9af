"""Reference system under test: a pure-pursuit route follower.

Subscribes to the robot's ``odom`` and to ``/tf_static`` (for ``world → odom``, so routes are
written in world coordinates), publishes ``cmd_vel`` at ``rate_hz``. It steers towards the
point ``lookahead`` metres further along the route than the closest point, slows down near the
goal and stops within ``goal_tolerance``; after that it keeps publishing zero velocity so its
output stays alive. With ``alarm_topic`` set it slows down and then stops while that topic
says true (the safety monitor's alarm).

Bound to a robot (``robot:`` in the scenario), its relative topics resolve in that robot's
namespace and the odometry's own frame id finds its ``world →`` transform, so one class
drives several robots.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from harness.geometry import dot_floats
from harness.scenario.schema import num
from harness.serde.messages import twist, twist_packer
from harness.sut.base import SutContext, SystemUnderTest, sut_params
from harness.sut.errors import PluginError
from harness.sut.pose import OdomPose

__all__ = ["RouteFollower", "RouteFollowerParams", "clip", "pure_pursuit"]


@dataclass(frozen=True)
class RouteFollowerParams:
    route: str
    speed: float = num(1.2, 0.0, 20.0, lo_open=True)
    lookahead: float = num(1.5, 0.0, 100.0, lo_open=True)
    rate_hz: float = num(20.0, 0.0, 1000.0, lo_open=True)
    goal_tolerance: float = num(0.3, 0.0, 100.0, lo_open=True)
    max_angular: float = num(0.8, 0.0, 20.0)
    slow_radius: float = num(3.0, 0.0, 1000.0, lo_open=True)
    odom_topic: str = "odom"
    cmd_vel_topic: str = "cmd_vel"
    tf_static_topic: str = "/tf_static"
    world_frame: str = "world"
    odom_frame: str = ""  # "": the frame the odometry names in its header
    alarm_topic: str = ""  # e.g. /safety/alarm: slow down, then stop while it is true
    alarm_stop_after: int = num(4, 0, 1_000_000)  # commands at reduced speed before stopping


def clip(x: float, lo: float, hi: float) -> float:
    """``float(np.clip(x, lo, hi))`` for one float, without the array machinery: NaN passes
    through and a tie keeps ``x`` (so ``-0.0`` stays ``-0.0`` against a bound of ``0.0``)."""
    if x != x:
        return x
    m = lo if x < lo else x
    return hi if m > hi else m


def _norm(v: Sequence[float]) -> float:
    """Length of a short vector: ``sqrt`` of :func:`dot_floats`, the same on every CPU."""
    return math.sqrt(dot_floats(v, v))


class _Route:
    """A route as the follower walks it: the waypoints, cumulative arc length, and per
    segment its vector, squared length and length, computed once, as Python floats."""

    def __init__(self, waypoints: object) -> None:
        self.path = np.array(waypoints, dtype=np.float64)
        seg = np.linalg.norm(np.diff(self.path, axis=0), axis=1)
        self.cum = np.concatenate([[0.0], np.cumsum(seg)])
        self.cum_f: list[float] = self.cum.tolist()
        self.points: list[list[float]] = self.path.tolist()
        self.segs = [self.path[i + 1] - self.path[i] for i in range(len(self.path) - 1)]
        self.segs_f: list[list[float]] = [seg.tolist() for seg in self.segs]
        self.length2 = [dot_floats(seg, seg) for seg in self.segs_f]
        self.length = [math.sqrt(l2) for l2 in self.length2]
        last = self.path[-1] - self.path[-2]
        self.last_dir: list[float] = (last / max(_norm(last.tolist()), 1e-9)).tolist()


def _project(route: _Route, px: float, py: float, start: int) -> tuple[float, int]:
    """Arc length of the point of the route closest to (``px``, ``py``), searching segments
    from ``start`` on (progress never goes backwards)."""
    best = (math.inf, route.cum_f[start], start)
    for i in range(start, len(route.points) - 1):
        (ax, ay), (sx, sy), length2 = route.points[i], route.segs_f[i], route.length2[i]
        t = 0.0 if length2 == 0 else clip(dot_floats((px - ax, py - ay), (sx, sy)) / length2,
                                          0.0, 1.0)
        d = _norm((ax + t * sx - px, ay + t * sy - py))
        if d < best[0] - 1e-12:
            best = (d, route.cum_f[i] + t * route.length[i], i)
    return best[1], best[2]


def _point_at(route: _Route, s: float) -> tuple[float, float]:
    cum = route.cum_f
    s = min(max(s, 0.0), cum[-1])
    i = bisect.bisect_right(cum, s) - 1  # np.searchsorted(cum, s, side="right") - 1
    i = min(i, len(cum) - 2)
    seg = cum[i + 1] - cum[i]
    t = 0.0 if seg == 0 else (s - cum[i]) / seg
    (ax, ay), (bx, by) = route.points[i], route.points[i + 1]
    return ax + t * (bx - ax), ay + t * (by - ay)


def pure_pursuit(x: float, y: float, yaw: float, target: Sequence[float]) -> float:
    """Curvature of the arc from pose (x, y, yaw) through ``target``."""
    dx, dy = target[0] - x, target[1] - y
    local_y = -math.sin(yaw) * dx + math.cos(yaw) * dy
    dist2 = dx * dx + dy * dy
    return 0.0 if dist2 < 1e-9 else 2.0 * local_y / dist2


class RouteFollower(SystemUnderTest):
    def setup(self, ctx: SutContext) -> None:
        self.p: RouteFollowerParams = sut_params(RouteFollowerParams, ctx)
        route = ctx.scenario.routes.get(self.p.route)
        if route is None:
            raise PluginError(f"{ctx.field}.params.route: no route named {self.p.route!r} "
                              f"(routes: {', '.join(sorted(ctx.scenario.routes)) or 'none'})")
        self.route = _Route(route.waypoints)
        self.path, self.cum = self.route.path, self.route.cum
        self.period_ns = round(1e9 / self.p.rate_hz)
        self.next_ns = 0
        self.segment = 0
        self.done = False
        self.alarm_ticks = 0
        self.pose = OdomPose(ctx, self.p.odom_topic, self.p.tf_static_topic,
                             self.p.world_frame, self.p.odom_frame).pose
        self.alarm = False
        if self.p.alarm_topic:
            ctx.subscribe(self.p.alarm_topic, "std_msgs/msg/Bool", self._on_alarm)
        self.pub = ctx.publisher(self.p.cmd_vel_topic, "geometry_msgs/msg/Twist")
        self._twist = twist_packer()

    def _on_alarm(self, msg: Any) -> None:
        self.alarm = bool(msg.data)

    def command(self) -> tuple[float, float]:
        pose = self.pose()
        if pose is None or self.done:
            return 0.0, 0.0
        x, y, yaw = pose
        route, p = self.route, self.p
        gx, gy = route.points[-1]
        goal_dist = _norm((gx - x, gy - y))
        s, self.segment = _project(route, x, y, self.segment)
        end = route.cum_f[-1]
        remaining = end - s
        if goal_dist < p.goal_tolerance or (remaining < p.goal_tolerance
                                            and goal_dist < 2 * p.goal_tolerance):
            self.done = True
            return 0.0, 0.0
        target = _point_at(route, s + p.lookahead)
        if s + p.lookahead > end:
            # Past the end of the route: aim along the last segment so the approach stays
            # straight instead of circling the goal.
            (gx, gy), (dx, dy), past = route.points[-1], route.last_dir, s + p.lookahead - end
            target = (gx + dx * past, gy + dy * past)
        v = p.speed * min(1.0, max(0.15, remaining / p.slow_radius))
        if self.alarm:  # a person where the safety monitor says it matters: creep, then stop
            self.alarm_ticks += 1
            v = 0.0 if self.alarm_ticks > p.alarm_stop_after else v * 0.3
        else:
            self.alarm_ticks = 0
        w = clip(pure_pursuit(x, y, yaw, target) * v, -p.max_angular, p.max_angular)
        return v, w

    def step(self, now_ns: int) -> None:
        if now_ns < self.next_ns:
            return
        while self.next_ns <= now_ns:
            self.next_ns += self.period_ns
        v, w = self.command()
        linear, angular = (v, 0.0, 0.0), (0.0, 0.0, w)
        # packed from the values (the Twist object is built only if a subscriber reads it)
        self.pub.publish_serialized(self._twist.pack(*linear, *angular),
                                    partial(twist, linear, angular))
