"""Evaluation plans: what ``Graph.evaluate`` resolves once and reuses every tick.

Per node (:class:`NodePlan`), the node's attribute bindings; per graph (:class:`GraphPlan`),
the execution flow: its event nodes, each a :class:`Step` holding the steps its execution
outputs lead to, so a tick walks object references instead of looking nodes up by name.

Resolving ``db.inputs.x`` from scratch means finding the declaration, looking the input up in
the graph's connection index, finding the source node and its declaration and dispatching the
coercion on the type name. None of that changes between graph edits, so :func:`build_plan`
does it once per node and :class:`NodePlan` keeps the answers:

* every input maps to ``(full name, default, reader)``: ``reader`` is None for an input that is
  unconnected (or an execution input) — its value is ``node._values.get(full, default)`` —
  and otherwise a closure that pulls the upstream node when needed and converts the value;
* every output maps to an :class:`OutputSlot` with its converter already chosen;
* the execution fan-out of the node, as ``(exec output, target node name)`` in connection order;
* what the node's ``db`` serves once planned (``NodePlan.members`` / ``set_output``, see
  :meth:`~harness.graph.node.Database.specialize`): an unconnected input's value as a class
  attribute of ``db.inputs`` (read with no call at all), a connected input as a property
  doing the reader's work in one call, and one ``db.outputs.__setattr__`` for the outputs.

A :class:`GraphPlan` is built from the node plans (:func:`build_graph_plan`) and follows the
same invariant: every edit drops it (and the closures :mod:`~harness.graph.runner` compiles
from it). An edit made *while* the graph evaluates (a compute that
adds an attribute) is seen by the engine, which then finishes that evaluation resolving each
step by name, exactly as without a graph plan.

Invariant: a plan describes the graph as it was when the plan was built. It holds source
*nodes* and declarations, never values: values are read from ``node._values`` /
``node._outputs`` at read time (the one exception: an unconnected input's value, which only
an edit can change), so running nodes never make a plan stale. Every graph edit that
could change a plan (create or delete a node, connect, disconnect, set a value, create an
attribute, reset) drops the plans of the whole graph (``Graph._invalidate``); the next read
builds a fresh one. Readers therefore behave exactly like resolving the binding on every read.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from harness.errors import GraphError
from harness.graph.attributes import EXECUTION, Attr, Converter, converter
from harness.graph.node import OutputSetter

if TYPE_CHECKING:
    from harness.graph.engine import Connection, Node

__all__ = [
    "Evaluation",
    "GraphPlan",
    "InputEntry",
    "InputReader",
    "NodePlan",
    "OutputSlot",
    "Step",
    "build_graph_plan",
    "build_plan",
]


class Evaluation:
    """Book-keeping of one ``Graph.evaluate`` call."""

    __slots__ = ("computing", "ctx", "done", "exec_stack")

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self.done: set[str] = set()
        self.computing: set[str] = set()
        self.exec_stack: list[str] = []


#: Reads one connected input; the evaluation is None outside ``Graph.evaluate`` (get_value).
InputReader = Callable[[Evaluation | None], Any]
#: ``(full name, default, reader or None)`` of one input, see the module docstring.
InputEntry = tuple[str, Any, InputReader | None]
#: ``Graph._pull``: compute a data node once per evaluation.
Pull = Callable[["Node", Evaluation], None]
#: ``Graph._input_value``: the value of an input (used by input-to-input connections).
ReadInput = Callable[["Node", str, Evaluation | None], Any]

# Values of exactly these Python types are already in the stored form of the attribute type:
# the matching converter would return them unchanged, so writes skip it.
_STORED_AS: dict[str, type] = {
    "double": float,
    "float": float,
    "bool": bool,
    "string": str,
    "token": str,
    "path": str,
}


@dataclass(frozen=True, slots=True)
class OutputSlot:
    """One output of a planned node: where it is stored and how a written value is converted."""

    full: str
    type_name: str
    is_execution: bool
    stored_as: type | None
    convert: Converter | None


@dataclass(frozen=True, slots=True)
class NodePlan:
    """The resolved bindings of one node (see the module docstring for the invariant).

    ``inputs`` holds every input by bare name; ``readable`` is the same minus names starting
    with ``__``, which ``db.inputs`` never serves (Python protocol probes such as
    ``__deepcopy__`` must get a plain AttributeError). ``connected`` holds the bare names of the
    inputs with any incoming connection (data or execution).

    ``members`` and ``set_output`` are what the node's ``db`` serves once planned
    (:meth:`~harness.graph.node.Database.specialize`): each unconnected input's value, each
    connected input as a property reading its source, and ``db.outputs.__setattr__``.
    """

    inputs: Mapping[str, InputEntry]
    readable: Mapping[str, InputEntry]
    outputs: Mapping[str, OutputSlot]
    connected: frozenset[str]
    exec_out: tuple[tuple[str, str], ...]
    members: Mapping[str, Any]
    set_output: OutputSetter


def build_plan(
    node: Node,
    nodes: Mapping[str, Node],
    connections: tuple[Connection, ...],
    pull: Pull,
    read_input: ReadInput,
) -> NodePlan:
    """Resolve every binding of ``node`` in a graph of ``nodes`` and ``connections``."""
    data_in = {
        c.dst_attr: c for c in connections if c.kind == "data" and c.dst_node == node.name
    }
    inputs: dict[str, InputEntry] = {}
    outputs: dict[str, OutputSlot] = {}
    members: dict[str, Any] = {}
    for full, attr in node.attributes().items():
        port, _, name = full.partition(":")
        if port == "outputs":
            outputs[name] = _output_slot(full, attr)
            continue
        reader: InputReader | None = None
        conn = data_in.get(full) if attr.type != EXECUTION else None
        if conn is not None:
            src = nodes[conn.src_node]
            if conn.src_attr.startswith("inputs:"):
                reader = _input_reader(node, full, attr, src, conn.src_attr, read_input)
                members[name] = _reader_property(node, reader)
            else:
                reader = _output_reader(node, full, attr, src, conn.src_attr, pull)
                members[name] = _output_property(node, full, attr, src, conn.src_attr, pull)
        else:
            members[name] = _constant(node._values.get(full, attr.default))
        inputs[name] = (full, attr.default, reader)
    readable = inputs
    if any(name.startswith("__") for name in inputs):
        readable = {k: v for k, v in inputs.items() if not k.startswith("__")}
    connected = frozenset(
        c.dst_attr.partition(":")[2] for c in connections if c.dst_node == node.name
    )
    exec_out = tuple(
        (c.src_attr, c.dst_node)
        for c in connections
        if c.kind == "exec" and c.src_node == node.name
    )
    return NodePlan(inputs, readable, outputs, connected, exec_out, members,
                    _output_setter(node, outputs))


def _output_slot(full: str, attr: Attr) -> OutputSlot:
    if attr.type == EXECUTION:
        return OutputSlot(full, attr.type, True, None, None)
    return OutputSlot(full, attr.type, False, _STORED_AS.get(attr.type), converter(attr.type))


def _does_not_fit(
    node: Node, full: str, attr: Attr, src: Node, src_full: str, err: ValueError
) -> GraphError:
    return GraphError(
        f"{node.path}.{full} (type {attr.type}): value from "
        f"{src.path}.{src_full} does not fit: {err}"
    )


def _output_reader(
    node: Node, full: str, attr: Attr, src: Node, src_full: str, pull: Pull
) -> InputReader:
    """Reader of an input fed by ``src``'s output ``src_full``.

    A data source computes first (once per evaluation: ``evaluation.done`` is checked here so a
    memoized source costs no call). Outputs are stored coerced, so a source of the same type
    gives its value as is; any other type is converted to the input's.
    """
    src_attr = src.attr(src_full)
    same_type = src_attr is not None and src_attr.type == attr.type
    convert = converter(attr.type)
    pulls = src.kind == "data"
    src_name = src.name

    def read(evaluation: Evaluation | None) -> Any:
        if pulls and evaluation is not None and src_name not in evaluation.done:
            pull(src, evaluation)
        raw = src._outputs[src_full]
        if same_type:
            return raw
        try:
            return convert(raw)
        except ValueError as err:
            raise _does_not_fit(node, full, attr, src, src_full, err) from err

    return read


def _input_reader(
    node: Node, full: str, attr: Attr, src: Node, src_full: str, read_input: ReadInput
) -> InputReader:
    """Reader of an input fed by ``src``'s input ``src_full`` (resolved, then converted)."""
    convert = converter(attr.type)

    def read(evaluation: Evaluation | None) -> Any:
        raw = read_input(src, src_full, evaluation)
        try:
            return convert(raw)
        except ValueError as err:
            raise _does_not_fit(node, full, attr, src, src_full, err) from err

    return read


