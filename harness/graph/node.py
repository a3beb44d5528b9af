"""The base class of node implementations and the ``db`` object their compute receives.

A node type is a subclass of :class:`NodeType` with class-level ``kind``, ``inputs`` and
``outputs``; the engine makes one instance per node, so per-node state lives on ``self``.
``compute(db, ctx)`` reads ``db.inputs.<name>`` (pulling connected upstream values) and writes
``db.outputs.<name> = value`` (coerced to the declared type).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, ClassVar, Literal, Protocol

from harness.graph.attributes import Attr
from harness.graph.errors import GraphError

if TYPE_CHECKING:
    from harness.bus.endpoints import Endpoint, TfEdge

__all__ = [
    "MISSING",
    "NODE_KINDS",
    "AttributeLookupError",
    "Database",
    "NodeKind",
    "NodePort",
    "NodeType",
]

NodeKind = Literal["event", "action", "data"]
NODE_KINDS: tuple[str, ...] = ("event", "action", "data")


class AttributeLookupError(GraphError, AttributeError):
    """An unknown attribute was named on ``db.inputs`` / ``db.outputs``.

    It is a :class:`~harness.graph.errors.GraphError` and also an :class:`AttributeError`, so
    ``getattr(db.inputs, "x", default)`` and ``hasattr`` behave as usual.
    """


class _Missing:
    """Type of :data:`MISSING`."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "MISSING"


#: What :meth:`NodePort.read_input` returns for a name the node has no input for.
MISSING: Any = _Missing()


class NodePort(Protocol):
    """What a :class:`Database` needs from the engine for one node during one evaluation.

    ``read_input`` and ``write_output`` serve what a specialized ``db`` does not (see
    :meth:`Database.specialize`): they check the name
    themselves (``read_input`` returns :data:`MISSING`, ``write_output`` False, for a name the
    node does not have, and never serve inputs whose names start with ``__``), so ``db``
    makes one call per access and builds its error messages only on a miss.
    """

    @property
    def node_path(self) -> str: ...

    @property
    def graph_path(self) -> str: ...

    def input_attr(self, name: str) -> Attr | None: ...

    def output_attr(self, name: str) -> Attr | None: ...

    def input_names(self) -> tuple[str, ...]: ...

    def output_names(self) -> tuple[str, ...]: ...

    def read_input(self, name: str) -> Any: ...

    def read_output(self, name: str) -> Any: ...

    def write_output(self, name: str, value: Any) -> bool: ...

    def is_connected(self, name: str) -> bool: ...


def _bare(name: str, prefix: str) -> str:
    return name[len(prefix):] if name.startswith(prefix) else name


class _Inputs:
    """Base of every ``db.inputs`` class. Instances hold nothing: each node's
    :class:`Database` makes a subclass whose methods close over the node's port, so every
    name that does not start with ``__`` is free for an input.

    That plain class resolves each read through the port (``__getattr__``: the ordinary
    look-up fails first). Each program compiled for the node's graph swaps the object's class
    for a subclass (:meth:`Database.specialize`) holding each unconnected input's value as a
    class attribute and each connected input as a property, so a read is one attribute
    look-up (and one call when connected); the port then serves only names the node lacks."""

    __slots__ = ()


class _Outputs:
    """Base of every ``db.outputs`` class (see :class:`_Inputs`): writes are coerced and
    stored on the node, reads give the stored value. A planned subclass replaces the plain
    ``__setattr__`` by one resolved for the node's outputs."""

    __slots__ = ()


def _unknown_output(port: NodePort, name: str) -> AttributeLookupError:
    known = ", ".join(port.output_names()) or "none"
    return AttributeLookupError(
        f"{port.node_path}: no attribute 'outputs:{name}' (outputs: {known})"
    )


def _plain_inputs(port: NodePort) -> type[_Inputs]:
    """The ``db.inputs`` class of one node before it is planned (its ``__getattr__`` also
    serves, through the port, names a planned class does not define)."""

    def __getattr__(self: _Inputs, name: str) -> Any:
        if name[:2] == "__":
            raise AttributeError(name)
        value = port.read_input(name)
        if value is MISSING:
            known = ", ".join(port.input_names()) or "none"
            raise AttributeLookupError(
                f"{port.node_path}: no attribute 'inputs:{name}' (inputs: {known})"
            )
        return value

    def __setattr__(self: _Inputs, name: str, value: Any) -> None:
        raise GraphError(f"{port.node_path}.inputs:{name}: inputs are read-only inside compute")

    def __dir__(self: _Inputs) -> list[str]:
        return list(port.input_names())

    return type("Inputs", (_Inputs,), {
        "__slots__": (), "__getattr__": __getattr__, "__setattr__": __setattr__,
        "__dir__": __dir__,
    })


