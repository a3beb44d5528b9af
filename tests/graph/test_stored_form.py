"""Nodes that write their outputs straight into their stored values (``db.stored``, without
``db.outputs``' conversion) must write exactly what the conversion would have kept."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from harness import api
from harness.engine import Simulation
from harness.graph.attributes import coerce

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"

#: The node types whose compute writes ``db.stored`` directly.
DIRECT = {"srr.OnPlaybackTick", "srr.OnTick", "srr.ReadSimulationTime", "srr.ReadPrimPose",
          "srr.ComputeOdometry"}


def _same(a: Any, b: Any) -> bool:
    """Equal, and of the same types all the way down (a numpy float is not a float)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return bool(a == b)


@pytest.mark.slow
def test_directly_written_outputs_are_in_their_stored_form() -> None:
    sim = Simulation(api.load(SCENARIOS / "forklift_warehouse.yaml", duration=1.0))
    try:
        sim.run(30)  # long enough for the forklift to move and the odometry to change
        checked: set[str] = set()
        for graph in sim.stage.graphs():
            for node in graph.nodes:
                if node.canonical_type not in DIRECT:
                    continue
                for full, attr in node.attributes().items():
                    if not full.startswith("outputs:") or attr.type == "execution":
                        continue
                    value = node.runtime.outputs[full]
                    assert _same(coerce(attr.type, value), value), (node.path, full, value)
                    checked.add(node.canonical_type)
        assert checked == DIRECT - {"srr.OnTick"}  # the scenario has no OnTick node
    finally:
        sim.close()
