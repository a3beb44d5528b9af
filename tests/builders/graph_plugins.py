"""``graphs:`` builders for the tests of :mod:`harness.builders.custom`."""

from __future__ import annotations

from typing import Any

from harness.isaac import og

SEEN: list[Any] = []  # contexts the builders were given, newest last

NOT_A_FUNCTION = 42


def clock(ctx: Any) -> None:
    """A clock graph at the entry's path, on ``params.topic``."""
    SEEN.append(ctx)
    og.Controller.edit(ctx.graph_config, {
        og.Controller.Keys.CREATE_NODES: [
            ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
            ("PublishClock", "isaacsim.ros2.bridge.ROS2PublishClock"),
        ],
        og.Controller.Keys.CONNECT: [("OnPlaybackTick.outputs:tick",
                                      "PublishClock.inputs:execIn")],
        og.Controller.Keys.SET_VALUES: [("PublishClock.inputs:topicName",
                                         ctx.params.get("topic", "clock2"))],
    })


def takes_the_clock_path(ctx: Any) -> None:
    og.Controller.create_node("/World/ClockPublisherGraph/Tick",
                              "omni.graph.action.OnPlaybackTick")


def raises(ctx: Any) -> None:
    raise ValueError("no robot arm in this scene")


def unknown_node(ctx: Any) -> None:
    og.Controller.create_node(ctx.graph_path + "/Pub", "isaacsim.ros2.bridge.ROS2PublishClok")


def missing_prim(ctx: Any) -> None:
    """A node of type ``params.type`` whose ``params.input`` names a prim the world lacks
    (the camera graph a user builds with a typo in its camera's path)."""
    node_type, name = ctx.params["type"], ctx.params["input"]
    og.Controller.edit(ctx.graph_config, {
        og.Controller.Keys.CREATE_NODES: [
            ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"), ("Node", node_type)],
        og.Controller.Keys.CONNECT: [("OnPlaybackTick.outputs:tick", "Node.inputs:execIn")],
        og.Controller.Keys.SET_VALUES: [(f"Node.inputs:{name}",
                                         [ctx.robot.prim + "/no_such_camera"])],
    })