def _constant(value: Any) -> Any:
    """``value`` as a class attribute of ``db.inputs``: as is, unless it would bind (a
    function or other descriptor), then a property giving it back unchanged."""
    if hasattr(type(value), "__get__"):
        return property(lambda _inputs: value)
    return value


def _reader_property(node: Node, reader: InputReader) -> property:
    binding = node._binding

    def get(_inputs: object) -> Any:
        return reader(binding._evaluation)

    return property(get)


def _output_property(
    node: Node, full: str, attr: Attr, src: Node, src_full: str, pull: Pull
) -> property:
    """``db.inputs.<name>`` of an input fed by ``src``'s output: :func:`_output_reader`
    reading the evaluation of the node's run in progress, in one call."""
    binding = node._binding
    src_attr = src.attr(src_full)
    convert = converter(attr.type)
    src_name = src.name
    if src.kind != "data" and src_attr is not None and src_attr.type == attr.type:

        def get_stored(_inputs: object) -> Any:
            return src._outputs[src_full]

        return property(get_stored)
    same_type = src_attr is not None and src_attr.type == attr.type
    pulls = src.kind == "data"

    def get(_inputs: object) -> Any:
        evaluation = binding._evaluation
        if pulls and evaluation is not None and src_name not in evaluation.done:
            pull(src, evaluation)
        raw = src._outputs[src_full]
        if same_type:
            return raw
        try:
            return convert(raw)
        except ValueError as err:
            raise _does_not_fit(node, full, attr, src, src_full, err) from err

    return property(get)


