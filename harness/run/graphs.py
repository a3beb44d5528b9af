"""The action graphs a run directory keeps (``graphs.json``, ``graphs.mmd``; the report draws
them from there): taken from the scene as built, or, for a run directory from before runs wrote
them, from the scene built again from its scenario."""

from __future__ import annotations

import contextlib
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from harness.report.graphs import RunGraphs

if TYPE_CHECKING:
    from harness.engine import Simulation
    from harness.scenario import Scenario

__all__ = ["graphs_of", "rebuild_graphs"]


def graphs_of(sim: Simulation) -> RunGraphs:
    from harness.graph import stage_to_json, stage_to_mermaid

    return RunGraphs(stage_to_json(sim.stage), stage_to_mermaid(sim.stage))


def rebuild_graphs(scenario: Scenario, summary: Mapping[str, Any], run_dir: Path) -> RunGraphs:
    """The action graphs of a run directory from before runs wrote ``graphs.json``: the
    scene built again from its scenario (the report itself never builds one). The scene
    builders are imported here, only then: re-rendering a run that has its graphs needs none
    of them."""
    from harness.engine import Simulation

    srr_gt = summary.get("srr_gt")
    # Model and world files are named relative to the scenario file the run was started
    # from (the run's own scenario.yaml keeps those paths as written), as for a replay.
    source = str(summary.get("scenario_file") or run_dir / "scenario.yaml")
    sim = Simulation(scenario, srr_gt=srr_gt if isinstance(srr_gt, bool) else None,
                     source=source)
    try:
        return graphs_of(sim)
    finally:
        with contextlib.suppress(Exception):  # nothing ran: nothing worth reporting
            sim.close()
