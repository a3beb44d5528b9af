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
from harness.graph.registry import Registry, all_types, canonical_name, lookup, register

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

# The node modules import the public API above (``from harness.graph import register``), so
# they must load after it: register them at the very end, in one place.
from harness.graph.nodes import register_all as _register_all

_register_all()
del _register_all
