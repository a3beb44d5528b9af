"""Plug-ins for the multi-robot tests (imported by the scenarios as ``tests.wiring.plugins``)."""

from __future__ import annotations

import logging
import warnings

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


class WarnsInSetup(SystemUnderTest):
    """Warns in set-up as a library would: a Python warning (as MuJoCo's compiler warns) and
    a record on srr's ``harness.sim`` logger (as MuJoCo's runtime warnings arrive)."""

    def setup(self, ctx: SutContext) -> None:
        warnings.warn("Inertia matrix is too close to singular\x1b", UserWarning, stacklevel=1)
        logging.getLogger("harness.sim").warning("MuJoCo: %s", "contact buffer is full")
