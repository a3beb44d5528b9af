"""Graphs, nodes, connections and the action-graph evaluator.

A :class:`GraphStage` holds graphs keyed by path (insertion ordered); ``with stage:`` makes it
the current stage the :class:`~harness.graph.controller.Controller` edits. ``Graph.evaluate``
runs one tick with OmniGraph action-graph semantics:

* every event node fires, in creation order: its compute runs and, when it returns True,
  execution is pushed from its execution outputs along their connections, depth-first in
  connection order;
* an action node reached by execution computes (pulling its data inputs) and, when compute
  returns True, pushes on; a node reached twice (fan-in) runs twice;
* data nodes compute lazily when one of their outputs is pulled, at most once per evaluation.

Execution cycles and data-pull cycles are refused when connected (and guarded at run time).
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterator, Mapping
from contextvars import ContextVar, Token
from dataclasses import dataclass
from types import MappingProxyType, TracebackType
from typing import Any, Literal

from harness.errors import GraphError, SrrError
from harness.graph.attributes import EXECUTION, Attr, coerce, compatible, is_valid_attr_name
from harness.graph.node import MISSING, Database, NodeType
from harness.graph.plan import (
    Evaluation,
    GraphPlan,
    NodePlan,
    build_graph_plan,
    build_plan,
)
from harness.graph.registry import DEFAULT_REGISTRY, Registry
from harness.graph.runner import Run, compile_flow, failure

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
    matches = difflib.get_close_matches(name, candidates, n=1, cutoff=0.6)
    return f"; did you mean {matches[0]!r}?" if matches else ""


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
        self.impl: NodeType = cls()
        self._static: dict[str, Attr] = {}
        for port, attrs in (("inputs", cls.inputs), ("outputs", cls.outputs)):
            for attr in attrs:
                self._static[f"{port}:{attr.name}"] = attr
        self._dynamic: dict[str, Attr] = {}
        self._values: dict[str, Any] = {}
        self._outputs: dict[str, Any] = {}
        self._initialized = False
        # Resolved bindings, built by Graph._build_plan and dropped by Graph._invalidate.
        self._plan: NodePlan | None = None
        # The port and ``db`` every compute of this node gets (one pair, reused every run).
        self._binding = _Binding(self)
        self._db = Database(self._binding)
        self._reset_outputs()

    def __repr__(self) -> str:
        return f"Node({self.path!r}, {self.type_name!r})"

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
        return self._outputs[full_name]

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

    def _drop_plan(self) -> None:
        """Forget the plan (an edit): the next access builds a new one."""
        if self._plan is not None:
            self._plan = None
            self._db.generalize()

    def _reset_outputs(self) -> None:
        self._outputs = {
            full: attr.default
            for full, attr in self.attributes().items()
            if full.startswith("outputs:")
        }


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


class _Binding:
    """Implements :class:`~harness.graph.node.NodePort` for one node.

    Each node has one, made with the node and reused by every run: :meth:`Graph._run` points
    it at the evaluation in progress and clears :attr:`fired` before each compute (a node
    never runs inside its own compute: execution and data cycles are refused).

    Reads and writes go through the node's :class:`~harness.graph.plan.NodePlan`, fetched
    from the node on every access (never kept here): a compute that edits the graph (e.g. adds
    an attribute to its own node) drops the plan, and the next access sees the new bindings.
    """

    __slots__ = ("_evaluation", "_node", "fired")

    def __init__(self, node: Node) -> None:
        self._node = node
        self._evaluation: Evaluation | None = None
        # Execution outputs written by this run, by full name (created on the first write).
        self.fired: dict[str, bool] | None = None

    @property
    def node_path(self) -> str:
        return self._node.path

    @property
    def graph_path(self) -> str:
        return self._node.graph_path

    def input_attr(self, name: str) -> Attr | None:
        return self._node.attr(f"inputs:{name}")

    def output_attr(self, name: str) -> Attr | None:
        return self._node.attr(f"outputs:{name}")

    def input_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self._node.input_attrs())

    def output_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self._node.output_attrs())

    def read_input(self, name: str) -> Any:
        """``db.inputs.<name>`` of a node whose ``db`` is not specialized yet (it builds the
        plan, which specializes it) or for a name it lacks: the value or its reader."""
        node = self._node
        plan = node._plan
        if plan is None:
            plan = node._graph._build_plan(node)
        entry = plan.readable.get(name)
        if entry is None:
            return MISSING
        full, default, reader = entry
        if reader is None:
            return node._values.get(full, default)
        return reader(self._evaluation)

    def read_output(self, name: str) -> Any:
        return self._node.output_value(f"outputs:{name}")

    def write_output(self, name: str, value: Any) -> bool:
        """``db.outputs.<name> = value`` before the ``db`` is specialized (the planned
        setter of :mod:`.plan` follows the same rules); False when there is no such output.

        A value already in the stored form of the output's type (a ``float`` for ``double``,
        a ``str`` for ``string``...) is stored as is, which is what its converter would do.
        """
        node = self._node
        plan = node._plan
        if plan is None:
            plan = node._graph._build_plan(node)
        slot = plan.outputs.get(name)
        if slot is None:
            return False
        if slot.is_execution:
            if self.fired is None:
                self.fired = {}
            self.fired[slot.full] = bool(value)
            return True
        if type(value) is slot.stored_as:
            node._outputs[slot.full] = value
            return True
        assert slot.convert is not None
        try:
            node._outputs[slot.full] = slot.convert(value)
        except ValueError as err:
            raise GraphError(f"{node.path}.{slot.full} (type {slot.type_name}): {err}") from err
        return True

    def is_connected(self, name: str) -> bool:
        node = self._node
        plan = node._plan
        if plan is None:
            plan = node._graph._build_plan(node)
        return name in plan.connected


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
        self._flow: GraphPlan | None = None  # the execution flow, see .plan
        self._tick: Run | None = None  # the flow compiled, see .runner

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
        node = self.node(name)
        del self._nodes[name]
        self._connections = [c for c in self._connections if name not in (c.src_node, c.dst_node)]
        node._drop_plan()
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
            node._outputs[full_name] = attr.default
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
            node._outputs[full_name] = coerced
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
        return self._input_value(node, full_name, None)

    # -- evaluation ----------------------------------------------------------------------

    def evaluate(self, ctx: Any) -> None:
        """Run one tick: fire every event node in creation order (see the module docstring).

        Execution follows the graph's plan (:class:`~harness.graph.plan.GraphPlan`), compiled
        into closures (:mod:`~harness.graph.runner`). Should a compute edit the graph, the rest
        of the tick resolves each step by name instead (:meth:`_fire`), so the edit is seen
        exactly as it would be without a plan."""
        tick = self._tick if self._flow is not None else self._build_flow()
        assert tick is not None
        tick(Evaluation(ctx))

    def reset(self) -> None:
        """Reset every node: ``NodeType.reset``, outputs back to defaults, re-initialize later."""
        for node in self._nodes.values():
            node.impl.reset()
            node._reset_outputs()
            node._initialized = False
        self._invalidate()

    def _fire(self, node: Node, evaluation: Evaluation) -> None:
        """Run ``node`` and push execution on, resolving targets by name (after an edit)."""
        stack = evaluation.exec_stack
        if node.name in stack:
            chain = " -> ".join([*stack, node.name])
            raise GraphError(f"{self.path}: execution cycle {chain}")
        stack.append(node.name)
        try:
            if self._run(node, evaluation):
                self._push(node, evaluation)
        finally:
            stack.pop()

    def _push(self, node: Node, evaluation: Evaluation) -> None:
        """Fire the targets of the execution outputs ``node``'s last compute let through."""
        fired = node._binding.fired
        selected = {name for name, on in fired.items() if on} if fired else None
        # The plan is fetched after compute, which may have edited the graph; its exec_out
        # is an immutable snapshot, like the copy of the connection list it replaces.
        plan = node._plan if node._plan is not None else self._build_plan(node)
        for src_attr, dst_name in plan.exec_out:
            if selected is not None and src_attr not in selected:
                continue
            target = self._nodes.get(dst_name)
            if target is not None:
                self._fire(target, evaluation)

    def _run(self, node: Node, evaluation: Evaluation) -> bool:
        binding = node._binding
        binding._evaluation = evaluation
        binding.fired = None
        db = node._db
        try:
            if not node._initialized:
                node.impl.initialize(db, evaluation.ctx)
                node._initialized = True
            return bool(node.impl.compute(db, evaluation.ctx))
        except SrrError:
            raise
        except Exception as err:
            raise failure(node, err) from err

    def _pull(self, node: Node, evaluation: Evaluation) -> None:
        if node.name in evaluation.done:
            return
        if node.name in evaluation.computing:
            raise GraphError(f"{self.path}: data cycle through {node.name}")
        evaluation.computing.add(node.name)
        try:
            self._run(node, evaluation)
        finally:
            evaluation.computing.discard(node.name)
        evaluation.done.add(node.name)

    def _input_value(self, node: Node, full_name: str, evaluation: Evaluation | None) -> Any:
        attr = node.require_attr(full_name)
        if attr.type == EXECUTION:
            return None
        plan = node._plan if node._plan is not None else self._build_plan(node)
        _, default, reader = plan.inputs[full_name.partition(":")[2]]
        if reader is None:
            return node._values.get(full_name, default)
        return reader(evaluation)

    # -- plans -----------------------------------------------------------------------------

    def _build_plan(self, node: Node) -> NodePlan:
        """The node's resolved bindings, built now when the last edit dropped them."""
        plan = build_plan(
            node, self._nodes, tuple(self._connections), self._pull, self._input_value
        )
        node._plan = plan
        node._db.specialize(plan.members, plan.set_output, plan.connected)
        return plan

    def _build_flow(self) -> Run:
        """The graph's execution flow and its compiled tick, built now when the last edit
        dropped them."""
        events = tuple(n for n in self._nodes.values() if n.kind == "event")
        flow = build_graph_plan(
            events, self._nodes, lambda n: n._plan if n._plan is not None else self._build_plan(n)
        )
        self._flow, self._tick = flow, compile_flow(self, flow)
        return self._tick

    # -- indexes and cycle checks --------------------------------------------------------

    def _invalidate(self) -> None:
        """Drop every cache derived from the graph's structure: the data-input index, the
        execution flow and each node's plan. Called by every edit (see :mod:`.plan`)."""
        self._data_in = None
        self._flow = self._tick = None
        for node in self._nodes.values():
            node._drop_plan()

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
        graph._stage = self
        self._graphs[graph.path] = graph

    def evaluate(self, ctx: Any) -> None:
        """Evaluate every graph once, in insertion order."""
        for graph in list(self._graphs.values()):
            graph.evaluate(ctx)

    def reset(self) -> None:
        """Reset every node of every graph (see :meth:`Graph.reset`)."""
        for graph in self._graphs.values():
            graph.reset()
