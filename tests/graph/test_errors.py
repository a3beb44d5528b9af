"""User errors raise GraphError with a message naming the graph, node and attribute."""

from __future__ import annotations

import re

import pytest

import harness.graph as og
from harness.graph import Attr, GraphStage, NodeType, Registry, register
from harness.graph.errors import GraphError
from harness.graph.registry import DEFAULT_REGISTRY

from .conftest import run_ticks

keys = og.Controller.Keys
TICK = "omni.graph.action.OnPlaybackTick"


def test_unknown_node_type_names_it_and_suggests(stage: GraphStage) -> None:
    with pytest.raises(GraphError) as info:
        og.Controller.edit("/G", {keys.CREATE_NODES: [
            ("Tick", "omni.graph.action.OnPlayBackTick"),
        ]})
    message = str(info.value)
    assert "/G/Tick" in message
    assert "unknown node type 'omni.graph.action.OnPlayBackTick'" in message
    assert "did you mean 'omni.graph.action.OnPlaybackTick'" in message


def test_unknown_node_type_suggests_by_last_segment() -> None:
    with pytest.raises(GraphError, match=r"did you mean .*IsaacSimulationGate"):
        og.lookup("some.vendor.IsaacSimulationGat")
    with pytest.raises(GraphError, match=r"unknown node type 'zzz'$"):
        og.canonical_name("zzz")


def test_lookup_and_canonical_name() -> None:
    gate = og.lookup("omni.isaac.core_nodes.IsaacSimulationGate")
    assert gate is og.lookup("srr.SimulationGate")
    assert og.canonical_name("isaacsim.core.nodes.IsaacSimulationGate") == "srr.SimulationGate"
    assert "srr.ScriptNode" in og.all_types()
    assert "omni.graph.scriptnode.ScriptNode" not in og.all_types()  # canonical names only


def test_duplicate_registration_is_refused() -> None:
    class Dup(NodeType):
        kind = "data"

    with pytest.raises(GraphError, match=r"'srr\.OnTick' is already registered"):
        register("srr.OnTick")(Dup)
    with pytest.raises(GraphError, match=r"'omni.graph.action.OnTick' is already registered"):
        register("test.NeverRegistered", aliases=("omni.graph.action.OnTick",))(Dup)
    assert "test.NeverRegistered" not in DEFAULT_REGISTRY
    private = Registry()
    private.register("test.Dup")(Dup)
    with pytest.raises(GraphError, match="already registered"):
        private.register("test.Other", aliases=("test.Dup",))(Dup)


def test_child_registry_shadows_without_touching_the_parent() -> None:
    class Shadow(NodeType):
        kind = "event"

    child = Registry(parent=DEFAULT_REGISTRY)
    child.register("test.Shadow", aliases=("omni.graph.action.OnTick",))(Shadow)
    assert child.lookup("omni.graph.action.OnTick") is Shadow
    assert child.lookup("srr.OnPlaybackTick") is og.lookup("srr.OnPlaybackTick")
    assert og.canonical_name("omni.graph.action.OnTick") == "srr.OnTick"


@pytest.mark.parametrize(("cls_body", "message"), [
    ({"kind": "sometimes"}, "kind 'sometimes'"),
    ({"kind": "action"}, "action nodes need an execution input"),
    ({"kind": "data", "outputs": (Attr("go", "execution"),)}, "data nodes cannot have"),
    ({"kind": "event", "inputs": (Attr("go", "execution"),)}, "event nodes cannot have"),
    ({"kind": "data", "inputs": (Attr("x", "int"), Attr("x", "double"))}, "duplicate attribute"),
])
def test_bad_node_classes_are_refused(cls_body: dict[str, object], message: str) -> None:
    cls = type("Bad", (NodeType,), cls_body)
    with pytest.raises(GraphError, match=message):
        Registry().register("test.Bad")(cls)


def test_bad_attribute_declarations() -> None:
    with pytest.raises(GraphError, match="unknown type 'vector3'"):
        Attr("x", "vector3")
    with pytest.raises(GraphError, match="not an identifier"):
        Attr("inputs:x", "double")
    with pytest.raises(GraphError, match="bad default"):
        Attr("x", "double[3]", (1.0, 2.0))


def test_duplicate_node(stage: GraphStage) -> None:
    og.Controller.create_node("/G/Tick", TICK)
    with pytest.raises(GraphError, match=r"^/G: node 'Tick' already exists$"):
        og.Controller.edit("/G", {keys.CREATE_NODES: [("Tick", TICK)]})
    with pytest.raises(GraphError, match="node name '1st'"):
        og.Controller.create_node("/G/1st", TICK)


@pytest.fixture
def clock_graph(stage: GraphStage) -> GraphStage:
    og.Controller.edit("/G", {keys.CREATE_NODES: [
        ("Tick", TICK),
        ("Time", "omni.isaac.core_nodes.IsaacReadSimulationTime"),
        ("Pub", "isaacsim.ros2.bridge.ROS2PublishClock"),
        ("Gate", "omni.isaac.core_nodes.IsaacSimulationGate"),
    ]})
    return stage


