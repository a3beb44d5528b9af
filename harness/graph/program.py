"""A graph compiled into one program: the only way a graph evaluates.

:func:`compile_program` resolves everything about a graph that only an edit can change, once,
and returns a :class:`Program` whose :meth:`~Program.run` is one tick:

* every event node fires, in creation order: its compute runs and, when it returns true,
  execution goes on along its execution outputs, depth-first in connection order (only along
  those it selected, when it set any with ``db.outputs.execOut = True``); a node reached
  twice (fan-in) runs twice;
* a data node computes when one of its outputs is pulled, at most once per run;
* a compute's exceptions other than :class:`~harness.errors.SrrError` become a GraphError
  naming the node.

Each node is one closure holding its implementation, its ``db`` and the closures of the nodes
its execution outputs lead to, so a tick is one call per node run and no look-up by name.
Each node's ``db`` is specialized for the program (:meth:`~harness.graph.node.Database.
specialize`): an unconnected input's value is a class attribute of ``db.inputs``, a connected
input a property reading its source (pulling a data source first), ``db.outputs.__setattr__``
one function resolved for the node's outputs.

Edits made while a graph evaluates. OmniGraph keeps the graph users edit (the authoring
graph) apart from the graph it executes: an edit invalidates the execution graph's topology,
and the execution graph is rebuilt lazily, before the next execution, never in the middle of
one (Omniverse Execution Framework, "Graph Invalidation"). This module follows that rule:

* an edit (``og.Controller.edit``, ``Graph.connect``, ``Attribute.set``... from anywhere,
  a node's compute included) changes the graph at once, so queries (``Graph.get_value``,
  ``Node.attr``, the node list) see it at once, and drops the graph's program;
* a tick in progress runs to its end with the programs it started with: a node deleted during
  the tick still runs if the tick reaches it, a connection made during the tick is first
  followed, and a value set during the tick first read, at the next tick;
* the next tick compiles a new program for each edited graph before any graph of the stage
  runs (``GraphStage.evaluate``), so an edit of another graph of the stage waits for the next
  tick too, whichever graph evaluates first.

Runtime state (output values, whether ``initialize`` ran) lives in each node's
:class:`NodeRuntime`, which survives recompiling; a program holds declarations and where
values live, never values (the one exception: an unconnected input's value, which only an
edit changes).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

from harness.errors import SrrError
from harness.graph.attributes import EXECUTION, Attr, Converter, converter
from harness.graph.errors import GraphError
from harness.graph.node import MISSING, Database, NodeType, OutputSetter

__all__ = [
    "Bindings",
    "CompiledGraph",
    "CompiledNode",
    "Evaluation",
    "NodeDeclarations",
    "NodeRuntime",
    "OutputSlot",
    "Program",
    "compile_program",
]


class Evaluation:
    """One tick of a program (:meth:`Program.run`), or of a stage's programs together
    (:meth:`Program.run_in`): its context, and by its identity which data nodes it has
    computed already (:attr:`NodeRuntime.pulled`)."""

    __slots__ = ("ctx",)

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx


#: Reads one connected input during a run (the evaluation of the run).
InputReader = Callable[[Evaluation | None], Any]
#: ``(full name, value when unconnected, reader when connected)`` of one input.
InputEntry = tuple[str, Any, InputReader | None]
#: An input's entry and what ``db.inputs`` serves for it (its value, or a property).
_Resolved = tuple[InputEntry, Any]
#: One node of a compiled flow: runs the node and the execution it leads to.
Run = Callable[[Evaluation], None]

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


class NodeDeclarations(Protocol):
    """What a :class:`NodeRuntime` reads from its node: its path and declarations."""

    @property
    def path(self) -> str: ...

    @property
    def graph_path(self) -> str: ...

    def attr(self, full_name: str) -> Attr | None: ...

    def attributes(self) -> dict[str, Attr]: ...


@dataclass(frozen=True, slots=True)
class OutputSlot:
    """One output of a compiled node: where it is stored and how a written value converts."""

    full: str
    type_name: str
    is_execution: bool
    stored_as: type | None
    convert: Converter | None


@dataclass(frozen=True, slots=True)
class Bindings:
    """A node's inputs and outputs as the program in force resolved them.

    ``readable`` holds every input by bare name except those starting with ``__``, which
    ``db.inputs`` never serves; ``connected`` the bare names of the inputs with any incoming
    connection (data or execution)."""

    readable: Mapping[str, InputEntry]
    outputs: Mapping[str, OutputSlot]
    connected: frozenset[str]


class NodeRuntime:
    """The evaluation state of one node, kept across programs: its implementation, its
    ``db``, its output values (one dict, updated in place), whether ``initialize`` ran, and
    the bindings of the program in force.

    It is the :class:`~harness.graph.node.NodePort` of the node's ``db``; the port's reads
    and writes serve only what the specialized ``db`` does not (names the node lacks, for the
    error messages)."""

    __slots__ = ("bindings", "computing", "db", "decl", "evaluation", "fired", "impl",
                 "initialized", "outputs", "pulled")

    def __init__(self, decl: NodeDeclarations, impl: NodeType) -> None:
        self.decl = decl
        self.impl = impl
        self.outputs: dict[str, Any] = {}
        self.initialized = False
        self.bindings: Bindings | None = None
        self.evaluation: Evaluation | None = None
        # Execution outputs written by the compute in progress, by full name (made on demand).
        self.fired: dict[str, bool] | None = None
        # A data node: the run that last computed it, and whether its compute is under way.
        self.pulled: Evaluation | None = None
        self.computing = False
        self.db = Database(self)
        self.reset_outputs()

    def reset_outputs(self) -> None:
        """Every output back to its default (in place: programs keep the dict)."""
        self.outputs.clear()
        self.outputs.update({full: attr.default for full, attr in self.decl.attributes().items()
                             if full.startswith("outputs:")})

    # -- NodePort --------------------------------------------------------------------------

    @property
    def node_path(self) -> str:
        return self.decl.path

    @property
    def graph_path(self) -> str:
        return self.decl.graph_path

    def input_attr(self, name: str) -> Attr | None:
        return self.decl.attr(f"inputs:{name}")

    def output_attr(self, name: str) -> Attr | None:
        return self.decl.attr(f"outputs:{name}")

    def input_names(self) -> tuple[str, ...]:
        return tuple(full.partition(":")[2] for full in self.decl.attributes()
                     if full.startswith("inputs:"))

    def output_names(self) -> tuple[str, ...]:
        return tuple(full.partition(":")[2] for full in self.decl.attributes()
                     if full.startswith("outputs:"))

    def read_input(self, name: str) -> Any:
        entry = self.bindings.readable.get(name) if self.bindings is not None else None
        if entry is None:
            return MISSING
        _, value, reader = entry
        return value if reader is None else reader(self.evaluation)

    def read_output(self, name: str) -> Any:
        return self.outputs[f"outputs:{name}"]

    def write_output(self, name: str, value: Any) -> bool:
        slot = self.bindings.outputs.get(name) if self.bindings is not None else None
        if slot is None:
            return False
        _store(self, slot, value)
        return True

    def is_connected(self, name: str) -> bool:
        return self.bindings is not None and name in self.bindings.connected


def _store(runtime: NodeRuntime, slot: OutputSlot, value: Any) -> None:
    """``db.outputs.<name> = value``: an execution output is selected, a value already in the
    stored form of its type kept as is, any other value converted."""
    if type(value) is slot.stored_as:
        runtime.outputs[slot.full] = value
    elif slot.is_execution:
        fired = runtime.fired
        if fired is None:
            fired = runtime.fired = {}
        fired[slot.full] = bool(value)
    else:
        assert slot.convert is not None
        try:
            runtime.outputs[slot.full] = slot.convert(value)
        except ValueError as err:
            raise GraphError(f"{runtime.decl.path}.{slot.full} (type {slot.type_name}): "
                             f"{err}") from err


class CompiledNode(Protocol):
    """What :func:`compile_program` reads from a node."""

    @property
    def name(self) -> str: ...

    @property
    def path(self) -> str: ...

    @property
    def canonical_type(self) -> str: ...

    @property
    def kind(self) -> str: ...

    @property
    def runtime(self) -> NodeRuntime: ...

    @property
    def values(self) -> Mapping[str, Any]: ...

    def attr(self, full_name: str) -> Attr | None: ...

    def attributes(self) -> dict[str, Attr]: ...


class _Connection(Protocol):
    @property
    def src_node(self) -> str: ...

    @property
    def src_attr(self) -> str: ...

    @property
    def dst_node(self) -> str: ...

    @property
    def dst_attr(self) -> str: ...

    @property
    def kind(self) -> str: ...


class CompiledGraph(Protocol):
    """What :func:`compile_program` reads from a graph."""

    @property
    def path(self) -> str: ...

    @property
    def nodes(self) -> tuple[CompiledNode, ...]: ...

    @property
    def connections(self) -> tuple[_Connection, ...]: ...


class Program:
    """One graph compiled: :meth:`run` evaluates it once (see the module docstring)."""

    __slots__ = ("_events",)

    def __init__(self, events: tuple[Run, ...]) -> None:
        self._events = events

    def run(self, ctx: Any) -> None:
        """One tick: every event node fires, in creation order."""
        self.run_in(Evaluation(ctx))

    def run_in(self, evaluation: Evaluation) -> None:
        """One tick within ``evaluation``, which several programs may share (a stage's tick:
        each data node belongs to one graph, so it is still computed at most once per run of
        its graph)."""
        for fire in self._events:
            fire(evaluation)


def failure(node: CompiledNode, err: Exception) -> GraphError:
    """The error of a compute that raised ``err`` (anything but an SrrError)."""
    return GraphError(
        f"{node.path} ({node.canonical_type}): compute failed: {type(err).__name__}: {err}"
    )


def compile_program(graph: CompiledGraph) -> Program:
    """Compile ``graph`` as it is now; specializes every node's ``db`` for the program."""
    nodes = {node.name: node for node in graph.nodes}
    connections = graph.connections
    data_in = {(c.dst_node, c.dst_attr): c for c in connections if c.kind == "data"}
    connected: dict[str, set[str]] = {}
    exec_out: dict[str, list[tuple[str, str]]] = {}
    for c in connections:
        connected.setdefault(c.dst_node, set()).add(c.dst_attr.partition(":")[2])
        if c.kind == "exec":
            exec_out.setdefault(c.src_node, []).append((c.src_attr, c.dst_node))
    reading = {dst_node for dst_node, _ in data_in}
    entries: dict[tuple[str, str], _Resolved] = {}
    values = {name: node.values for name, node in nodes.items()}
    pulls = {name: _pull(graph.path, node) for name, node in nodes.items()
             if node.kind == "data"}

    def entry_of(node: CompiledNode, full: str, attr: Attr) -> _Resolved:
        key = (node.name, full)
        made = entries.get(key)
        if made is None:
            made = entries[key] = resolve(node, full, attr)
        return made

    def resolve(node: CompiledNode, full: str, attr: Attr) -> _Resolved:
        conn = data_in.get((node.name, full)) if attr.type != EXECUTION else None
        if conn is None:
            value = values[node.name].get(full, attr.default)
            return (full, value, None), _constant(value)
        src = nodes[conn.src_node]
        if conn.src_attr.startswith("inputs:"):
            src_attr = src.attr(conn.src_attr)
            assert src_attr is not None
            (_, value, src_reader), _ = entry_of(src, conn.src_attr, src_attr)
            reader = _input_reader(node, full, attr, src, conn.src_attr, value, src_reader)
            return (full, None, reader), _member(node, reader)
        reader, member = _output_reader(node, full, attr, src, conn.src_attr,
                                        pulls.get(src.name))
        return (full, None, reader), member

    for node in nodes.values():
        _bind(node, entry_of, frozenset(connected.get(node.name, ())))

    runs: dict[str, Run] = {}

    def run_of(node: CompiledNode) -> Run:
        made = runs.get(node.name)
        if made is None:
            children = tuple((src_attr, run_of(nodes[dst]))
                             for src_attr, dst in exec_out.get(node.name, ()) if dst in nodes)
            made = runs[node.name] = _step(node, children, node.name in reading)
        return made

    return Program(tuple(run_of(node) for node in nodes.values() if node.kind == "event"))


