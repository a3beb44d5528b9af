"""Action graphs with Isaac Sim OmniGraph semantics.

Builders written for Isaac Sim port by changing imports::

    import harness.graph as og
    from harness.graph import usdrt

    keys = og.Controller.Keys
    with og.GraphStage() as stage:
        og.Controller.edit({"graph_path": "/ActionGraph", "evaluator_name": "execution"}, {
            keys.CREATE_NODES: [("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"), ...],
            keys.CONNECT: [...],
            keys.SET_VALUES: [...],
        })
    stage.evaluate(ctx)  # one tick; ctx has .tick and .time_ns

Node types register with :func:`register`; importing this package registers the built-ins
(:mod:`harness.graph.nodes.core`), the simulation nodes (:mod:`~harness.graph.nodes.isaac_core`)
and the ROS bridge nodes (:mod:`~harness.graph.nodes.ros_bridge`).
"""

from __future__ import annotations

from harness.graph import usdrt
from harness.graph.attributes import Attr, coerce
from harness.graph.controller import Controller, GraphPipelineStage, Keys
from harness.graph.dump import stage_to_dict, stage_to_json, stage_to_mermaid
from harness.graph.engine import Attribute, Connection, Graph, GraphStage, Node
from harness.graph.node import Database, NodeType
from harness.graph.nodes import core as _core  # registers the built-in node types
from harness.graph.registry import Registry, all_types, canonical_name, lookup, register

# Simulation and ROS bridge nodes use the public API above, so they register last.
from harness.graph.nodes import camera as _camera  # noqa: E402
from harness.graph.nodes import isaac_core as _isaac_core  # noqa: E402
from harness.graph.nodes import prims as _prims  # noqa: E402
from harness.graph.nodes import ros_bridge as _ros_bridge  # noqa: E402
from harness.graph.nodes import ros_subscriber as _ros_subscriber  # noqa: E402
from harness.graph.nodes import sensors_range as _sensors_range  # noqa: E402

del _core, _isaac_core, _ros_bridge, _sensors_range, _prims, _ros_subscriber, _camera

__all__ = [
    "Attr",
    "Attribute",
    "Connection",
    "Controller",
    "Database",
    "Graph",
    "GraphPipelineStage",
    "GraphStage",
    "Keys",
    "Node",
    "NodeType",
    "Registry",
    "all_types",
    "canonical_name",
    "coerce",
    "lookup",
    "register",
    "stage_to_dict",
    "stage_to_json",
    "stage_to_mermaid",
    "usdrt",
]
