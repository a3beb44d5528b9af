"""The node-type registry: canonical names, Isaac Sim aliases, lookup with suggestions.

Node modules register their types with the :func:`register` class decorator on import::

    @register("srr.PublishClock", aliases=("isaacsim.ros2.bridge.ROS2PublishClock",))
    class PublishClock(NodeType): ...

The module-level functions work on the process-wide :data:`DEFAULT_REGISTRY`. A
:class:`Registry` made with ``parent=`` falls back to its parent and may shadow its names,
which lets tests and tools use private node types without touching the shared registry
(pass it to ``GraphStage(registry=...)``).
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Iterable
from typing import TypeVar

from harness.graph.attributes import EXECUTION
from harness.graph.errors import GraphError
from harness.graph.node import NODE_KINDS, NodeType

__all__ = [
    "DEFAULT_REGISTRY",
    "Registry",
    "all_types",
    "canonical_name",
    "lookup",
    "register",
]

N = TypeVar("N", bound=type[NodeType])


def _validate_node_class(cls: object, name: str) -> None:
    if not (isinstance(cls, type) and issubclass(cls, NodeType)):
        raise GraphError(f"node type {name!r}: {cls!r} is not a NodeType subclass")
    if cls.kind not in NODE_KINDS:
        raise GraphError(
            f"node type {name!r}: kind {cls.kind!r} is not one of {', '.join(NODE_KINDS)}"
        )
    for port, attrs in (("inputs", cls.inputs), ("outputs", cls.outputs)):
        seen: set[str] = set()
        for attr in attrs:
            if attr.name in seen:
                raise GraphError(f"node type {name!r}: duplicate attribute '{port}:{attr.name}'")
            seen.add(attr.name)
    exec_inputs = [a for a in cls.inputs if a.type == EXECUTION]
    exec_outputs = [a for a in cls.outputs if a.type == EXECUTION]
    if cls.kind == "data" and (exec_inputs or exec_outputs):
        raise GraphError(f"node type {name!r}: data nodes cannot have execution attributes")
    if cls.kind == "event" and exec_inputs:
        raise GraphError(f"node type {name!r}: event nodes cannot have execution inputs")
    if cls.kind == "action" and not exec_inputs:
        raise GraphError(f"node type {name!r}: action nodes need an execution input")


class Registry:
    """Maps node type names (canonical or alias) to :class:`NodeType` subclasses."""

    def __init__(self, parent: Registry | None = None) -> None:
        self._parent = parent
        self._types: dict[str, type[NodeType]] = {}
        self._canonical: dict[str, str] = {}

    def snapshot(self) -> tuple[dict[str, type[NodeType]], dict[str, str]]:
        """This registry's own names, to :meth:`restore` later (a process that runs one
        scenario after another forgets the types a run's plug-ins registered)."""
        return dict(self._types), dict(self._canonical)

    def restore(self, snapshot: tuple[dict[str, type[NodeType]], dict[str, str]]) -> None:
        """Back to a :meth:`snapshot`: names registered since are forgotten."""
        self._types, self._canonical = dict(snapshot[0]), dict(snapshot[1])

    @property
    def parent(self) -> Registry | None:
        """The registry consulted for names this one does not know."""
        return self._parent

    def register(self, canonical_name: str, *, aliases: Iterable[str] = ()) -> Callable[[N], N]:
        """Class decorator registering a node type under ``canonical_name`` and ``aliases``.

        A name already known to this registry (as canonical or alias) is refused.
        """
        alias_list = tuple(aliases)
        names = (canonical_name, *alias_list)
        for name in names:
            if not isinstance(name, str) or not name:
                raise GraphError(f"node type names must be non-empty strings, got {name!r}")
        if len(set(names)) != len(names):
            raise GraphError(f"node type {canonical_name!r}: a name is given twice in {names}")
        for name in names:
            if name in self._canonical:
                raise GraphError(
                    f"node type name {name!r} is already registered "
                    f"(for {self._canonical[name]!r})"
                )

        def decorate(cls: N) -> N:
            _validate_node_class(cls, canonical_name)
            for name in names:  # re-check: another registration may have run in between
                if name in self._canonical:
                    raise GraphError(
                        f"node type name {name!r} is already registered "
                        f"(for {self._canonical[name]!r})"
                    )
            self._types[canonical_name] = cls
            for name in names:
                self._canonical[name] = canonical_name
            return cls

        return decorate

    def _find(self, type_name: str) -> tuple[str, type[NodeType]] | None:
        canonical = self._canonical.get(type_name)
        if canonical is not None:
            return canonical, self._types[canonical]
        if self._parent is not None:
            return self._parent._find(type_name)
        return None

    def names(self) -> frozenset[str]:
        """Every known name, canonical and alias, including the parent's."""
        own = frozenset(self._canonical)
        return own | self._parent.names() if self._parent is not None else own

    def __contains__(self, type_name: object) -> bool:
        return isinstance(type_name, str) and self._find(type_name) is not None

    def _unknown(self, type_name: str) -> GraphError:
        names = sorted(self.names())
        matches = difflib.get_close_matches(type_name, names, n=3, cutoff=0.6)
        if not matches:
            by_tail: dict[str, str] = {}
            for name in names:
                by_tail.setdefault(name.rsplit(".", 1)[-1], name)
            tail = type_name.rsplit(".", 1)[-1]
            tails = difflib.get_close_matches(tail, list(by_tail), n=3, cutoff=0.6)
            matches = [by_tail[t] for t in tails]
        hint = f"; did you mean {' or '.join(repr(m) for m in matches)}?" if matches else ""
        return GraphError(f"unknown node type {type_name!r}{hint}")

    def lookup(self, type_name: str) -> type[NodeType]:
        """The node type class for a canonical name or alias; unknown names raise GraphError."""
        found = self._find(type_name)
        if found is None:
            raise self._unknown(type_name)
        return found[1]

    def canonical_name(self, type_name: str) -> str:
        """The canonical name for a canonical name or alias; unknown names raise GraphError."""
        found = self._find(type_name)
        if found is None:
            raise self._unknown(type_name)
        return found[0]

    def all_types(self) -> dict[str, type[NodeType]]:
        """Canonical name -> class for every known type (own names shadow the parent's)."""
        merged = dict(self._parent.all_types()) if self._parent is not None else {}
        merged.update(self._types)
        return dict(sorted(merged.items()))

    def aliases(self, canonical: str) -> tuple[str, ...]:
        """The aliases registered here for ``canonical`` (sorted)."""
        return tuple(sorted(n for n, c in self._canonical.items() if c == canonical and n != c))


#: The process-wide registry the module-level functions use.
DEFAULT_REGISTRY = Registry()


def register(canonical_name: str, *, aliases: Iterable[str] = ()) -> Callable[[N], N]:
    """Class decorator: register a node type in :data:`DEFAULT_REGISTRY`."""
    return DEFAULT_REGISTRY.register(canonical_name, aliases=aliases)


def lookup(type_name: str) -> type[NodeType]:
    """The class registered in :data:`DEFAULT_REGISTRY` under ``type_name``."""
    return DEFAULT_REGISTRY.lookup(type_name)


def canonical_name(type_name: str) -> str:
    """The canonical name for ``type_name`` in :data:`DEFAULT_REGISTRY`."""
    return DEFAULT_REGISTRY.canonical_name(type_name)


def all_types() -> dict[str, type[NodeType]]:
    """Canonical name -> class for every type in :data:`DEFAULT_REGISTRY`."""
    return DEFAULT_REGISTRY.all_types()