def _bind(node: CompiledNode, entry_of: Callable[[CompiledNode, str, Attr], _Resolved],
          connected: frozenset[str]) -> None:
    """Resolve ``node``'s inputs and outputs and specialize its ``db`` for them."""
    runtime = node.runtime
    readable: dict[str, InputEntry] = {}
    outputs: dict[str, OutputSlot] = {}
    members: dict[str, Any] = {}
    for full, attr in node.attributes().items():
        port, _, name = full.partition(":")
        if port == "outputs":
            outputs[name] = _output_slot(full, attr)
            continue
        if name[:2] != "__":
            readable[name], members[name] = entry_of(node, full, attr)
    runtime.bindings = Bindings(readable, outputs, connected)
    runtime.db.specialize(members, _output_setter(runtime, outputs), connected,
                          runtime.outputs)


def _output_slot(full: str, attr: Attr) -> OutputSlot:
    if attr.type == EXECUTION:
        return OutputSlot(full, attr.type, True, None, None)
    return OutputSlot(full, attr.type, False, _STORED_AS.get(attr.type), converter(attr.type))


def _does_not_fit(node: CompiledNode, full: str, attr: Attr, src: CompiledNode, src_full: str,
                  err: ValueError) -> GraphError:
    return GraphError(
        f"{node.path}.{full} (type {attr.type}): value from "
        f"{src.path}.{src_full} does not fit: {err}"
    )