def _output_setter(node: Node, outputs: Mapping[str, OutputSlot]) -> OutputSetter:
    """``db.outputs.__setattr__`` for the planned ``outputs`` (see ``_Binding.write_output``,
    whose rules it follows in one call). It stores into the node's output dict of the time
    of planning: only ``Graph.reset`` replaces that dict, and it drops the plan."""
    binding = node._binding
    db = node._db
    store = node._outputs
    slots = {name: (slot.full, slot.stored_as, slot) for name, slot in outputs.items()}

    def set_output(_outputs: object, name: str, value: Any) -> None:
        entry = slots.get(name)
        if entry is None:
            raise db.unknown_output(name)
        full, stored_as, slot = entry
        if type(value) is stored_as:
            store[full] = value
        elif slot.is_execution:
            fired = binding.fired
            if fired is None:
                fired = binding.fired = {}
            fired[full] = bool(value)
        else:
            assert slot.convert is not None
            try:
                store[full] = slot.convert(value)
            except ValueError as err:
                raise GraphError(f"{node.path}.{full} (type {slot.type_name}): {err}") from err

    return set_output


@dataclass(eq=False, slots=True)
class Step:
    """One node in a graph's execution flow: the node and, in connection order, each execution
    output with the step it leads to. A node reached along several paths has one step."""

    node: Node
    children: tuple[tuple[str, Step], ...] = ()


@dataclass(frozen=True, slots=True)
class GraphPlan:
    """A graph's execution flow, resolved: its event nodes' steps, in creation order."""

    events: tuple[Step, ...]


def build_graph_plan(
    events: tuple[Node, ...], nodes: Mapping[str, Node], plan_of: Callable[[Node], NodePlan]
) -> GraphPlan:
    """The steps reachable from ``events`` along the execution connections of the node plans
    (``plan_of``). Execution cycles are refused when connecting, so the steps form a DAG."""
    steps: dict[str, Step] = {}

    def step(node: Node) -> Step:
        done = steps.get(node.name)
        if done is not None:
            return done
        made = steps[node.name] = Step(node)
        made.children = tuple(
            (src_attr, step(nodes[dst])) for src_attr, dst in plan_of(node).exec_out
            if dst in nodes
        )
        return made

    return GraphPlan(tuple(step(node) for node in events))
