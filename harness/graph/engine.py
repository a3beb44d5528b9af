"""Graphs, nodes, connections and the stage holding them: the graph as users edit it.

A :class:`GraphStage` holds graphs keyed by path (insertion ordered); ``with stage:`` makes it
the current stage the :class:`~harness.graph.controller.Controller` edits. Every edit checks
its arguments (execution cycles and data-pull cycles are refused when connected) and drops the
graph's compiled program; ``Graph.evaluate`` runs one tick with the program, compiled anew
after an edit (:mod:`harness.graph.program`, which also says when an edit made during a tick
takes effect).
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from contextvars import ContextVar, Token
from dataclasses import dataclass
from types import MappingProxyType, TracebackType
from typing import Any, Literal

from harness.graph.attributes import (
    EXECUTION,
    Attr,
    coerce,
    compatible,
    converter,
    is_valid_attr_name,
)
from harness.graph.errors import GraphError
from harness.graph.node import NodeType
from harness.graph.program import Evaluation, NodeRuntime, Program, compile_program
from harness.graph.registry import DEFAULT_REGISTRY, Registry
from harness.validation import close_match

__all__ = [
    "Attribute",
    "Connection",
    "Graph",
    "GraphStage",
    "Node",
    "is_valid_graph_path",
    "is_valid_node_name",
    "split_attribute_name",
]

_NODE_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_GRAPH_PATH_RE = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")
_PORTS = ("inputs", "outputs")


def is_valid_node_name(name: str) -> bool:
    """True for a USD-style prim name: letters, digits, underscores, not starting with a digit."""
    return isinstance(name, str) and bool(_NODE_NAME_RE.match(name))


def is_valid_graph_path(path: str) -> bool:
    """True for an absolute prim path such as ``/World/ClockGraph``."""
    return isinstance(path, str) and bool(_GRAPH_PATH_RE.match(path))


def split_attribute_name(full_name: str) -> tuple[str, str]:
    """``"inputs:x"`` -> ``("inputs", "x")``; anything else raises GraphError."""
    port, sep, name = full_name.partition(":")
    if not sep or port not in _PORTS or not is_valid_attr_name(name):
        raise GraphError(
            f"attribute name {full_name!r} must look like 'inputs:<name>' or 'outputs:<name>'"
        )
    return port, name


def _suggest(name: str, candidates: list[str]) -> str:
    match = close_match(name, candidates)
    return f"; did you mean {match!r}?" if match else ""


@dataclass(frozen=True)
class Connection:
    """A connection inside one graph, between ``src_node.src_attr`` and ``dst_node.dst_attr``.

    Node fields are node names; attribute fields carry their port prefix (``outputs:tick``).
    ``kind`` is ``"exec"`` for execution flow and ``"data"`` for value flow.
    """

    src_node: str
    src_attr: str
    dst_node: str
    dst_attr: str
    kind: Literal["exec", "data"]

    @property
    def src(self) -> str:
        """``"<node>.<attr>"`` of the source, relative to the graph."""
        return f"{self.src_node}.{self.src_attr}"

    @property
    def dst(self) -> str:
        """``"<node>.<attr>"`` of the destination, relative to the graph."""
        return f"{self.dst_node}.{self.dst_attr}"


class Node:
    """One node of a graph: a named instance of a registered node type.

    ``type_name`` is the type as written when the node was created (possibly an Isaac alias),
    ``canonical_type`` the registered canonical name, ``impl`` the node-type instance holding
    per-node state.
    """

    def __init__(
        self, graph: Graph, name: str, type_name: str, canonical_type: str, cls: type[NodeType]
    ) -> None:
        self._graph = graph
        self.name = name
        self.type_name = type_name
        self.canonical_type = canonical_type
        self._static: dict[str, Attr] = {}
        for port, attrs in (("inputs", cls.inputs), ("outputs", cls.outputs)):
            for attr in attrs:
                self._static[f"{port}:{attr.name}"] = attr
        self._dynamic: dict[str, Attr] = {}
        self._values: dict[str, Any] = {}
        #: The node's evaluation state (implementation, ``db``, output values), which the
        #: graph's programs run; it outlives every program.
        self.runtime = NodeRuntime(self, cls())

    def __repr__(self) -> str:
        return f"Node({self.path!r}, {self.type_name!r})"

    @property
    def impl(self) -> NodeType:
        """The node-type instance holding per-node state."""
        return self.runtime.impl

    @property
    def graph(self) -> Graph:
        """The graph holding this node."""
        return self._graph

    @property
    def graph_path(self) -> str:
        return self._graph.path

    @property
    def path(self) -> str:
        """``<graph_path>/<name>``."""
        return f"{self._graph.path}/{self.name}"

    @property
    def kind(self) -> str:
        """``"event"``, ``"action"`` or ``"data"``, from the node type."""
        return type(self.impl).kind

    @property
    def values(self) -> Mapping[str, Any]:
        """Input values set on this node (``SET_VALUES`` / ``Attribute.set``), by full name."""
        return MappingProxyType(dict(self._values))

    @property
    def connections(self) -> tuple[Connection, ...]:
        """Connections of the graph that start or end at this node, in creation order."""
        return tuple(
            c for c in self._graph.connections if self.name in (c.src_node, c.dst_node)
        )

    @property
    def dynamic_attributes(self) -> Mapping[str, Attr]:
        """Attributes added with ``CREATE_ATTRIBUTES``, by full name, in creation order."""
        return MappingProxyType(dict(self._dynamic))

    def attributes(self) -> dict[str, Attr]:
        """Every attribute by full name: static inputs, dynamic inputs, then outputs likewise."""
        merged = {**self._static, **self._dynamic}
        return {
            full: merged[full]
            for port in _PORTS
            for full in merged
            if full.startswith(port + ":")
        }

    def attr(self, full_name: str) -> Attr | None:
        """The declaration of ``inputs:x`` / ``outputs:y``, or None when the node has none."""
        return self._static.get(full_name) or self._dynamic.get(full_name)

    def input_attrs(self) -> tuple[Attr, ...]:
        return tuple(a for f, a in self.attributes().items() if f.startswith("inputs:"))

    def output_attrs(self) -> tuple[Attr, ...]:
        return tuple(a for f, a in self.attributes().items() if f.startswith("outputs:"))

    def get_attribute(self, full_name: str) -> Attribute:
        """A handle on one attribute of this node (``"inputs:x"``)."""
        return Attribute(self, full_name)

    def get_prim_path(self) -> str:
        """OmniGraph spelling of :attr:`path`."""
        return self.path

    def get_type_name(self) -> str:
        """OmniGraph spelling of :attr:`type_name`."""
        return self.type_name

    def output_value(self, full_name: str) -> Any:
        """The value last stored on output ``full_name``."""
        return self.runtime.outputs[full_name]

    def require_attr(self, full_name: str) -> Attr:
        """The declaration of ``full_name``; unknown names raise GraphError with a suggestion."""
        attr = self._static.get(full_name) or self._dynamic.get(full_name)
        if attr is not None:
            return attr
        split_attribute_name(full_name)
        attr = self.attr(full_name)
        if attr is None:
            known = list(self.attributes())
            raise GraphError(
                f"{self.path}: node type {self.canonical_type!r} has no attribute "
                f"{full_name!r}{_suggest(full_name, known)}"
            )
        return attr


class Attribute:
    """A handle on one attribute of one node, as ``Controller.attribute`` returns it."""

    def __init__(self, node: Node, name: str) -> None:
        node.require_attr(name)
        self.node = node
        self.name = name

    def __repr__(self) -> str:
        return f"Attribute({self.path!r})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Attribute) and (self.node, self.name) == (other.node, other.name)

    def __hash__(self) -> int:
        return hash((id(self.node), self.name))

    @property
    def path(self) -> str:
        """``<node_path>.<inputs|outputs>:<name>``."""
        return f"{self.node.path}.{self.name}"

    @property
    def attr(self) -> Attr:
        """The attribute's declaration."""
        return self.node.require_attr(self.name)

    @property
    def type(self) -> str:
        return self.attr.type

    def get(self) -> Any:
        """The current value (see :meth:`Graph.get_value`)."""
        return self.node.graph.get_value(self.node.name, self.name)

    def set(self, value: Any) -> None:
        """Set the value, coerced to the attribute's type (see :meth:`Graph.set_value`)."""
        self.node.graph.set_value(self.node.name, self.name, value)

    def get_path(self) -> str:
        """OmniGraph spelling of :attr:`path`."""
        return self.path

    def get_name(self) -> str:
        """OmniGraph spelling of :attr:`name`."""
        return self.name