Pull = Callable[[Evaluation], None]


def _pull(graph_path: str, node: CompiledNode) -> Pull:
    """Computes the data node ``node`` once per run (the first pull; later pulls return)."""
    runtime, name = node.runtime, node.name
    impl, db = runtime.impl, runtime.db

    def pull(evaluation: Evaluation) -> None:
        if runtime.pulled is evaluation:
            return
        if runtime.computing:
            raise GraphError(f"{graph_path}: data cycle through {name}")
        runtime.computing = True
        runtime.evaluation = evaluation
        runtime.fired = None
        try:
            if not runtime.initialized:
                impl.initialize(db, evaluation.ctx)
                runtime.initialized = True
            impl.compute(db, evaluation.ctx)
        except SrrError:
            raise
        except Exception as err:
            raise failure(node, err) from err
        finally:
            runtime.computing = False
        runtime.pulled = evaluation

    return pull


def _output_reader(node: CompiledNode, full: str, attr: Attr, src: CompiledNode, src_full: str,
                   pull: Pull | None) -> tuple[InputReader, property]:
    """Reader of an input fed by ``src``'s output ``src_full``, and the ``db.inputs``
    property doing its work in one call: a data source computes first (once per run); a
    source of the input's type gives its stored value as is, any other type is converted."""
    src_attr = src.attr(src_full)
    same_type = src_attr is not None and src_attr.type == attr.type
    convert = converter(attr.type)
    src_runtime = src.runtime
    store = src_runtime.outputs
    runtime = node.runtime

    def read(evaluation: Evaluation | None) -> Any:
        if pull is not None and evaluation is not None and src_runtime.pulled is not evaluation:
            pull(evaluation)
        raw = store[src_full]
        if same_type:
            return raw
        try:
            return convert(raw)
        except ValueError as err:
            raise _does_not_fit(node, full, attr, src, src_full, err) from err

    if pull is None and same_type:

        def get_stored(_inputs: object) -> Any:
            return store[src_full]

        return read, property(get_stored)

    if pull is not None and same_type:  # a data source of the input's type: pulled, as is
        compute_source = pull

        def get_pulled(_inputs: object) -> Any:
            evaluation = runtime.evaluation
            if evaluation is not None and src_runtime.pulled is not evaluation:
                compute_source(evaluation)
            return store[src_full]

        return read, property(get_pulled)

    def get(_inputs: object) -> Any:
        return read(runtime.evaluation)

    return read, property(get)


