"""Systems under test that declare a message type with a typo, for test_message_types."""

from __future__ import annotations

from harness.sut import SutContext, SystemUnderTest


class PublishesTwits(SystemUnderTest):
    def setup(self, ctx: SutContext) -> None:
        self.pub = ctx.publisher("foo", "geometry_msgs/msg/Twits")

    def step(self, now_ns: int) -> None:
        pass


class SubscribesOdometri(SystemUnderTest):
    def setup(self, ctx: SutContext) -> None:
        ctx.subscribe("odom", "nav_msgs/msg/Odometri", lambda msg: None)

    def step(self, now_ns: int) -> None:
        pass


class ShortName(SystemUnderTest):
    def setup(self, ctx: SutContext) -> None:
        self.pub = ctx.publisher("foo", "std_msgs/String")

    def step(self, now_ns: int) -> None:
        pass
