"""Prim paths as a scenario names them (``/World/forklift/body``): the path rule and the
TF frame a prim gets. Pure string rules, shared by the scenario checks, the MuJoCo world
(:mod:`harness.sim.prims`) and the graph nodes, so none of them needs the others."""

from __future__ import annotations

import re

from harness.errors import SimulationError

__all__ = ["check_prim_path", "frame_of"]

_PRIM_RE = re.compile(r"^(/[A-Za-z0-9_][A-Za-z0-9_.\-]*)+$")


def check_prim_path(path: str) -> str:
    """Return ``path`` if it is an absolute prim path (``/World/forklift/body``), else raise."""
    if not isinstance(path, str) or not _PRIM_RE.match(path):
        raise SimulationError(f"not a valid prim path: {path!r}")
    return path


def frame_of(prim: str) -> str:
    """Isaac's frame naming: the last component of the prim path."""
    return prim.rstrip("/").rsplit("/", 1)[-1]
