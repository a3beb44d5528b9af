"""Plug-ins for the multi-robot tests (imported by the scenarios as ``tests.wiring.plugins``)."""

from __future__ import annotations

from harness.serde.messages import tf_message, transform_stamped
from harness.sut import SutContext, SystemUnderTest


class RogueTransform(SystemUnderTest):
    """Publishes ``map → <bound robot's base_link>`` on ``/tf`` every tick: a second parent
    for a frame the robot's odometry graph already publishes (a localisation node wired
    into the wrong tree)."""

    def setup(self, ctx: SutContext) -> None:
        self.child = ctx.frame("base_link")
        self.pub = ctx.publisher("/tf", "tf2_msgs/msg/TFMessage")

    def step(self, now_ns: int) -> None:
        self.pub.publish(tf_message([transform_stamped(now_ns, "map", self.child,
                                                       (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))]))
