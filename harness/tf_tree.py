"""Is a set of TF edges one valid tree, as tf2 needs it? Pure functions, no ROS.

An edge is a transform ``parent → child`` from one ``source`` (the scenario field that builds
it, before a run; the topic it was recorded on, after). tf2 keeps one parent per frame and
takes whatever was published last, so these are the problems that make lookups wrong:

* ``frame_id``: an id tf2 refuses (empty, a leading ``/``) or mishandles (whitespace);
* ``two_parents``: one frame with two different parents;
* ``static_dynamic``: one frame published both on a static and on a dynamic topic;
* ``two_sources``: one frame published by two sources (with the same parent);
* ``cycle``: following parents leads back to the start.

Several roots (a forest) are allowed: tf2 accepts them; :func:`roots` names them.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Literal

from harness.bus.names import FrameIdError, validate_frame_id

__all__ = ["Edge", "TreeProblem", "roots", "tree_problems"]

ProblemKind = Literal["frame_id", "two_parents", "static_dynamic", "two_sources", "cycle"]


@dataclass(frozen=True)
class Edge:
    parent: str
    child: str
    static: bool
    source: str


@dataclass(frozen=True)
class TreeProblem:
    """One problem: its kind, the frames involved, the edges (sources) behind it and a
    sentence naming them."""

    kind: ProblemKind
    frames: tuple[str, ...]
    edges: tuple[Edge, ...]
    detail: str


def _kind(static: bool) -> str:
    return "static" if static else "dynamic"


def tree_problems(edges: Iterable[Edge]) -> list[TreeProblem]:
    """Every problem of ``edges`` (deduplicated), in a stable order: bad ids, then per child
    frame (sorted) its parent / static-dynamic / source conflicts, then cycles."""
    unique = list(dict.fromkeys(edges))
    out: list[TreeProblem] = []
    bad: dict[str, list[Edge]] = {}
    for e in unique:
        for frame in (e.parent, e.child):
            try:
                validate_frame_id(frame)
            except FrameIdError:
                bad.setdefault(frame, []).append(e)
    for frame, es in bad.items():
        try:
            validate_frame_id(frame)
        except FrameIdError as err:
            out.append(TreeProblem("frame_id", (frame,), tuple(es), f"{err} (from "
                                   f"{', '.join(sorted({e.source for e in es}))})"))
    by_child: dict[str, list[Edge]] = {}
    for e in unique:
        by_child.setdefault(e.child, []).append(e)
    for child in sorted(by_child):
        es = by_child[child]
        parents = sorted({e.parent for e in es})
        if len(parents) > 1:
            who = "; ".join(f"'{e.parent}' from {e.source}" for e in es)
            out.append(TreeProblem("two_parents", (child, *parents), tuple(es),
                                   f"frame '{child}' has {len(parents)} parents: {who}"))
            continue
        kinds = {e.static for e in es}
        if len(kinds) > 1:
            who = "; ".join(f"{_kind(e.static)} from {e.source}" for e in es)
            out.append(TreeProblem("static_dynamic", (child,), tuple(es),
                                   f"frame '{child}' is published both static and dynamic: "
                                   f"{who}"))
            continue
        sources = sorted({e.source for e in es})
        if len(sources) > 1:
            out.append(TreeProblem("two_sources", (child,), tuple(es),
                                   f"frame '{child}' (child of '{parents[0]}') is published "
                                   f"by {len(sources)} sources: {', '.join(sources)}"))
    out.extend(_cycles(unique))
    return out


def _cycles(edges: Sequence[Edge]) -> list[TreeProblem]:
    parent: dict[str, str] = {}
    for e in edges:
        parent.setdefault(e.child, e.parent)
    out: list[TreeProblem] = []
    reported: set[str] = set()
    for start in sorted(parent):
        path: list[str] = []
        cur: str | None = start
        while cur is not None and cur not in path:
            path.append(cur)
            cur = parent.get(cur)
        if cur is None:
            continue
        loop = path[path.index(cur):][::-1]  # parent → child order
        if reported.intersection(loop):
            continue
        reported.update(loop)
        first = loop.index(min(loop))
        loop = loop[first:] + loop[:first]
        ring = " → ".join([*loop, loop[0]])
        es = tuple(e for e in edges if e.child in loop and e.parent == parent[e.child])
        out.append(TreeProblem("cycle", tuple(loop), es, f"frames form a cycle: {ring} (from "
                               f"{', '.join(sorted({e.source for e in es}))})"))
    return out


def roots(edges: Iterable[Edge]) -> list[str]:
    """Frames that are a parent and never a child: the roots of the forest, sorted."""
    es = list(edges)
    children = {e.child for e in es}
    return sorted({e.parent for e in es} - children)
