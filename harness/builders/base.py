"""What every graph builder shares: its inputs and the replace-on-rebuild rule."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from harness.graph import GraphStage
from harness.scenario import Scenario

__all__ = ["BuildContext", "GraphEdits", "fresh_graph", "gate_step", "gated_render_product"]

GraphEdits = tuple[list[tuple[str, str]], list[tuple[str, str]], list[tuple[str, Any]]]


@dataclass(frozen=True)
class BuildContext:
    """A builder's inputs: the resolved scenario and the built world (read for prim paths)."""

    scenario: Scenario
    world: Any
    srr_gt: bool = False


def fresh_graph(path: str) -> dict[str, str]:
    """Delete any graph already at ``path`` (builders are idempotent) and return the
    ``Controller.edit`` config that creates it anew."""
    stage = GraphStage.current()
    if stage.has_graph(path):
        stage.delete_graph(path)
    return {"graph_path": path, "evaluator_name": "execution"}


def gate_step(tick_hz: int, fps: float) -> int:
    """SimulationGate step for ``fps`` on a ``tick_hz`` tick: ``round(tick_hz / fps)``, >= 1
    (seed 001's ``step_size = int(60 / freq)``, rounded instead of truncated)."""
    return max(1, round(tick_hz / fps))


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