class Graph:
    """An action graph: nodes in creation order and the connections between them."""

    def __init__(
        self,
        stage: GraphStage,
        path: str,
        *,
        evaluator_name: str = "execution",
        pipeline_stage: Any = None,
    ) -> None:
        self._stage = stage
        self.path = path
        self.evaluator_name = evaluator_name
        self.pipeline_stage = pipeline_stage
        self._nodes: dict[str, Node] = {}
        self._connections: list[Connection] = []
        self._data_in: dict[tuple[str, str], Connection] | None = None
        self._program: Program | None = None  # dropped by every edit

    def __repr__(self) -> str:
        return f"Graph({self.path!r}, nodes={len(self._nodes)})"

    # -- queries -------------------------------------------------------------------------

    @property
    def stage(self) -> GraphStage:
        return self._stage

    @property
    def nodes(self) -> tuple[Node, ...]:
        """Nodes in creation order."""
        return tuple(self._nodes.values())

    @property
    def connections(self) -> tuple[Connection, ...]:
        """Connections in creation order."""
        return tuple(self._connections)

    def get_path_to_graph(self) -> str:
        """OmniGraph spelling of :attr:`path`."""
        return self.path

    def get_nodes(self) -> tuple[Node, ...]:
        """OmniGraph spelling of :attr:`nodes`."""
        return self.nodes

    def has_node(self, name: str) -> bool:
        return name in self._nodes

    def node(self, name: str) -> Node:
        """The node called ``name``; unknown names raise GraphError with a suggestion."""
        node = self._nodes.get(name)
        if node is None:
            raise GraphError(
                f"{self.path}: no node {name!r}{_suggest(name, list(self._nodes))}"
            )
        return node

    # -- edits ---------------------------------------------------------------------------

    def create_node(self, name: str, type_name: str) -> Node:
        """Create a node of ``type_name`` (canonical or alias) called ``name``."""
        if not is_valid_node_name(name):
            raise GraphError(
                f"{self.path}: node name {name!r} must be letters, digits and underscores, "
                "not starting with a digit"
            )
        if name in self._nodes:
            raise GraphError(f"{self.path}: node {name!r} already exists")
        if self._stage.has_graph(f"{self.path}/{name}"):
            raise GraphError(f"{self.path}/{name}: a graph already lives at that path")
        registry = self._stage.registry
        try:
            cls = registry.lookup(type_name)
            canonical = registry.canonical_name(type_name)
        except GraphError as err:
            raise GraphError(f"{self.path}/{name}: {err}") from None
        node = Node(self, name, type_name, canonical, cls)
        self._nodes[name] = node
        self._invalidate()
        return node

    def delete_node(self, name: str) -> None:
        """Delete a node and every connection touching it."""
        self.node(name)
        del self._nodes[name]
        self._connections = [c for c in self._connections if name not in (c.src_node, c.dst_node)]
        self._invalidate()

    def create_attribute(self, node_name: str, full_name: str, type_name: str) -> Attr:
        """Add a dynamic attribute (``"inputs:x"``, ``"double[3]"``) to a node."""
        node = self.node(node_name)
        where = f"{node.path}.{full_name}"
        try:
            port, name = split_attribute_name(full_name)
        except GraphError as err:
            raise GraphError(f"{node.path}: {err}") from None
        if node.attr(full_name) is not None:
            raise GraphError(f"{where}: attribute already exists")
        try:
            attr = Attr(name, type_name)
        except GraphError as err:
            raise GraphError(f"{where}: {err}") from None
        if attr.type == EXECUTION and (
            node.kind == "data" or (node.kind == "event" and port == "inputs")
        ):
            raise GraphError(f"{where}: a {node.kind} node cannot have this execution attribute")
        node._dynamic[full_name] = attr
        if port == "outputs":
            node.runtime.outputs[full_name] = attr.default
        self._invalidate()
        return attr

    def connect(self, src_node: str, src_attr: str, dst_node: str, dst_attr: str) -> Connection:
        """Connect ``src_node.src_attr`` to ``dst_node.dst_attr``; mistakes raise GraphError."""
        src, dst = self.node(src_node), self.node(dst_node)
        src_decl, dst_decl = src.require_attr(src_attr), dst.require_attr(dst_attr)
        where = f"{self.path}: cannot connect {src_node}.{src_attr} -> {dst_node}.{dst_attr}"
        if not dst_attr.startswith("inputs:"):
            raise GraphError(f"{where}: the destination must be an input")
        src_exec, dst_exec = src_decl.type == EXECUTION, dst_decl.type == EXECUTION
        if src_exec and not src_attr.startswith("outputs:"):
            raise GraphError(f"{where}: an execution input cannot be a source")
        if src_exec != dst_exec:
            raise GraphError(
                f"{where}: execution ports connect only to execution ports "
                f"({src_decl.type} -> {dst_decl.type})"
            )
        if not compatible(src_decl.type, dst_decl.type):
            raise GraphError(f"{where}: type {src_decl.type} does not fit {dst_decl.type}")
        conn = Connection(src_node, src_attr, dst_node, dst_attr, "exec" if src_exec else "data")
        if conn in self._connections:
            raise GraphError(f"{where}: already connected")
        if conn.kind == "data":
            existing = self._index_data_in().get((dst_node, dst_attr))
            if existing is not None:
                raise GraphError(
                    f"{where}: {dst_node}.{dst_attr} is already fed by {existing.src} "
                    "(a data input takes one source)"
                )
            if self._pulls(conn) and self._pull_reaches(dst_node, src_node):
                raise GraphError(f"{where}: it would close a data cycle")
        elif self._exec_reaches(dst_node, src_node):
            raise GraphError(f"{where}: it would close an execution cycle")
        self._connections.append(conn)
        self._invalidate()
        return conn

    def disconnect(self, src_node: str, src_attr: str, dst_node: str, dst_attr: str) -> None:
        """Remove one connection; a connection that does not exist raises GraphError."""
        self.node(src_node).require_attr(src_attr)
        self.node(dst_node).require_attr(dst_attr)
        for i, conn in enumerate(self._connections):
            if (conn.src_node, conn.src_attr, conn.dst_node, conn.dst_attr) == (
                src_node, src_attr, dst_node, dst_attr
            ):
                del self._connections[i]
                self._invalidate()
                return
        raise GraphError(
            f"{self.path}: {src_node}.{src_attr} is not connected to {dst_node}.{dst_attr}"
        )

    def set_value(self, node_name: str, full_name: str, value: Any) -> None:
        """Set an input (or seed an output) value, coerced to the attribute's type.

        Execution attributes and connected inputs cannot be set.
        """
        node = self.node(node_name)
        attr = node.require_attr(full_name)
        where = f"{node.path}.{full_name}"
        if attr.type == EXECUTION:
            raise GraphError(f"{where}: execution attributes carry no value")
        conn = self._index_data_in().get((node_name, full_name))
        if conn is not None:
            raise GraphError(f"{where}: is connected to {conn.src}; its value comes from there")
        try:
            coerced = coerce(attr.type, value)
        except ValueError as err:
            raise GraphError(f"{where} (type {attr.type}): cannot set {value!r}: {err}") from err
        if full_name.startswith("inputs:"):
            node._values[full_name] = coerced
        else:
            node.runtime.outputs[full_name] = coerced
        self._invalidate()

    def get_value(self, node_name: str, full_name: str) -> Any:
        """The value of an attribute now, without computing anything.

        An output gives its stored value; an input gives its upstream's stored value when
        connected, else the value set on it, else its default. Execution attributes give None.
        """
        node = self.node(node_name)
        node.require_attr(full_name)
        if full_name.startswith("outputs:"):
            return node.output_value(full_name)
        return self._input_value(node, full_name)

    def _input_value(self, node: Node, full_name: str) -> Any:
        """An input's value now: its source's stored value (converted as a read in a tick
        converts it) when connected, else the value set on it, else its default."""
        attr = node.require_attr(full_name)
        if attr.type == EXECUTION:
            return None
        conn = self._index_data_in().get((node.name, full_name))
        if conn is None:
            return node._values.get(full_name, attr.default)
        src = self._nodes[conn.src_node]
        if conn.src_attr.startswith("outputs:"):
            raw = src.output_value(conn.src_attr)
            src_decl = src.attr(conn.src_attr)
            if src_decl is not None and src_decl.type == attr.type:
                return raw
        else:
            raw = self._input_value(src, conn.src_attr)
        try:
            return converter(attr.type)(raw)
        except ValueError as err:
            raise GraphError(
                f"{node.path}.{full_name} (type {attr.type}): value from "
                f"{src.path}.{conn.src_attr} does not fit: {err}"
            ) from err

    # -- evaluation ----------------------------------------------------------------------

    def program(self) -> Program:
        """The graph compiled as it is now (:mod:`~harness.graph.program`): compiled at the
        first call after an edit, then the same object until the next edit."""
        program = self._program
        if program is None:
            program = self._program = compile_program(self)
        return program

    def evaluate(self, ctx: Any) -> None:
        """Run one tick with the graph's program (see :mod:`~harness.graph.program`; an edit
        made during the tick takes effect at the next one)."""
        self.program().run(ctx)

    def reset(self) -> None:
        """Reset every node: ``NodeType.reset``, outputs back to defaults, re-initialize later."""
        for node in self._nodes.values():
            runtime = node.runtime
            runtime.impl.reset()
            runtime.reset_outputs()
            runtime.initialized = False
        self._invalidate()

    # -- indexes and cycle checks --------------------------------------------------------

    def _invalidate(self) -> None:
        """Drop every cache derived from the graph's structure: the data-input index and the
        program. Called by every edit; a tick in progress finishes with the program it has."""
        self._data_in = None
        self._program = None
        self._stage._forget_programs()

    def _index_data_in(self) -> dict[tuple[str, str], Connection]:
        if self._data_in is None:
            self._data_in = {
                (c.dst_node, c.dst_attr): c for c in self._connections if c.kind == "data"
            }
        return self._data_in

    def _pulls(self, conn: Connection) -> bool:
        """True when reading the destination makes the source compute or resolve (a pull)."""
        return conn.src_attr.startswith("inputs:") or self._nodes[conn.src_node].kind == "data"

    def _reaches(self, start: str, goal: str, edges: Iterator[tuple[str, str]]) -> bool:
        forward: dict[str, list[str]] = {}
        for a, b in edges:
            forward.setdefault(a, []).append(b)
        seen: set[str] = set()
        todo = [start]
        while todo:
            current = todo.pop()
            if current == goal:
                return True
            if current not in seen:
                seen.add(current)
                todo.extend(forward.get(current, ()))
        return False

    def _exec_reaches(self, start: str, goal: str) -> bool:
        edges = ((c.src_node, c.dst_node) for c in self._connections if c.kind == "exec")
        return self._reaches(start, goal, edges)

    def _pull_reaches(self, start: str, goal: str) -> bool:
        edges = (
            (c.src_node, c.dst_node)
            for c in self._connections
            if c.kind == "data" and self._pulls(c)
        )
        return self._reaches(start, goal, edges)


