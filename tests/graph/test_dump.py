"""JSON and Mermaid dumps of a stage."""

from __future__ import annotations

import json

import harness.graph as og
from harness.graph import GraphStage, Registry

keys = og.Controller.Keys


def build(registry: Registry) -> GraphStage:
    stage = GraphStage(registry=registry)
    with stage:
        og.Controller.edit({"graph_path": "/World/ClockGraph", "evaluator_name": "execution"}, {
            keys.CREATE_NODES: [
                ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
                ("ReadSimTime", "isaacsim.core.nodes.IsaacReadSimulationTime"),
                ("PublishClock", "isaacsim.ros2.bridge.ROS2PublishClock"),
            ],
            keys.CONNECT: [
                ("OnPlaybackTick.outputs:tick", "PublishClock.inputs:execIn"),
                ("ReadSimTime.outputs:simulationTime", "PublishClock.inputs:timeStamp"),
            ],
            keys.SET_VALUES: [("PublishClock.inputs:topicName", "/clock")],
        })
        og.Controller.edit("/World/ControlGraph", {
            keys.CREATE_NODES: [
                ("Tick", "omni.graph.action.OnPlaybackTick"),
                ("SwivelIK", "omni.graph.scriptnode.ScriptNode"),
                ("Gate", "srr.SimulationGate"),
            ],
            keys.CREATE_ATTRIBUTES: [("SwivelIK.inputs:linearVelocity", "double[3]")],
            keys.CONNECT: [("Tick.outputs:tick", "Gate.inputs:execIn"),
                           ("Gate.outputs:execOut", "SwivelIK.inputs:execIn")],
            keys.SET_VALUES: [
                ("SwivelIK.inputs:script", 'def compute(db):\n    return "ok"\n'),
                ("SwivelIK.inputs:linearVelocity", (1, 0, 0)),
                ("Gate.inputs:step", 1),  # the default: not dumped
            ],
        })
    return stage


def test_stage_to_dict(registry: Registry) -> None:
    data = og.stage_to_dict(build(registry))
    assert [g["path"] for g in data["graphs"]] == ["/World/ClockGraph", "/World/ControlGraph"]
    clock = data["graphs"][0]
    assert clock["nodes"][1] == {
        "name": "ReadSimTime",
        "type": "isaacsim.core.nodes.IsaacReadSimulationTime",
        "canonical_type": "srr.ReadSimulationTime",
        "kind": "data",
        "values": {},
        "dynamic_attributes": {},
    }
    assert clock["nodes"][2]["values"] == {"inputs:topicName": "/clock"}
    assert clock["connections"] == [
        {"src": "OnPlaybackTick.outputs:tick", "dst": "PublishClock.inputs:execIn",
         "kind": "exec"},
        {"src": "ReadSimTime.outputs:simulationTime", "dst": "PublishClock.inputs:timeStamp",
         "kind": "data"},
    ]
    control = data["graphs"][1]
    script = control["nodes"][1]
    assert script["dynamic_attributes"] == {"inputs:linearVelocity": "double[3]"}
    assert script["values"]["inputs:linearVelocity"] == [1.0, 0.0, 0.0]
    assert control["nodes"][2]["values"] == {}


def test_stage_to_json_is_stable_and_sorted(registry: Registry) -> None:
    first, second = og.stage_to_json(build(registry)), og.stage_to_json(build(registry))
    assert first == second
    assert first.endswith("\n")
    assert json.loads(first) == og.stage_to_dict(build(registry))
    node_text = first[first.index('"canonical_type"'):]
    keys_in_order = [k for k in ("canonical_type", "dynamic_attributes", "kind", "name")
                     if f'"{k}"' in node_text]
    positions = [node_text.index(f'"{k}"') for k in keys_in_order]
    assert positions == sorted(positions)


def test_stage_to_json_changes_with_the_stage(registry: Registry) -> None:
    stage = build(registry)
    before = og.stage_to_json(stage)
    with stage:
        og.Controller.set("/World/ClockGraph/PublishClock.inputs:topicName", "/clock2")
    assert og.stage_to_json(stage) != before


def test_stage_to_mermaid(registry: Registry) -> None:
    text = og.stage_to_mermaid(build(registry))
    lines = text.splitlines()
    assert lines[0] == "flowchart LR"
    assert '  subgraph g0["/World/ClockGraph"]' in lines
    assert '  subgraph g1["/World/ControlGraph"]' in lines
    assert lines.count("  end") == 2
    assert '    g0_OnPlaybackTick(["OnPlaybackTick<br/><small>srr.OnPlaybackTick</small>"])' \
        in lines
    assert '    g0_ReadSimTime[/"ReadSimTime<br/><small>srr.ReadSimulationTime</small>"/]' \
        in lines
    assert "  g0_OnPlaybackTick --> g0_PublishClock" in lines
    assert '  g0_ReadSimTime -.->|"simulationTime → timeStamp"| g0_PublishClock' in lines
    assert "  g1_Tick --> g1_Gate" in lines
    assert "  g1_Gate --> g1_SwivelIK" in lines


def test_empty_stage_dumps() -> None:
    stage = GraphStage()
    assert og.stage_to_dict(stage) == {"graphs": []}
    assert og.stage_to_mermaid(stage) == "flowchart LR\n"
