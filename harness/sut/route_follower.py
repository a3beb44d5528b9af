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

import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from harness.bus.messages import twist
from harness.errors import PluginError
from harness.sut.base import SutContext, SystemUnderTest, sut_params
from harness.sut.pose import OdomPose

__all__ = ["RouteFollower", "RouteFollowerParams", "pure_pursuit"]


@dataclass(frozen=True)
class RouteFollowerParams:
    route: str
    speed: float = 1.2
    lookahead: float = 1.5
    rate_hz: float = 20.0
    goal_tolerance: float = 0.3
    max_angular: float = 0.8
    slow_radius: float = 3.0
    odom_topic: str = "odom"
    cmd_vel_topic: str = "cmd_vel"
    tf_static_topic: str = "/tf_static"
    world_frame: str = "world"
    odom_frame: str = ""  # "": the frame the odometry names in its header
    alarm_topic: str = ""  # e.g. /safety/alarm: slow down, then stop while it is true
    alarm_stop_after: int = 4  # commands at reduced speed before stopping


def _project(path: np.ndarray, cum: np.ndarray, p: np.ndarray, start: int) -> tuple[float, int]:
    """Arc length of the point of the path closest to ``p``, searching segments from
    ``start`` on (progress never goes backwards)."""
    best = (math.inf, cum[start], start)
    for i in range(start, len(path) - 1):
        a, b = path[i], path[i + 1]
        seg = b - a
        length2 = float(seg @ seg)
        t = 0.0 if length2 == 0 else float(np.clip((p - a) @ seg / length2, 0.0, 1.0))
        d = float(np.linalg.norm(a + t * seg - p))
        if d < best[0] - 1e-12:
            best = (d, cum[i] + t * math.sqrt(length2), i)
    return best[1], best[2]


def _point_at(path: np.ndarray, cum: np.ndarray, s: float) -> npt.NDArray[np.float64]:
    s = min(max(s, 0.0), float(cum[-1]))
    i = int(np.searchsorted(cum, s, side="right") - 1)
    i = min(i, len(path) - 2)
    seg = cum[i + 1] - cum[i]
    t = 0.0 if seg == 0 else (s - cum[i]) / seg
    # Indexing an unshaped array is typed as Any; the rows of ``path`` are float64 points.
    return cast("npt.NDArray[np.float64]", path[i] + t * (path[i + 1] - path[i]))


def pure_pursuit(x: float, y: float, yaw: float, target: np.ndarray) -> float:
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
        self.path = np.array(route.waypoints, dtype=np.float64)
        seg = np.linalg.norm(np.diff(self.path, axis=0), axis=1)
        self.cum = np.concatenate([[0.0], np.cumsum(seg)])
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

    def _on_alarm(self, msg: Any) -> None:
        self.alarm = bool(msg.data)

    def command(self) -> tuple[float, float]:
        pose = self.pose()
        if pose is None or self.done:
            return 0.0, 0.0
        x, y, yaw = pose
        here = np.array([x, y])
        goal_dist = float(np.linalg.norm(self.path[-1] - here))
        s, self.segment = _project(self.path, self.cum, here, self.segment)
        remaining = float(self.cum[-1]) - s
        if goal_dist < self.p.goal_tolerance or (remaining < self.p.goal_tolerance
                                                 and goal_dist < 2 * self.p.goal_tolerance):
            self.done = True
            return 0.0, 0.0
        target = _point_at(self.path, self.cum, s + self.p.lookahead)
        if s + self.p.lookahead > self.cum[-1]:
            # Past the end of the route: aim along the last segment so the approach stays
            # straight instead of circling the goal.
            direction = self.path[-1] - self.path[-2]
            direction = direction / max(float(np.linalg.norm(direction)), 1e-9)
            target = self.path[-1] + direction * (s + self.p.lookahead - self.cum[-1])
        v = self.p.speed * min(1.0, max(0.15, remaining / self.p.slow_radius))
        if self.alarm:  # a person where the safety monitor says it matters: creep, then stop
            self.alarm_ticks += 1
            v = 0.0 if self.alarm_ticks > self.p.alarm_stop_after else v * 0.3
        else:
            self.alarm_ticks = 0
        w = float(np.clip(pure_pursuit(x, y, yaw, target) * v,
                          -self.p.max_angular, self.p.max_angular))
        return v, w

    def step(self, now_ns: int) -> None:
        if now_ns < self.next_ns:
            return
        while self.next_ns <= now_ns:
            self.next_ns += self.period_ns
        v, w = self.command()
        self.pub.publish(twist((v, 0.0, 0.0), (0.0, 0.0, w)))
