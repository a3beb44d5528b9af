"""Loading a scenario the way the command line does, its overrides applied."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from harness.scenario import Scenario, load_scenario, parse_override

__all__ = ["ScenarioLoads", "load"]


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


class ScenarioLoads:
    """Each (scenario file, overrides) loaded once, then the same :class:`Scenario` (frozen)
    for every later use: planning a suite loads an entry's scenario to learn its name, to
    plan its runs, to check it and to find its baseline file (four loads of each before:
    half of the nightly's 0.74 s of checking on the 2-core box). A load that fails is not
    kept: the next use fails the same way."""

    def __init__(self) -> None:
        self._loaded: dict[tuple[str, tuple[str, ...]], Scenario] = {}

    def __call__(self, path: str | Path, overrides: Sequence[str] = ()) -> Scenario:
        key = (str(path), tuple(overrides))
        sc = self._loaded.get(key)
        if sc is None:
            sc = self._loaded[key] = load(path, overrides=list(overrides))
        return sc
