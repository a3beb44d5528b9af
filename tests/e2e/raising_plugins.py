"""Systems under test that raise: the code under test breaking during a run, in each hook."""

from __future__ import annotations

from typing import Any

from harness.sut.base import SutContext
from harness.sut.route_follower import RouteFollower

#: Simulated time at which the plug-ins raise.
AT_NS = 1_000_000_000


class RaisesInStep(RouteFollower):
    def step(self, now_ns: int) -> None:
        if now_ns >= AT_NS:
            raise RuntimeError("boom in step")
        super().step(now_ns)


class RaisesInSetup(RouteFollower):
    def setup(self, ctx: SutContext) -> None:
        raise ValueError("boom in setup")


class RaisesInCallback(RouteFollower):
    def setup(self, ctx: SutContext) -> None:
        super().setup(ctx)
        ctx.subscribe("/clock", "rosgraph_msgs/msg/Clock", self._on_clock)

    def _on_clock(self, msg: Any) -> None:
        if msg.clock.sec * 1_000_000_000 + msg.clock.nanosec >= AT_NS:
            raise KeyError("boom in a callback")
