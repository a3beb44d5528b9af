"""The wiring plan of a built scenario: every topic each graph node and system under test will
publish or subscribe, and every TF edge the graphs will publish, each with the scenario field
that set it.

Graph nodes declare their endpoints from their input values (:meth:`NodeType.endpoints`), so
the plan covers any graph on the stage, built-in or not; the builders' annotations
(:class:`NodeOrigin`, made by :meth:`harness.builders.base.BuildContext.annotate`) turn a
node input into a scenario field path (``robots[1].odometry.odom_topic``); a node without
one is named by its attribute path.
Systems under test are planned from what they advertised and subscribed in ``setup``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from harness.bus import TopicNameError
from harness.bus.endpoints import TfEdge
from harness.errors import ScenarioError
from harness.graph import GraphStage, Node
from harness.graph.errors import GraphError
from harness.scenario import Scenario
from harness.sut.base import SutContext

__all__ = ["NodeOrigin", "Plan", "PlannedEdge", "PlannedTopic", "plan_wiring"]


@dataclass(frozen=True)
class NodeOrigin:
    """Which scenario field a node was built from (``robots[1].odometry``) and, per input,
    which sub-field set it (``topicName`` → ``odom_topic``), so wiring errors name fields.
    ``node``: the path of a node a ``graphs:`` entry built (``field`` is ``graphs[i]``),
    whose inputs are named by their attribute path after the entry
    (``graphs[0]: /World/TeleopGraph/Pub.inputs:topicName``)."""

    field: str
    inputs: Mapping[str, str] = dataclasses.field(default_factory=dict)
    node: str = ""

    def field_for(self, input_name: str) -> str:
        if self.node:
            return f"{self.field}: {self.node}.inputs:{input_name}"
        sub = self.inputs.get(input_name)
        return f"{self.field}.{sub}" if sub else self.field


@dataclass(frozen=True)
class PlannedTopic:
    """One endpoint: ``field`` is the scenario field (or node attribute) that set its topic,
    ``owner`` the node path or ``systems_under_test[i] (name)``."""

    kind: Literal["pub", "sub"]
    topic: str
    msgtype: str
    required: bool
    field: str
    owner: str
    graph: bool

    @property
    def verb(self) -> str:
        return "publishes" if self.kind == "pub" else "subscribes to"


@dataclass(frozen=True)
class PlannedEdge:
    edge: TfEdge
    parent_field: str
    child_field: str
    owner: str


@dataclass(frozen=True)
class Plan:
    topics: tuple[PlannedTopic, ...]
    edges: tuple[PlannedEdge, ...]


def _node_field(node: Node, origin: NodeOrigin | None, input_name: str) -> str:
    return origin.field_for(input_name) if origin else f"{node.path}.inputs:{input_name}"


def _fail(sc: Scenario, source: str, field: str, message: str) -> ScenarioError:
    return ScenarioError(sc.file_for(field, source), field, message)


def _check_prims(node: Node, world: Any) -> None:
    """Every prim path set on an unconnected ``target`` input of ``node`` is a prim of
    ``world``: what the node would refuse at the first tick (its initialize or compute)."""
    fed = {c.dst_attr for c in node.connections if c.dst_node == node.name}
    for attr in node.input_attrs():
        full = f"inputs:{attr.name}"
        if attr.type != "target" or full in fed:
            continue
        for prim in node.graph.get_value(node.name, full) or ():
            if prim and not world.has_prim(str(prim)):
                raise GraphError(f"{node.path}.{full}: prim {str(prim)!r} does not exist")


def _graph_items(stage: GraphStage, origins: Mapping[str, NodeOrigin], sc: Scenario,
                 source: str, world: Any) -> tuple[list[PlannedTopic], list[PlannedEdge]]:
    topics: list[PlannedTopic] = []
    edges: list[PlannedEdge] = []
    for graph in stage.graphs():
        for node in graph.nodes:
            origin = origins.get(node.path)

            def value(name: str, node: Node = node) -> Any:
                return node.graph.get_value(node.name, f"inputs:{name}")

            try:
                if world is not None:
                    _check_prims(node, world)
                declared = [*node.impl.endpoints(value),
                            *(node.impl.world_edges(value, world) if world is not None else ())]
            except TopicNameError as err:
                raise _fail(sc, source, _node_field(node, origin, "topicName"),
                            str(err)) from err
            except GraphError as err:
                raise _fail(sc, source, origin.field if origin else node.path,
                            str(err)) from err
            for item in declared:
                if isinstance(item, TfEdge):
                    edges.append(PlannedEdge(item, _node_field(node, origin, item.parent_input),
                                             _node_field(node, origin, item.child_input),
                                             node.path))
                    continue
                field = _node_field(node, origin, item.input)
                try:
                    topic = item.topic
                except TopicNameError as err:
                    raise _fail(sc, source, field, str(err)) from err
                topics.append(PlannedTopic(item.kind, topic, item.msgtype, item.required,
                                           field, node.path, graph=True))
    return topics, edges


def _sut_items(suts: Sequence[tuple[str, Any, SutContext]], sc: Scenario) -> list[PlannedTopic]:
    out: list[PlannedTopic] = []
    for name, _, ctx in suts:
        field = ctx.field.rsplit(": ", 1)[-1]  # "systems_under_test[i]", after the file
        for ep in ctx.endpoints:
            out.append(PlannedTopic(ep.kind, ep.topic, ep.msgtype, ep.required, field,
                                    f"{field} ({name})", graph=False))
    return out


def plan_wiring(stage: GraphStage, origins: Mapping[str, NodeOrigin],
                suts: Sequence[tuple[str, Any, SutContext]], sc: Scenario,
                source: str = "<scenario>", world: Any = None) -> Plan:
    """The plan of a built simulation (graphs on ``stage``, systems under test already set
    up; with its ``world``, also the TF edges only the world can tell, such as an
    articulation root's links). A topic name that does not resolve is a
    :class:`ScenarioError` naming its field."""
    topics, edges = _graph_items(stage, origins, sc, source, world)
    topics += _sut_items(suts, sc)
    return Plan(tuple(topics), tuple(edges))
