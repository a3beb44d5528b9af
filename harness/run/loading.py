"""Loading a scenario the way the command line does, its overrides applied."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from harness.scenario import Scenario, load_scenario, parse_override

__all__ = ["load"]


def load(path: str | Path, *, seed: int | None = None, duration: float | None = None,
         srr_gt: bool | None = None, overrides: Sequence[str] = ()) -> Scenario:
    """Load a scenario with CLI-style overrides (``--set``, ``--seed``, ``--duration``):
    ``overrides`` is a list of ``KEY=VALUE`` strings, or one such string."""
    if isinstance(overrides, str):  # a str is a Sequence[str] too: of its characters
        overrides = [overrides]
    pairs = [parse_override(o) for o in overrides]
    if seed is not None:
        pairs.append(("seed", seed))
    if duration is not None:
        pairs.append(("duration", duration))
    if srr_gt is not None:
        pairs.append(("srr_gt", srr_gt))
    return load_scenario(path, pairs)
