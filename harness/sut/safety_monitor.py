"""Reference safety monitor: mutes the trailer alarm when it is safe to load.

``/safety/is_muted`` is true when the forklift is inside the trailer (past the tripwire, by
its own odometry) and no tracked person is inside the loading ROI. ``/safety/alarm`` is true
while a tracked person is inside the ROI (the route follower slows and stops on it). A new
state is published only after it has held for ``reaction_delay`` seconds (debounce), so a
slower monitor is one parameter away. Zones default to the scenario's ``zones`` block.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from harness.scenario.schema import num
from harness.serde.messages import make
from harness.sut.base import SutContext, SystemUnderTest, sut_params
from harness.sut.errors import PluginError
from harness.sut.pose import OdomPose
from harness.sut.zones import point_in_polygon, side_of_line

__all__ = ["SafetyMonitor", "SafetyMonitorParams"]


@dataclass(frozen=True)
class SafetyMonitorParams:
    odom_topic: str = "odom"
    tracks_topic: str = "/perception/tracks"
    muted_topic: str = "/safety/is_muted"
    alarm_topic: str = "/safety/alarm"
    person_class: str = "person"
    rate_hz: float = num(20.0, 0.0, 1000.0, lo_open=True)
    reaction_delay: float = num(0.0, 0.0, 3600.0)
    roi: tuple[tuple[float, float], ...] = ()
    tripwire: tuple[tuple[float, float], ...] = ()
    inside: Literal["", "left", "right"] = ""


class SafetyMonitor(SystemUnderTest):
    def setup(self, ctx: SutContext) -> None:
        self.p: SafetyMonitorParams = sut_params(SafetyMonitorParams, ctx)
        zones = getattr(ctx.scenario, "zones", None)
        self.roi = self.p.roi or (tuple(zones.loading_roi) if zones else ())
        wire = zones.trailer_tripwire if zones else None
        if self.p.tripwire:
            if len(self.p.tripwire) != 2:
                raise PluginError(f"{ctx.field}.params.tripwire: two points, a and b")
            self.a, self.b = self.p.tripwire
            self.inside = self.p.inside or "left"
        elif wire is not None:
            self.a, self.b, self.inside = wire.a, wire.b, wire.inside
        else:
            raise PluginError(f"{ctx.field}.params.tripwire: not set and the scenario has no "
                              "zones.trailer_tripwire")
        if len(self.roi) < 3:
            raise PluginError(f"{ctx.field}.params.roi: not set and the scenario has no "
                              "zones.loading_roi" if not self.roi else
                              f"{ctx.field}.params.roi: a polygon needs at least three "
                              f"points, got {len(self.roi)}")
        self.pose = OdomPose(ctx, self.p.odom_topic).pose
        self.people: list[tuple[float, float]] = []
        ctx.subscribe(self.p.tracks_topic, "visualization_msgs/msg/MarkerArray", self._on_tracks)
        self.muted_pub = ctx.publisher(self.p.muted_topic, "std_msgs/msg/Bool")
        self.alarm_pub = ctx.publisher(self.p.alarm_topic, "std_msgs/msg/Bool")
        self.period_ns = round(1e9 / self.p.rate_hz)
        self.delay_ns = round(self.p.reaction_delay * 1e9)
        self.next_ns = 0
        self.output = False
        self.pending: tuple[bool, int] | None = None

    def _on_tracks(self, msg: Any) -> None:
        people: list[tuple[float, float]] = []
        for m in msg.markers:
            if m.action == 3:  # DELETEALL
                people = []
            elif m.action == 0 and m.ns == self.p.person_class:
                people.append((m.pose.position.x, m.pose.position.y))
        self.people = people

    def person_in_roi(self) -> bool:
        return any(point_in_polygon(x, y, self.roi) for x, y in self.people)

    def desired(self) -> bool:
        pose = self.pose()
        if pose is None:
            return False
        in_trailer = side_of_line(pose[0], pose[1], self.a, self.b) == self.inside
        return in_trailer and not self.person_in_roi()

    def step(self, now_ns: int) -> None:
        if now_ns < self.next_ns:
            return
        while self.next_ns <= now_ns:
            self.next_ns += self.period_ns
        want = self.desired()
        if want == self.output:
            self.pending = None
        elif self.pending is None or self.pending[0] != want:
            self.pending = (want, now_ns)
        if self.pending is not None and now_ns - self.pending[1] >= self.delay_ns:
            self.output = want
            self.pending = None
        self.muted_pub.publish(make("std_msgs/msg/Bool", data=self.output))
        self.alarm_pub.publish(make("std_msgs/msg/Bool", data=self.person_in_roi()))