def test_unknown_attribute(clock_graph: GraphStage) -> None:
    with pytest.raises(GraphError) as info:
        og.Controller.edit("/G", {keys.CONNECT: [("Time.outputs:simTime", "Pub.inputs:timeStamp")]})
    message = str(info.value)
    assert "/G/Time" in message and "'outputs:simTime'" in message
    assert "did you mean 'outputs:simulationTime'" in message
    with pytest.raises(GraphError, match=r"/G/Pub.*'inputs:topic'"):
        og.Controller.attribute("/G/Pub.inputs:topic")
    with pytest.raises(GraphError, match="must look like 'inputs:<name>'"):
        og.Controller.attribute("/G/Pub.topicName")
    with pytest.raises(GraphError, match=r"/G: no node 'Pubb'; did you mean 'Pub'\?"):
        og.Controller.set("/G/Pubb.inputs:topicName", "clock")


@pytest.mark.parametrize(("attr", "value", "expected"), [
    ("Pub.inputs:topicName", 5, "type string"),
    ("Gate.inputs:step", -1, "type uint"),
    ("Gate.inputs:step", 1.5, "type uint"),
    ("Gate.inputs:step", "2", "type uint"),
    ("Time.inputs:resetOnStop", "yes", "type bool"),
    ("Pub.inputs:timeStamp", [1.0], "type double"),
])
def test_bad_value_type(clock_graph: GraphStage, attr: str, value: object, expected: str) -> None:
    with pytest.raises(GraphError) as info:
        og.Controller.edit("/G", {keys.SET_VALUES: [(attr, value)]})
    assert str(info.value).startswith(f"/G/{attr} ({expected})")


def test_setting_exec_or_connected_inputs_is_refused(clock_graph: GraphStage) -> None:
    with pytest.raises(GraphError, match=r"/G/Pub.inputs:execIn: execution attributes"):
        og.Controller.set("/G/Pub.inputs:execIn", 1)
    og.Controller.connect("/G/Time.outputs:simulationTime", "/G/Pub.inputs:timeStamp")
    with pytest.raises(GraphError, match=r"is connected to Time\.outputs:simulationTime"):
        og.Controller.set("/G/Pub.inputs:timeStamp", 1.0)


@pytest.mark.parametrize(("src", "dst", "message"), [
    ("Tick.outputs:tick", "Gate.outputs:execOut", "destination must be an input"),
    ("Tick.outputs:time", "Time.outputs:simulationTime", "destination must be an input"),
    ("Tick.outputs:tick", "Pub.inputs:timeStamp", "execution ports connect only"),
    ("Tick.outputs:time", "Gate.inputs:execIn", "execution ports connect only"),
    ("Gate.inputs:execIn", "Pub.inputs:execIn", "execution input cannot be a source"),
    ("Tick.outputs:time", "Pub.inputs:topicName", "type double does not fit string"),
])
def test_bad_connections(clock_graph: GraphStage, src: str, dst: str, message: str) -> None:
    with pytest.raises(GraphError, match=re.escape(message)) as info:
        og.Controller.edit("/G", {keys.CONNECT: [(src, dst)]})
    assert f"/G: cannot connect {src} -> {dst}" in str(info.value)
    assert clock_graph.graph("/G").connections == ()


def test_one_source_per_data_input_many_per_exec_input(clock_graph: GraphStage) -> None:
    og.Controller.edit("/G", {keys.CONNECT: [
        ("Time.outputs:simulationTime", "Pub.inputs:timeStamp"),
        ("Tick.outputs:tick", "Pub.inputs:execIn"),
        ("Gate.outputs:execOut", "Pub.inputs:execIn"),
    ]})
    with pytest.raises(GraphError, match=r"already fed by Time\.outputs:simulationTime"):
        og.Controller.connect("/G/Tick.outputs:time", "/G/Pub.inputs:timeStamp")
    with pytest.raises(GraphError, match="already connected"):
        og.Controller.connect("/G/Tick.outputs:tick", "/G/Pub.inputs:execIn")


def test_connections_stay_inside_one_graph(clock_graph: GraphStage) -> None:
    og.Controller.create_node("/Other/Tick", TICK)
    with pytest.raises(GraphError, match="belongs to graph /Other"):
        og.Controller.edit("/G", {keys.CONNECT: [("/Other/Tick.outputs:tick",
                                                  "Pub.inputs:execIn")]})


def test_bad_edit_arguments(stage: GraphStage) -> None:
    with pytest.raises(GraphError, match="evaluator 'push' is not supported"):
        og.Controller.edit({"graph_path": "/P", "evaluator_name": "push"})
    with pytest.raises(GraphError, match="unknown key"):
        og.Controller.edit({"graph_path": "/P", "evaluater_name": "execution"})
    with pytest.raises(GraphError, match=r"^/P: unsupported edit key.*'create_prims'"):
        og.Controller.edit("/P", {"create_prims": []})
    with pytest.raises(GraphError, match="absolute prim path"):
        og.Controller.edit("NoSlash")
    assert not stage.has_graph("/P")
    with pytest.raises(GraphError, match="2-tuples"):
        og.Controller.edit("/P", {keys.CREATE_NODES: [("OnlyName",)]})


