"""What every graph builder shares: its inputs and the replace-on-rebuild rule."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from harness.graph import GraphStage
from harness.scenario import Scenario

__all__ = ["BuildContext", "fresh_graph"]


@dataclass(frozen=True)
class BuildContext:
    """A builder's inputs: the resolved scenario and the built world (read for prim paths)."""

    scenario: Scenario
    world: Any
    srr_gt: bool = False


def fresh_graph(path: str) -> dict[str, str]:
    """Delete any graph already at ``path`` (builders are idempotent) and return the
    ``Controller.edit`` config that creates it anew."""
    stage = GraphStage.current()
    if stage.has_graph(path):
        stage.delete_graph(path)
    return {"graph_path": path, "evaluator_name": "execution"}
