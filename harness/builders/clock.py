"""Clock graph (/World/ClockPublisherGraph): simulation time on ``/clock``.

OnPlaybackTick ─▶ ROS2PublishClock ◀─ ReadSimulationTime (timeStamp)
"""

from __future__ import annotations

from harness.builders.base import BuildContext, fresh_graph
from harness.graph import Controller

__all__ = ["GRAPH_PATH", "build"]

GRAPH_PATH = "/World/ClockPublisherGraph"


def build(bc: BuildContext) -> str | None:
    spec = bc.scenario.clock
    if not spec.enabled:
        return None
    keys = Controller.Keys
    Controller.edit(fresh_graph(GRAPH_PATH), {
        keys.CREATE_NODES: [
            ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
            ("ROS2Context", "isaacsim.ros2.bridge.ROS2Context"),
            ("ReadSimTime", "isaacsim.core.nodes.IsaacReadSimulationTime"),
            ("PublishClock", "isaacsim.ros2.bridge.ROS2PublishClock"),
        ],
        keys.CONNECT: [
            ("OnPlaybackTick.outputs:tick", "PublishClock.inputs:execIn"),
            ("ROS2Context.outputs:context", "PublishClock.inputs:context"),
            ("ReadSimTime.outputs:simulationTime", "PublishClock.inputs:timeStamp"),
        ],
        keys.SET_VALUES: [
            ("PublishClock.inputs:topicName", spec.clock_topic),
        ],
    })
    bc.annotate(GRAPH_PATH, "PublishClock", "clock", topicName="clock_topic")
    return GRAPH_PATH