def test_dynamic_attribute_errors(stage: GraphStage) -> None:
    og.Controller.create_node("/G/S", "omni.graph.scriptnode.ScriptNode")
    og.Controller.create_node("/G/T", "omni.isaac.core_nodes.IsaacReadSimulationTime")
    with pytest.raises(GraphError, match=r"/G/S.inputs:script: attribute already exists"):
        og.Controller.edit("/G", {keys.CREATE_ATTRIBUTES: [("S.inputs:script", "string")]})
    with pytest.raises(GraphError, match=r"/G/S.inputs:v: .*unknown type 'vec3'"):
        og.Controller.edit("/G", {keys.CREATE_ATTRIBUTES: [("S.inputs:v", "vec3")]})
    with pytest.raises(GraphError, match="data node cannot have"):
        og.Controller.create_attribute("/G/T.outputs:go", "execution")


def _script_graph(script: str) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("Script", "omni.graph.scriptnode.ScriptNode")],
        keys.CREATE_ATTRIBUTES: [("Script.inputs:x", "double"), ("Script.outputs:y", "double")],
        keys.CONNECT: [("Tick.outputs:tick", "Script.inputs:execIn")],
        keys.SET_VALUES: [("Script.inputs:script", script)],
    })


def test_script_syntax_error(stage: GraphStage) -> None:
    _script_graph("def compute(db)\n    return True\n")
    with pytest.raises(GraphError, match=r"^/G/Script: script syntax error at line 1") as info:
        run_ticks(stage, 1)
    assert isinstance(info.value.__cause__, SyntaxError)


def test_script_without_compute(stage: GraphStage) -> None:
    _script_graph("def calculate(db):\n    return True\n")
    with pytest.raises(GraphError, match=r"^/G/Script: script defines no compute\(db\)"):
        run_ticks(stage, 1)


def test_script_exception_is_chained(stage: GraphStage) -> None:
    _script_graph("def compute(db):\n    db.outputs.y = 1.0 / db.inputs.x\n    return True\n")
    with pytest.raises(GraphError, match=r"^/G/Script: script compute\(db\) raised "
                                         "ZeroDivisionError") as info:
        run_ticks(stage, 1)
    assert isinstance(info.value.__cause__, ZeroDivisionError)
    og.Controller.set("/G/Script.inputs:x", 4.0)
    run_ticks(stage, 1)
    assert og.Controller.get("/G/Script.outputs:y") == 0.25


@pytest.mark.parametrize(("body", "message"), [
    ("db.inputs.z", r"/G/Script: no attribute 'inputs:z' \(inputs: execIn, script, usePath, "
                    r"scriptPath, x\)"),
    ("db.outputs.z = 1", r"/G/Script: no attribute 'outputs:z'"),
    ("db.outputs.y = 'high'", r"/G/Script.outputs:y \(type double\): expected double"),
    ("db.inputs.x = 2.0", r"/G/Script.inputs:x: inputs are read-only"),
])
def test_script_db_errors(stage: GraphStage, body: str, message: str) -> None:
    _script_graph(f"def compute(db):\n    {body}\n    return True\n")
    with pytest.raises(GraphError, match=message):
        run_ticks(stage, 1)


def test_db_unknown_attribute_is_also_an_attribute_error(stage: GraphStage) -> None:
    _script_graph(
        "def compute(db):\n"
        "    db.outputs.y = getattr(db.inputs, 'missing', 7.0) + db.is_connected('x')\n"
        "    return True\n"
    )
    run_ticks(stage, 1)
    assert og.Controller.get("/G/Script.outputs:y") == 7.0


def test_missing_script_file(stage: GraphStage) -> None:
    _script_graph("")
    og.Controller.edit("/G", {keys.SET_VALUES: [("Script.inputs:usePath", True),
                                                ("Script.inputs:scriptPath", "/nonexistent.py")]})
    with pytest.raises(GraphError, match=r"/G/Script: cannot read inputs:scriptPath"):
        run_ticks(stage, 1)


def test_empty_script(stage: GraphStage) -> None:
    _script_graph("   \n")
    with pytest.raises(GraphError, match=r"/G/Script: inputs:script is empty"):
        run_ticks(stage, 1)


def test_construct_array_beyond_its_inputs(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("Array", "omni.graph.nodes.ConstructArray"),
                            ("A", "test.Record")],
        keys.CONNECT: [("Tick.outputs:tick", "A.inputs:execIn"),
                       ("Array.outputs:array", "A.inputs:value")],
        keys.SET_VALUES: [("Array.inputs:arraySize", 5)],
    })
    with pytest.raises(GraphError, match="arraySize is 5 but there is no inputs:input4"):
        run_ticks(stage, 1)
    og.Controller.create_attribute("/G/Array.inputs:input4", "any")
    og.Controller.set("/G/Array.inputs:input4", "last")
    assert run_ticks(stage, 1).log == [("A", (None, None, None, None, "last"))]


def test_controller_needs_an_active_stage() -> None:
    with pytest.raises(GraphError, match="no graph stage is active"):
        og.Controller.edit("/G", {})