def _plain_outputs(port: NodePort) -> type[_Outputs]:
    """The ``db.outputs`` class of one node before it is planned."""

    def __getattr__(self: _Outputs, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        if port.output_attr(name) is None:
            raise _unknown_output(port, name)
        return port.read_output(name)

    def __setattr__(self: _Outputs, name: str, value: Any) -> None:
        if not port.write_output(name, value):
            raise _unknown_output(port, name)

    def __dir__(self: _Outputs) -> list[str]:
        return list(port.output_names())

    return type("Outputs", (_Outputs,), {
        "__slots__": (), "__getattr__": __getattr__, "__setattr__": __setattr__,
        "__dir__": __dir__,
    })


def _set_class(obj: object, cls: type) -> None:
    """Swap ``obj``'s class (around the classes' own ``__setattr__``, which refuses)."""
    object.__setattr__(obj, "__class__", cls)


#: A planned ``db.outputs.__setattr__``: stores ``value`` on output ``name`` (or raises).
OutputSetter = Callable[[Any, str, Any], None]


class Database:
    """The ``db`` handed to :meth:`NodeType.compute`.

    ``db.inputs.<name>`` reads an input: the upstream value when connected (computing an upstream
    data node first), else the value set on the node, else the declared default.
    ``db.outputs.<name> = value`` stores an output, coerced to its type; setting an execution
    output (``db.outputs.execOut = True``) selects which execution outputs fire.
    """

    __slots__ = ("_connected", "_plain", "_port", "inputs", "outputs", "stored")

    def __init__(self, port: NodePort) -> None:
        self._port = port
        self._connected: frozenset[str] = frozenset()  # of the plan, once specialized
        self._plain = (_plain_inputs(port), _plain_outputs(port))
        self.inputs: Any = self._plain[0]()
        self.outputs: Any = self._plain[1]()
        #: The node's output values by full name (``"outputs:time"``), once specialized;
        #: None before. A fast path for a node writing, every tick, values already in their
        #: stored form (a ``float`` for ``double``): one dict store instead of the checks of
        #: ``db.outputs.<name> = value``. Anything else goes through ``db.outputs``.
        self.stored: dict[str, Any] | None = None

    def specialize(self, inputs: Mapping[str, Any], set_output: OutputSetter,
                   connected: frozenset[str] = frozenset(),
                   stored: dict[str, Any] | None = None) -> None:
        """Resolve ``db.inputs`` / ``db.outputs`` for a planned node: ``inputs`` maps input
        names to their value (unconnected) or a ``property`` (connected); ``set_output``
        becomes ``db.outputs.__setattr__``. The same objects change class, so a reference to
        ``db.inputs`` kept across an edit sees it once the graph's program is compiled anew.
        Names starting with ``__`` are never served (Python protocol probes keep the ordinary
        look-up). ``connected``: the connected inputs' names, which :meth:`is_connected` then
        answers at once. ``stored``: the dict the node's outputs are kept in, served as
        :attr:`stored`."""
        plain_in, plain_out = self._plain
        self._connected = connected
        self.stored = stored
        members = {k: v for k, v in inputs.items() if k[:2] != "__"}
        _set_class(self.inputs, type("PlannedInputs", (plain_in,), {"__slots__": (), **members}))
        _set_class(self.outputs, type("PlannedOutputs", (plain_out,), {
            "__slots__": (), "__setattr__": set_output}))

    def unknown_output(self, name: str) -> AttributeLookupError:
        """The error for writing an output the node does not have."""
        return _unknown_output(self._port, name)

    @property
    def node_path(self) -> str:
        """The node's absolute path, ``<graph_path>/<name>``."""
        return self._port.node_path

    @property
    def graph_path(self) -> str:
        """The path of the graph holding the node."""
        return self._port.graph_path

    def is_connected(self, input_name: str) -> bool:
        """True when the input (``"x"`` or ``"inputs:x"``) has an upstream connection."""
        if input_name in self._connected:
            return True
        if self._port.is_connected(input_name):  # only ever true for a bare input name
            return True
        name = _bare(input_name, "inputs:")
        if self._port.input_attr(name) is None:
            raise AttributeLookupError(f"{self.node_path}: no attribute 'inputs:{name}'")
        return self._port.is_connected(name)


class NodeType:
    """Base class of node implementations; subclass, declare ports, register.

    ``kind`` is ``"event"`` (fires every evaluation), ``"action"`` (runs when execution reaches
    one of its execution inputs) or ``"data"`` (pure, computed when a downstream node pulls one of
    its outputs, at most once per evaluation).
    """

    kind: ClassVar[str] = "action"
    inputs: ClassVar[tuple[Attr, ...]] = ()
    outputs: ClassVar[tuple[Attr, ...]] = ()

    def initialize(self, db: Database, ctx: Any) -> None:
        """Called once before the first compute (and again after :meth:`reset`)."""

    def compute(self, db: Database, ctx: Any) -> bool:
        """Do the node's work; True fires its execution outputs, False stops execution here."""
        return True

    def reset(self) -> None:
        """Forget per-node state (the engine calls it from ``GraphStage.reset``)."""

    def endpoints(self, value: Callable[[str], Any]) -> Sequence[Endpoint | TfEdge]:
        """The topics this node will publish or subscribe and the TF edges it will publish,
        from its input values as set (``value("topicName")``; nothing is computed), so the
        wiring can be checked before a run (:mod:`harness.wiring`). Default: none."""
        return ()

    def world_edges(self, value: Callable[[str], Any], world: Any) -> Sequence[TfEdge]:
        """TF edges the node will publish that only the built ``world`` can tell (the links
        of an articulation root it is given), for the same wiring checks. Default: none."""
        return ()
