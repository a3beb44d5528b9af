"""``og.Controller``: OmniGraph's editing API over the current :class:`GraphStage`.

Every method is a classmethod working on ``GraphStage.current()``, so Isaac Sim builder code
ports by changing imports (``import harness.graph as og``). ``Controller.edit`` applies its
operations in a fixed order, whatever the order of the dict: ``DELETE_NODES``,
``CREATE_NODES``, ``CREATE_ATTRIBUTES``, ``CONNECT``, ``DISCONNECT``, ``SET_VALUES``. As in
OmniGraph, an edit is not transactional: when an operation fails, the ones before it stay
applied and a GraphError is raised.

Attribute references are ``"Node.inputs:x"`` (relative to the edited graph) or
``"/Graph/Node.inputs:x"`` (absolute); node references likewise ``"Node"`` or ``"/Graph/Node"``.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from typing import Any, ClassVar

from harness.graph.engine import (
    Attribute,
    Graph,
    GraphStage,
    Node,
    is_valid_graph_path,
    split_attribute_name,
)
from harness.graph.errors import GraphError

__all__ = ["Controller", "GraphPipelineStage", "Keys"]


class Keys:
    """The operation keys of :meth:`Controller.edit` (``og.Controller.Keys``)."""

    CREATE_NODES: ClassVar[str] = "create_nodes"
    CONNECT: ClassVar[str] = "connect"
    DISCONNECT: ClassVar[str] = "disconnect"
    SET_VALUES: ClassVar[str] = "set_values"
    CREATE_ATTRIBUTES: ClassVar[str] = "create_attributes"
    DELETE_NODES: ClassVar[str] = "delete_nodes"


_ORDER = (
    Keys.DELETE_NODES,
    Keys.CREATE_NODES,
    Keys.CREATE_ATTRIBUTES,
    Keys.CONNECT,
    Keys.DISCONNECT,
    Keys.SET_VALUES,
)


class GraphPipelineStage(enum.Enum):
    """OmniGraph's pipeline stages; accepted in a graph config and stored, never acted on."""

    GRAPH_PIPELINE_STAGE_SIMULATION = "simulation"
    GRAPH_PIPELINE_STAGE_PRERENDER = "prerender"
    GRAPH_PIPELINE_STAGE_POSTRENDER = "postrender"
    GRAPH_PIPELINE_STAGE_ONDEMAND = "ondemand"


_CONFIG_KEYS = frozenset(
    {"graph_path", "evaluator_name", "pipeline_stage", "backing_type", "fc_backing_type",
     "evaluation_mode"}
)

AttributeRef = str | Attribute


def _entries(value: Any, key: str, graph_path: str) -> list[Any]:
    """The entries of one edit operation: a list of tuples, or one bare tuple / string."""
    if isinstance(value, (str, Node)):
        return [value]
    if key == Keys.DELETE_NODES and isinstance(value, (list, tuple)):
        return list(value)
    if isinstance(value, tuple) and value and isinstance(value[0], (str, Attribute)):
        return [value]
    if isinstance(value, (list, tuple)):
        return list(value)
    raise GraphError(f"{graph_path}: {key} expects a list of entries, got {value!r}")


def _describe_target(graph_path_or_config: Any) -> str:
    if isinstance(graph_path_or_config, Graph):
        return graph_path_or_config.path
    if isinstance(graph_path_or_config, Mapping):
        return str(graph_path_or_config.get("graph_path", "<graph config>"))
    return str(graph_path_or_config)


def _pair(entry: Any, key: str, graph_path: str) -> tuple[Any, Any]:
    if not isinstance(entry, (tuple, list)) or len(entry) != 2:
        raise GraphError(f"{graph_path}: {key} entries are 2-tuples, got {entry!r}")
    return entry[0], entry[1]


