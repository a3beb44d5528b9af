"""What every graph builder shares: its inputs and the replace-on-rebuild rule."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from harness.geometry import wxyz_to_xyzw
from harness.graph import GraphStage
from harness.graph.nodes.ros_bridge import relative_pose
from harness.scenario import RobotSpec, Scenario, gate_step
from harness.scenario.prims import frame_of
from harness.wiring.plan import NodeOrigin  # the wiring plan reads the annotations

__all__ = ["BuildContext", "GraphEdits", "NodeOrigin", "fresh_graph", "gate_step",
           "gated_render_product", "sensor_frame_tf"]

GraphEdits = tuple[list[tuple[str, str]], list[tuple[str, str]], list[tuple[str, Any]]]


@dataclass(frozen=True)
class BuildContext:
    """A builder's inputs: the resolved scenario and the built world (read for prim paths).

    ``source`` is the scenario file, for errors. ``origins`` collects, per node path, the
    scenario field the node was built from (:meth:`annotate`); :mod:`harness.wiring` reads it
    to name fields in its errors."""

    scenario: Scenario
    world: Any
    srr_gt: bool = False
    source: str = "<scenario>"
    origins: dict[str, NodeOrigin] = dataclasses.field(default_factory=dict)
    # graph path → ``graphs[i]`` of every graph a scenario's own builder built (in build
    # order), filled by :func:`harness.builders.custom.build_custom`
    custom_graphs: dict[str, str] = dataclasses.field(default_factory=dict)

    def robot_field(self, robot: RobotSpec, sub: str = "") -> str:
        """Field path of a robot block, e.g. ``robots[1].odometry``."""
        base = f"robots[{self.scenario.robot_index(robot.name)}]"
        return f"{base}.{sub}" if sub else base

    def annotate(self, graph_path: str, node: str, field_path: str, **inputs: str) -> None:
        """Record that ``<graph_path>/<node>`` comes from ``field_path``; ``inputs`` maps node
        inputs to the sub-fields that set them (``topicName="odom_topic"``)."""
        self.origins[f"{graph_path}/{node}"] = NodeOrigin(field_path, inputs)


def fresh_graph(path: str) -> dict[str, str]:
    """Delete any graph already at ``path`` (builders are idempotent) and return the
    ``Controller.edit`` config that creates it anew."""
    stage = GraphStage.current()
    if stage.has_graph(path):
        stage.delete_graph(path)
    return {"graph_path": path, "evaluator_name": "execution"}


def gated_render_product(tick_hz: int, fps: float, prim: str,
                         resolution: tuple[int, int]) -> GraphEdits:
    """The shared head of a camera graph: OnPlaybackTick → IsaacSimulationGate →
    CreateRenderProduct (plus a ROS2Context), as (nodes, connections, values) to extend."""
    width, height = resolution
    nodes = [
        ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
        ("ROS2Context", "isaacsim.ros2.bridge.ROS2Context"),
        ("IsaacSimulationGate", "isaacsim.core.nodes.IsaacSimulationGate"),
        ("CreateRenderProduct", "isaacsim.core.nodes.IsaacCreateRenderProduct"),
    ]
    connect = [
        ("OnPlaybackTick.outputs:tick", "IsaacSimulationGate.inputs:execIn"),
        ("IsaacSimulationGate.outputs:execOut", "CreateRenderProduct.inputs:execIn"),
    ]
    values: list[tuple[str, Any]] = [
        ("IsaacSimulationGate.inputs:step", gate_step(tick_hz, fps)),
        ("CreateRenderProduct.inputs:cameraPrim", [prim]),
        ("CreateRenderProduct.inputs:width", width),
        ("CreateRenderProduct.inputs:height", height),
    ]
    return nodes, connect, values


def render_product_helper(name: str) -> list[tuple[str, str]]:
    """The connections of a helper node ``name`` fed by :func:`gated_render_product`'s head:
    its execution, the render product path and the ROS 2 context."""
    return [
        ("CreateRenderProduct.outputs:execOut", f"{name}.inputs:execIn"),
        ("CreateRenderProduct.outputs:renderProductPath", f"{name}.inputs:renderProductPath"),
        ("ROS2Context.outputs:context", f"{name}.inputs:context"),
    ]



def sensor_frame_tf(bc: BuildContext, robot: RobotSpec, kind: str, frame_id: str,
                    path: str, node: str = "PublishSensorTF",
                    read_time: bool = True) -> GraphEdits:
    """The static TF ``<link> → <frame_id>`` of ``robot.sensors.<kind>``, with the sensor's
    pose in its link, when the robot publishes its TF tree and ``frame_id`` is not the link's
    own frame (else nothing). A ``PublishRawTransformTree`` on the robot's static TF topic,
    driven by the graph's ``OnPlaybackTick`` and stamped by its ``ReadSimTime`` (added
    unless ``read_time`` is False: the graph has one)."""
    sensor_prim = bc.world.sensor_prim(robot.name, kind)
    link_prim = sensor_prim.rsplit("/", 1)[0]
    if not robot.tf_tree.enabled or frame_id == frame_of(link_prim):
        return [], [], []
    translation, rotation = relative_pose(bc.world, link_prim, sensor_prim)
    nodes = [("ReadSimTime", "isaacsim.core.nodes.IsaacReadSimulationTime")] if read_time else []
    nodes.append((node, "isaacsim.ros2.bridge.ROS2PublishRawTransformTree"))
    connect = [("OnPlaybackTick.outputs:tick", f"{node}.inputs:execIn"),
               ("ReadSimTime.outputs:simulationTime", f"{node}.inputs:timeStamp")]
    values: list[tuple[str, Any]] = [
        (f"{node}.inputs:topicName", robot.tf_tree.static_topic),
        (f"{node}.inputs:staticPublisher", True),
        (f"{node}.inputs:parentFrameId", robot.frame(frame_of(link_prim))),
        (f"{node}.inputs:childFrameId", robot.frame(frame_id)),
        (f"{node}.inputs:translation", [float(v) for v in translation]),
        (f"{node}.inputs:rotation", [float(v) for v in wxyz_to_xyzw(
            [float(c) for c in rotation])]),
    ]
    bc.annotate(path, node, bc.robot_field(robot), topicName="tf_tree.static_topic",
                parentFrameId=f"sensors.{kind}.link", childFrameId=f"sensors.{kind}.frame_id")
    return nodes, connect, values
