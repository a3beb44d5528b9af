"""Graph builders and a plug-in for the ROS 1 output tests: one clock graph spelled with Isaac
Sim's ROS 1 bridge node, one with its ROS 2 bridge node, and a system under test that
publishes a type ROS 1 Noetic does not have."""

from __future__ import annotations

from typing import Any

from harness import graph as og
from harness.serde.messages import make
from harness.sut import SutContext, SystemUnderTest

keys = og.Controller.Keys


def _clock_graph(ctx: Any, type_name: str, topic: str) -> None:
    og.Controller.edit(ctx.graph_config, {
        keys.CREATE_NODES: [("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
                            ("PublishClock", type_name)],
        keys.CONNECT: [("OnPlaybackTick.outputs:tick", "PublishClock.inputs:execIn")],
        keys.SET_VALUES: [("PublishClock.inputs:topicName", topic)],
    })


def ros1_clock(ctx: Any) -> None:
    _clock_graph(ctx, "omni.isaac.ros_bridge.ROS1PublishClock", "/clock")


def ros2_clock(ctx: Any) -> None:
    _clock_graph(ctx, "isaacsim.ros2.bridge.ROS2PublishClock", "/clock")


class Velocity(SystemUnderTest):
    """Publishes a geometry_msgs/VelocityStamped (new in ROS 2) every tick."""

    def setup(self, ctx: SutContext) -> None:
        self.pub = ctx.publisher("/velocity", "geometry_msgs/msg/VelocityStamped")

    def step(self, now_ns: int) -> None:
        self.pub.publish(make("geometry_msgs/msg/VelocityStamped"))