class Controller:
    """OmniGraph's ``og.Controller``; use the class directly (``og.Controller.edit(...)``)."""

    Keys = Keys

    # -- resolution ----------------------------------------------------------------------

    @staticmethod
    def _stage() -> GraphStage:
        return GraphStage.current()

    @classmethod
    def _resolve_node(cls, ref: str | Node, graph: Graph | None = None) -> Node:
        """A node from ``"Name"`` (relative to ``graph``) or ``"/Graph/Name"``."""
        if isinstance(ref, Node):
            return ref
        if not isinstance(ref, str) or not ref:
            raise GraphError(f"node reference must be a path string, got {ref!r}")
        if ref.startswith("/"):
            graph_path, _, name = ref.rpartition("/")
            if not graph_path:
                raise GraphError(f"{ref!r} is not a node path (expected /Graph/Node)")
            target = cls._stage().graph(graph_path)
            if graph is not None and target is not graph:
                raise GraphError(
                    f"{graph.path}: {ref!r} belongs to graph {graph_path}; "
                    "connections and edits stay inside one graph"
                )
            return target.node(name)
        if graph is None:
            raise GraphError(f"node reference {ref!r} must be absolute (/Graph/Node)")
        return graph.node(ref)

    @classmethod
    def _resolve_attribute(cls, ref: AttributeRef, graph: Graph | None = None) -> Attribute:
        """An attribute from ``"Node.inputs:x"`` (relative) or ``"/Graph/Node.inputs:x"``."""
        if isinstance(ref, Attribute):
            if graph is not None and ref.node.graph is not graph:
                raise GraphError(
                    f"{graph.path}: {ref.path} belongs to graph {ref.node.graph_path}; "
                    "connections and edits stay inside one graph"
                )
            return ref
        if not isinstance(ref, str):
            raise GraphError(f"attribute reference must be a path string, got {ref!r}")
        node_ref, sep, attr_name = ref.rpartition(".")
        if not sep or not node_ref:
            raise GraphError(
                f"{ref!r} is not an attribute path (expected Node.inputs:x or /Graph/Node.inputs:x)"
            )
        node = cls._resolve_node(node_ref, graph)
        try:
            split_attribute_name(attr_name)
        except GraphError as err:
            raise GraphError(f"{node.path}: {err}") from None
        return Attribute(node, attr_name)

    @classmethod
    def _graph_for_edit(cls, graph_or_config: Any) -> Graph:
        stage = cls._stage()
        if isinstance(graph_or_config, Graph):
            return graph_or_config
        if isinstance(graph_or_config, str):
            path = graph_or_config
            return stage.graph(path) if stage.has_graph(path) else stage.create_graph(path)
        if isinstance(graph_or_config, Mapping):
            unknown = sorted(set(graph_or_config) - _CONFIG_KEYS)
            if unknown:
                raise GraphError(
                    f"graph config: unknown key(s) {', '.join(map(repr, unknown))} "
                    f"(known: {', '.join(sorted(_CONFIG_KEYS))})"
                )
            config_path = graph_or_config.get("graph_path")
            if not isinstance(config_path, str):
                raise GraphError(
                    f"graph config needs a 'graph_path' string, got {config_path!r}"
                )
            path = config_path
            evaluator = graph_or_config.get("evaluator_name", "execution")
            if evaluator != "execution":
                raise GraphError(
                    f"{path}: evaluator {evaluator!r} is not supported (only 'execution')"
                )
            if stage.has_graph(path):
                return stage.graph(path)
            return stage.create_graph(
                path,
                evaluator_name=evaluator,
                pipeline_stage=graph_or_config.get("pipeline_stage"),
            )
        raise GraphError(
            f"edit needs a graph path, a graph config dict or a Graph, got {graph_or_config!r}"
        )

    # -- edit ----------------------------------------------------------------------------

    @classmethod
    def edit(
        cls,
        graph_path_or_config: str | Mapping[str, Any] | Graph,
        edits: Mapping[str, Any] | None = None,
    ) -> tuple[Graph, list[Node], list[Any], dict[str, Node]]:
        """Create or extend a graph; returns ``(graph, nodes_created, prims, name_to_node)``.

        ``prims`` is always empty (the harness creates no USD prims).
        """
        edits = dict(edits or {})
        unknown = sorted(map(str, (k for k in edits if k not in _ORDER)))
        if unknown:
            raise GraphError(
                f"{_describe_target(graph_path_or_config)}: unsupported edit key(s) "
                f"{', '.join(map(repr, unknown))} (supported: {', '.join(_ORDER)})"
            )
        graph = cls._graph_for_edit(graph_path_or_config)
        created: list[Node] = []
        name_to_node: dict[str, Node] = {}
        for key in _ORDER:
            if key not in edits:
                continue
            for entry in _entries(edits[key], key, graph.path):
                if key == Keys.DELETE_NODES:
                    node = cls._resolve_node(entry, graph)
                    graph.delete_node(node.name)
                elif key == Keys.CREATE_NODES:
                    name, type_name = _pair(entry, key, graph.path)
                    node = graph.create_node(name, type_name)
                    created.append(node)
                    name_to_node[name] = node
                elif key == Keys.CREATE_ATTRIBUTES:
                    ref, type_name = _pair(entry, key, graph.path)
                    cls._create_attribute(ref, type_name, graph)
                elif key == Keys.CONNECT:
                    src, dst = _pair(entry, key, graph.path)
                    cls._connect(src, dst, graph)
                elif key == Keys.DISCONNECT:
                    src, dst = _pair(entry, key, graph.path)
                    cls._disconnect(src, dst, graph)
                else:
                    ref, value = _pair(entry, key, graph.path)
                    cls._resolve_attribute(ref, graph).set(value)
        return graph, created, [], name_to_node

    @classmethod
    def _create_attribute(cls, ref: Any, type_name: Any, graph: Graph | None) -> Attribute:
        if not isinstance(ref, str):
            raise GraphError(f"attribute reference must be a path string, got {ref!r}")
        node_ref, sep, attr_name = ref.rpartition(".")
        if not sep or not node_ref:
            raise GraphError(f"{ref!r} is not an attribute path (expected Node.inputs:x)")
        node = cls._resolve_node(node_ref, graph)
        if not isinstance(type_name, str):
            raise GraphError(f"{node.path}.{attr_name}: type must be a string, got {type_name!r}")
        node.graph.create_attribute(node.name, attr_name, type_name)
        return Attribute(node, attr_name)

    @classmethod
    def _connect(cls, src: AttributeRef, dst: AttributeRef, graph: Graph | None) -> None:
        source = cls._resolve_attribute(src, graph)
        target = cls._resolve_attribute(dst, graph if graph is not None else source.node.graph)
        source.node.graph.connect(source.node.name, source.name, target.node.name, target.name)

    @classmethod
    def _disconnect(cls, src: AttributeRef, dst: AttributeRef, graph: Graph | None) -> None:
        source = cls._resolve_attribute(src, graph)
        target = cls._resolve_attribute(dst, graph if graph is not None else source.node.graph)
        source.node.graph.disconnect(
            source.node.name, source.name, target.node.name, target.name
        )

    # -- single operations ---------------------------------------------------------------

    @classmethod
    def create_graph(cls, graph_path_or_config: str | Mapping[str, Any]) -> Graph:
        """Create (or return the existing) graph described by a path or config dict."""
        return cls._graph_for_edit(graph_path_or_config)

    @classmethod
    def create_node(cls, node_path: str, type_name: str) -> Node:
        """Create ``/Graph/Name`` of ``type_name``, creating the graph when it is missing."""
        if not isinstance(node_path, str):
            raise GraphError(f"node path must be a string, got {node_path!r}")
        graph_path, _, name = node_path.rpartition("/")
        if not is_valid_graph_path(graph_path):
            raise GraphError(f"{node_path!r} is not a node path (expected /Graph/Node)")
        graph = cls._graph_for_edit(graph_path)
        return graph.create_node(name, type_name)

    @classmethod
    def delete_node(cls, node_path: str | Node) -> None:
        """Delete a node (absolute path) and its connections."""
        node = cls._resolve_node(node_path)
        node.graph.delete_node(node.name)

    @classmethod
    def create_attribute(cls, attr_path: str, type_name: str) -> Attribute:
        """Add a dynamic attribute: ``create_attribute("/G/Script.inputs:x", "double")``."""
        return cls._create_attribute(attr_path, type_name, None)

    @classmethod
    def connect(cls, src: AttributeRef, dst: AttributeRef) -> None:
        """Connect two attributes given by absolute path (or :class:`Attribute`)."""
        cls._connect(src, dst, None)

    @classmethod
    def disconnect(cls, src: AttributeRef, dst: AttributeRef) -> None:
        """Remove the connection between two attributes."""
        cls._disconnect(src, dst, None)

    @classmethod
    def attribute(cls, path: AttributeRef, node: str | Node | None = None) -> Attribute:
        """An :class:`Attribute` from ``"/Graph/Node.inputs:x"``, or ``("inputs:x", node)``."""
        if node is not None:
            if not isinstance(path, str):
                raise GraphError(f"attribute name must be a string, got {path!r}")
            resolved = cls._resolve_node(node)
            return Attribute(resolved, path)
        return cls._resolve_attribute(path)

    @classmethod
    def get(cls, attribute: AttributeRef) -> Any:
        """The current value of an attribute (see ``Graph.get_value``)."""
        return cls._resolve_attribute(attribute).get()

    @classmethod
    def set(cls, attribute: AttributeRef, value: Any) -> None:
        """Set an attribute's value, coerced to its type."""
        cls._resolve_attribute(attribute).set(value)

    @classmethod
    def node(cls, path: str | Node) -> Node:
        """The node at an absolute path."""
        return cls._resolve_node(path)

    @classmethod
    def graph(cls, path: str | Graph) -> Graph:
        """The graph at ``path``."""
        if isinstance(path, Graph):
            return path
        return cls._stage().graph(path)