def _input_reader(node: CompiledNode, full: str, attr: Attr, src: CompiledNode, src_full: str,
                  value: Any, src_reader: InputReader | None) -> InputReader:
    """Reader of an input fed by ``src``'s input ``src_full`` (its value, converted)."""
    convert = converter(attr.type)

    def read(evaluation: Evaluation | None) -> Any:
        raw = value if src_reader is None else src_reader(evaluation)
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


def _member(node: CompiledNode, reader: InputReader) -> property:
    """``db.inputs.<name>`` of a connected input: its reader, given the run in progress."""
    runtime = node.runtime

    def get(_inputs: object) -> Any:
        return reader(runtime.evaluation)

    return property(get)


def _output_setter(runtime: NodeRuntime, outputs: Mapping[str, OutputSlot]) -> OutputSetter:
    """``db.outputs.__setattr__`` for the compiled ``outputs`` (the rules of :func:`_store`,
    in one call)."""
    db = runtime.db
    store = runtime.outputs
    slots = {name: (slot.full, slot.stored_as, slot) for name, slot in outputs.items()}

    def set_output(_outputs: object, name: str, value: Any) -> None:
        try:  # a subscript, not .get(): this runs for every write, and a miss is an error
            full, stored_as, slot = slots[name]
        except KeyError:
            raise db.unknown_output(name) from None
        if type(value) is stored_as:
            store[full] = value
        elif slot.is_execution:
            fired = runtime.fired
            if fired is None:
                fired = runtime.fired = {}
            fired[full] = bool(value)
        else:
            assert slot.convert is not None
            try:
                store[full] = slot.convert(value)
            except ValueError as err:
                raise GraphError(f"{runtime.decl.path}.{full} (type {slot.type_name}): "
                                 f"{err}") from err

    return set_output


