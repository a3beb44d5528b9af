"""Builders: idempotent, predictable paths, skipped when disabled, seed graph shapes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness import api
from harness.builders import BuildContext, build_all, forklift_control
from harness.graph import GraphStage, stage_to_dict
from harness.sim import World

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"


def _built(overrides: list[str] = ()) -> tuple[GraphStage, list[str]]:  # type: ignore[assignment]
    sc = api.load(SCENARIO, overrides=overrides)
    stage = GraphStage()
    with stage:
        paths = build_all(BuildContext(sc, World.build(sc)))
    return stage, paths


def test_paths_are_predictable() -> None:
    _, paths = _built()
    assert paths == ["/World/ClockPublisherGraph", "/World/forklift_ControlGraph",
                     "/World/forklift_OdometryGraph", "/World/forklift_TfGraph"]


def test_building_twice_gives_one_graph_each() -> None:
    sc = api.load(SCENARIO)
    stage = GraphStage()
    with stage:
        bc = BuildContext(sc, World.build(sc))
        build_all(bc)
        first = stage_to_dict(stage)
        build_all(bc)
        again = stage_to_dict(stage)
    assert [g.path for g in stage.graphs()] == [
        "/World/ClockPublisherGraph", "/World/forklift_ControlGraph",
        "/World/forklift_OdometryGraph", "/World/forklift_TfGraph"]
    assert first == again


@pytest.mark.parametrize(("flag", "gone"), [
    ("clock.enabled=false", "/World/ClockPublisherGraph"),
    ("robots.forklift.control.enabled=false", "/World/forklift_ControlGraph"),
    ("robots.forklift.odometry.enabled=false", "/World/forklift_OdometryGraph"),
    ("robots.forklift.tf_tree.enabled=false", "/World/forklift_TfGraph"),
])
def test_disabled_block_skips_its_graph(flag: str, gone: str) -> None:
    _, paths = _built([flag])
    assert gone not in paths and len(paths) == 3


def test_disabled_robot_builds_nothing_for_it() -> None:
    _, paths = _built(["robots.forklift.enabled=false"])
    assert paths == ["/World/ClockPublisherGraph"]


def test_control_graph_carries_the_seed_ik_with_prepended_constants() -> None:
    stage, _ = _built(["robots.forklift.control.wheelbase=1.7"])
    graph = stage.graph(forklift_control.graph_path(api.load(SCENARIO).robots[0]))
    script = graph.node("SwivelIK").values["inputs:script"]
    assert script.startswith("DRIVE_JOINT = 'back_wheel_drive'\n")
    assert "WHEELBASE = 1.7" in script and "FLIP_LINEAR_X = True" in script
    types = {n.name: n.type_name for n in graph.nodes}
    assert types["SubscribeTwist"] == "isaacsim.ros2.bridge.ROS2SubscribeTwist"
    assert types["ArticulationController"] == "isaacsim.core.nodes.IsaacArticulationController"


def test_graph_command_prints_mermaid_and_json(capsys: pytest.CaptureFixture[str]) -> None:
    from harness.cli import main

    assert main(["graph", str(SCENARIO)]) == 0
    text = capsys.readouterr().out
    assert text.startswith("flowchart LR") and "ClockPublisherGraph" in text
    assert main(["graph", str(SCENARIO), "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert {g["path"] for g in data["graphs"]} >= {"/World/forklift_ControlGraph"}