_CURRENT: ContextVar[GraphStage | None] = ContextVar("harness_graph_current_stage", default=None)


class GraphStage:
    """The set of graphs of one simulated world, keyed by path in insertion order.

    ``with stage:`` makes it the current stage (nestable; the previous one comes back on exit).
    Node types resolve through ``registry`` (the shared default registry when not given).
    """

    def __init__(self, registry: Registry | None = None) -> None:
        self._registry = registry if registry is not None else DEFAULT_REGISTRY
        self._graphs: dict[str, Graph] = {}
        self._tokens: list[Token[GraphStage | None]] = []
        # Every graph's program, in order, for the next tick; dropped by any edit.
        self._programs: tuple[Program, ...] | None = None

    def __repr__(self) -> str:
        return f"GraphStage(graphs={list(self._graphs)})"

    @classmethod
    def current(cls) -> GraphStage:
        """The stage of the innermost active ``with stage:``; none active raises GraphError."""
        stage = _CURRENT.get()
        if stage is None:
            raise GraphError("no graph stage is active")
        return stage

    def __enter__(self) -> GraphStage:
        self._tokens.append(_CURRENT.set(self))
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        _CURRENT.reset(self._tokens.pop())

    @property
    def registry(self) -> Registry:
        """The registry node types are looked up in."""
        return self._registry

    def create_graph(
        self, path: str, *, evaluator_name: str = "execution", pipeline_stage: Any = None
    ) -> Graph:
        """Create an empty graph at ``path``; an existing path raises GraphError."""
        if not is_valid_graph_path(path):
            raise GraphError(f"graph path {path!r} must be an absolute prim path like /World/G")
        if evaluator_name != "execution":
            raise GraphError(
                f"{path}: evaluator {evaluator_name!r} is not supported (only 'execution')"
            )
        if path in self._graphs:
            raise GraphError(f"{path}: graph already exists")
        parent, _, name = path.rpartition("/")
        owner = self._graphs.get(parent)
        if owner is not None and owner.has_node(name):
            raise GraphError(f"{path}: a node already lives at that path")
        graph = Graph(self, path, evaluator_name=evaluator_name, pipeline_stage=pipeline_stage)
        self._graphs[path] = graph
        self._programs = None
        return graph

    def graph(self, path: str) -> Graph:
        """The graph at ``path``; unknown paths raise GraphError with a suggestion."""
        graph = self._graphs.get(path)
        if graph is None:
            raise GraphError(f"no graph {path!r}{_suggest(path, list(self._graphs))}")
        return graph

    def graphs(self) -> tuple[Graph, ...]:
        """Graphs in insertion order."""
        return tuple(self._graphs.values())

    def has_graph(self, path: str) -> bool:
        return path in self._graphs

    def delete_graph(self, path: str) -> None:
        """Remove the graph at ``path``; unknown paths raise GraphError."""
        self.graph(path)
        del self._graphs[path]
        self._programs = None

    def adopt(self, graph: Graph) -> None:
        """Move ``graph``, built on another stage with this stage's registry, onto this one
        (at the end); its path must be free here. The other stage no longer has it."""
        if graph.stage is self:
            raise GraphError(f"{graph.path}: graph is already on this stage")
        if graph.stage.registry is not self._registry:
            raise GraphError(f"{graph.path}: built with another node-type registry")
        if graph.path in self._graphs:
            raise GraphError(f"{graph.path}: graph already exists")
        other = graph.stage
        if other._graphs.get(graph.path) is graph:
            del other._graphs[graph.path]
        other._programs = None
        graph._stage = self
        self._graphs[graph.path] = graph
        self._programs = None

    def evaluate(self, ctx: Any) -> None:
        """Evaluate every graph once, in insertion order. Each graph's program is taken
        before any graph runs, so an edit made during the tick, of any graph of the stage,
        takes effect at the next tick (see :mod:`~harness.graph.program`)."""
        programs = self._programs
        if programs is None:
            programs = self._programs = tuple(graph.program() for graph in self._graphs.values())
        evaluation = Evaluation(ctx)  # one for the stage's tick (see Program.run_in)
        for program in programs:
            program.run_in(evaluation)

    def _forget_programs(self) -> None:
        """A graph of the stage was edited: the next tick takes the programs anew."""
        self._programs = None

    def reset(self) -> None:
        """Reset every node of every graph (see :meth:`Graph.reset`)."""
        for graph in self._graphs.values():
            graph.reset()