def _step(node: CompiledNode, children: tuple[tuple[str, Run], ...], reads: bool) -> Run:
    """The closure running the action or event ``node`` and the execution it lets through.
    ``reads``: the node has connected data inputs (their readers need the run in progress).
    A node without execution targets never has its selection read, so it is not reset."""
    runtime = node.runtime
    impl, db = runtime.impl, runtime.db

    def leaf(evaluation: Evaluation) -> None:
        if reads:
            runtime.evaluation = evaluation
        try:
            if not runtime.initialized:
                impl.initialize(db, evaluation.ctx)
                runtime.initialized = True
            impl.compute(db, evaluation.ctx)
        except SrrError:
            raise
        except Exception as err:
            raise failure(node, err) from err

    def run(evaluation: Evaluation) -> None:
        if reads:
            runtime.evaluation = evaluation
        runtime.fired = None
        try:
            if not runtime.initialized:
                impl.initialize(db, evaluation.ctx)
                runtime.initialized = True
            if not impl.compute(db, evaluation.ctx):
                return
        except SrrError:
            raise
        except Exception as err:
            raise failure(node, err) from err
        fired = runtime.fired
        for src_attr, child in children:
            if fired and not fired.get(src_attr):  # outputs were selected, not this one
                continue
            child(evaluation)

    return run if children else leaf
