"""Evaluation semantics: exec push order, data pull and memoization, cycles, stage scoping."""

from __future__ import annotations

from typing import Any

import pytest

import harness.graph as og
from harness.graph import Attr, Database, GraphStage, NodeType, Registry
from harness.graph.errors import GraphError

from .conftest import Counter, Ctx, run_ticks

keys = og.Controller.Keys
TICK = "omni.graph.action.OnPlaybackTick"


def names(ctx: Ctx) -> list[str]:
    return [name for name, _ in ctx.log]


def test_exec_push_is_depth_first_in_connection_order(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("A", "test.Record"), ("B", "test.Record"),
                            ("C", "test.Record")],
        keys.CONNECT: [
            ("Tick.outputs:tick", "B.inputs:execIn"),  # B is connected first...
            ("Tick.outputs:tick", "A.inputs:execIn"),
            ("B.outputs:execOut", "C.inputs:execIn"),  # ...and C runs before A
        ],
    })
    assert names(run_ticks(stage, 1)) == ["B", "C", "A"]


def test_fan_in_runs_the_node_once_per_arrival(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("A", "test.Record"), ("B", "test.Record"),
                            ("X", "test.Record")],
        keys.CONNECT: [
            ("Tick.outputs:tick", "A.inputs:execIn"),
            ("Tick.outputs:tick", "B.inputs:execIn"),
            ("A.outputs:execOut", "X.inputs:execIn"),
            ("B.outputs:execOut", "X.inputs:execIn"),
        ],
    })
    ctx = run_ticks(stage, 2)
    assert names(ctx) == ["A", "X", "B", "X"] * 2
    assert og.Controller.get("/G/X.outputs:count") == 4


def test_false_compute_stops_execution(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("Halt", "test.Stop"), ("After", "test.Record"),
                            ("Other", "test.Record")],
        keys.CONNECT: [
            ("Tick.outputs:tick", "Halt.inputs:execIn"),
            ("Halt.outputs:execOut", "After.inputs:execIn"),
            ("Tick.outputs:tick", "Other.inputs:execIn"),
        ],
    })
    assert names(run_ticks(stage, 1)) == ["Halt", "Other"]


@pytest.mark.parametrize(("condition", "expected"), [(True, "Yes"), (False, "No")])
def test_setting_an_exec_output_selects_what_fires(
    stage: GraphStage, condition: bool, expected: str
) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("If", "test.Branch"), ("Yes", "test.Record"),
                            ("No", "test.Record")],
        keys.CONNECT: [
            ("Tick.outputs:tick", "If.inputs:execIn"),
            ("If.outputs:execTrue", "Yes.inputs:execIn"),
            ("If.outputs:execFalse", "No.inputs:execIn"),
        ],
        keys.SET_VALUES: [("If.inputs:condition", condition)],
    })
    assert names(run_ticks(stage, 1)) == [expected]


def test_event_nodes_fire_in_creation_order(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Second", TICK), ("First", TICK), ("A", "test.Record"),
                            ("B", "test.Record")],
        keys.CONNECT: [
            ("First.outputs:tick", "A.inputs:execIn"),
            ("Second.outputs:tick", "B.inputs:execIn"),
        ],
    })
    assert names(run_ticks(stage, 1)) == ["B", "A"]


def test_graphs_evaluate_in_insertion_order(stage: GraphStage) -> None:
    for path, node in (("/Zeta", "Z"), ("/Alpha", "A")):
        og.Controller.edit(path, {
            keys.CREATE_NODES: [("Tick", TICK), (node, "test.Record")],
            keys.CONNECT: [("Tick.outputs:tick", f"{node}.inputs:execIn")],
        })
    assert names(run_ticks(stage, 2)) == ["Z", "A", "Z", "A"]


def test_data_node_is_pulled_lazily_and_memoized_per_tick(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("Count", "test.Counter"), ("A", "test.Record"),
                            ("B", "test.Record")],
        keys.CONNECT: [
            ("Tick.outputs:tick", "A.inputs:execIn"),
            ("A.outputs:execOut", "B.inputs:execIn"),
            ("Count.outputs:value", "A.inputs:value"),
            ("Count.outputs:value", "B.inputs:value"),
        ],
        keys.SET_VALUES: [("Count.inputs:offset", 0.5)],
    })
    counter = og.Controller.node("/G/Count").impl
    assert isinstance(counter, Counter)
    assert counter.calls == 0  # nothing pulled before the first tick
    ctx = run_ticks(stage, 3)
    assert ctx.log == [("A", 0.5), ("B", 0.5), ("A", 10.5), ("B", 10.5), ("A", 20.5),
                       ("B", 20.5)]
    assert counter.calls == 3


def test_unreached_data_node_never_computes(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("Halt", "test.Stop"), ("Count", "test.Counter"),
                            ("A", "test.Record")],
        keys.CONNECT: [
            ("Tick.outputs:tick", "Halt.inputs:execIn"),
            ("Halt.outputs:execOut", "A.inputs:execIn"),
            ("Count.outputs:value", "A.inputs:value"),
        ],
    })
    run_ticks(stage, 3)
    counter = og.Controller.node("/G/Count").impl
    assert isinstance(counter, Counter)
    assert counter.calls == 0


def test_data_chains_and_inputs_used_as_sources(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [
            ("Tick", TICK), ("Time", "omni.isaac.core_nodes.IsaacReadSimulationTime"),
            ("Scale", "omni.isaac.core_nodes.OgnIsaacScaleToFromStageUnit"),
            ("Const", "omni.graph.nodes.ConstantDouble"),
            ("A", "test.Record"), ("B", "test.Record"),
        ],
        keys.CONNECT: [
            ("Tick.outputs:tick", "A.inputs:execIn"),
            ("Tick.outputs:tick", "B.inputs:execIn"),
            ("Time.outputs:simulationTime", "Scale.inputs:value"),
            ("Scale.outputs:result", "A.inputs:value"),
            ("Const.inputs:value", "B.inputs:value"),  # OmniGraph constants: input as source
        ],
        keys.SET_VALUES: [("Const.inputs:value", 2.5)],
    })
    ctx = run_ticks(stage, 2, hz=4)
    assert ctx.log == [("A", 0.0), ("B", 2.5), ("A", 0.25), ("B", 2.5)]


def test_exec_cycles_are_refused(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("A", "test.Record"), ("B", "test.Record")],
        keys.CONNECT: [("A.outputs:execOut", "B.inputs:execIn")],
    })
    with pytest.raises(GraphError, match="execution cycle"):
        og.Controller.connect("/G/B.outputs:execOut", "/G/A.inputs:execIn")
    with pytest.raises(GraphError, match="execution cycle"):
        og.Controller.connect("/G/A.outputs:execOut", "/G/A.inputs:execIn")
    assert len(stage.graph("/G").connections) == 1


def test_data_cycles_are_refused(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("P", "omni.graph.nodes.ConstantDouble"),
                            ("Q", "omni.graph.nodes.ConstantDouble")],
        keys.CONNECT: [("P.outputs:value", "Q.inputs:value")],
    })
    with pytest.raises(GraphError, match="data cycle"):
        og.Controller.connect("/G/Q.outputs:value", "/G/P.inputs:value")


def test_action_node_may_read_its_own_previous_output(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("A", "test.Record")],
        keys.CONNECT: [("Tick.outputs:tick", "A.inputs:execIn"),
                       ("A.outputs:count", "A.inputs:value")],
    })
    assert [v for _, v in run_ticks(stage, 3).log] == [0, 1, 2]


class _Lifecycle(NodeType):
    kind = "action"
    inputs = (Attr("execIn", "execution"),)
    outputs = (Attr("execOut", "execution"),)

    def __init__(self) -> None:
        self.events: list[str] = []

    def initialize(self, db: Database, ctx: Any) -> None:
        self.events.append(f"init@{ctx.tick}")

    def compute(self, db: Database, ctx: Any) -> bool:
        self.events.append(f"compute@{ctx.tick}")
        return True

    def reset(self) -> None:
        self.events.append("reset")


def test_initialize_once_and_reset(registry: Registry) -> None:
    registry.register("test.Lifecycle")(_Lifecycle)
    with GraphStage(registry=registry) as stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", TICK), ("L", "test.Lifecycle"),
                                ("Gate", "isaacsim.core.nodes.IsaacSimulationGate"),
                                ("A", "test.Record")],
            keys.CONNECT: [("Tick.outputs:tick", "L.inputs:execIn"),
                           ("L.outputs:execOut", "Gate.inputs:execIn"),
                           ("Gate.outputs:execOut", "A.inputs:execIn")],
            keys.SET_VALUES: [("Gate.inputs:step", 2)],
        })
        run_ticks(stage, 3)
        assert og.Controller.get("/G/A.outputs:count") == 2
        stage.reset()
        assert og.Controller.get("/G/A.outputs:count") == 0
        assert og.Controller.get("/G/Tick.outputs:time") == 0.0
        ctx = run_ticks(stage, 1)
    lifecycle = stage.graph("/G").node("L").impl
    assert isinstance(lifecycle, _Lifecycle)
    assert lifecycle.events == ["init@0", "compute@0", "compute@1", "compute@2", "reset",
                                "init@0", "compute@0"]
    assert names(ctx) == ["A"]  # the gate counts from the start again


class _Broken(NodeType):
    kind = "action"
    inputs = (Attr("execIn", "execution"),)

    def compute(self, db: Database, ctx: Any) -> bool:
        raise ZeroDivisionError("boom")


def test_compute_exceptions_become_graph_errors(registry: Registry) -> None:
    registry.register("test.Broken")(_Broken)
    with GraphStage(registry=registry) as stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", TICK), ("Bad", "test.Broken")],
            keys.CONNECT: [("Tick.outputs:tick", "Bad.inputs:execIn")],
        })
        with pytest.raises(GraphError, match=r"/G/Bad \(test.Broken\).*boom") as info:
            run_ticks(stage, 1)
    assert isinstance(info.value.__cause__, ZeroDivisionError)


def test_delete_node_and_disconnect(stage: GraphStage) -> None:
    graph, *_ = og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("A", "test.Record"), ("B", "test.Record")],
        keys.CONNECT: [("Tick.outputs:tick", "A.inputs:execIn"),
                       ("Tick.outputs:tick", "B.inputs:execIn")],
    })
    og.Controller.disconnect("/G/Tick.outputs:tick", "/G/A.inputs:execIn")
    assert names(run_ticks(stage, 1)) == ["B"]
    with pytest.raises(GraphError, match="is not connected"):
        og.Controller.disconnect("/G/Tick.outputs:tick", "/G/A.inputs:execIn")
    og.Controller.edit("/G", {keys.DELETE_NODES: ["B"]})
    assert [n.name for n in graph.nodes] == ["Tick", "A"]
    assert graph.connections == ()
    assert names(run_ticks(stage, 1)) == []


def test_create_node_makes_the_graph_and_lookups_work(stage: GraphStage) -> None:
    node = og.Controller.create_node("/World/Made/Tick", TICK)
    assert stage.has_graph("/World/Made")
    assert node.path == "/World/Made/Tick"
    assert og.Controller.node("/World/Made/Tick") is node
    assert og.Controller.graph("/World/Made").get_path_to_graph() == "/World/Made"
    attribute = og.Controller.attribute("/World/Made/Tick.outputs:time")
    assert attribute.path == "/World/Made/Tick.outputs:time"
    assert og.Controller.attribute("outputs:time", "/World/Made/Tick") == attribute
    run_ticks(stage, 3, hz=2)
    assert attribute.get() == 1.0
    assert og.Controller.get("/World/Made/Tick.outputs:deltaSeconds") == 0.5
    stage.delete_graph("/World/Made")
    assert not stage.has_graph("/World/Made")


def test_stage_nesting_restores_the_previous_stage() -> None:
    outer, inner = GraphStage(), GraphStage()
    with pytest.raises(GraphError, match="no graph stage is active"):
        GraphStage.current()
    with outer:
        assert GraphStage.current() is outer
        with inner:
            assert GraphStage.current() is inner
            with outer:
                assert GraphStage.current() is outer
            assert GraphStage.current() is inner
        assert GraphStage.current() is outer
        og.Controller.create_node("/G/Tick", TICK)
    with pytest.raises(GraphError, match="no graph stage is active"):
        og.Controller.graph("/G")
    assert outer.has_graph("/G") and not inner.has_graph("/G")


def test_stage_is_restored_when_the_block_raises() -> None:
    outer = GraphStage()
    with outer:
        with pytest.raises(RuntimeError), GraphStage():
            raise RuntimeError("x")
        assert GraphStage.current() is outer


class _Editor(NodeType):
    """Action: on its first compute, edits its own graph as ``self.edit`` says."""

    kind = "action"
    inputs = (Attr("execIn", "execution"),)
    outputs = (Attr("execOut", "execution"),)
    edit = ""

    def __init__(self) -> None:
        self.done = False

    def compute(self, db: Database, ctx: Any) -> bool:
        if not self.done:
            self.done = True
            graph = GraphStage.current().graph(db.graph_path)
            if self.edit == "connect":  # a new target of this very node
                graph.connect("E", "outputs:execOut", "Late", "inputs:execIn")
            elif self.edit == "delete":  # a sibling that has not run yet
                graph.delete_node("B")
            elif self.edit == "attribute":  # the ROS 2 Subscriber's way: outputs of its own
                graph.create_attribute("E", "outputs:extra", "double")
            elif self.edit == "value":  # an input of a node that runs later in this tick
                graph.set_value("B", "inputs:value", "set")
            elif self.edit == "other graph":  # a graph that evaluates after this one
                og.Controller.edit("/H", {keys.CONNECT: [("Tick.outputs:tick",
                                                          "C.inputs:execIn")]})
        return True


@pytest.mark.parametrize(("edit", "first", "then"), [
    ("connect", ["A", "B"], ["A", "Late", "B"]),
    ("delete", ["A", "B"], ["A"]),
    ("attribute", ["A", "B"], ["A", "B"]),
])
def test_an_edit_made_by_a_compute_takes_effect_at_the_next_tick(
        registry: Registry, edit: str, first: list[str], then: list[str]) -> None:
    """The tick in progress finishes with the program it started with (a node deleted meanwhile
    still runs, a new connection is not followed); the next tick runs the edited graph. The
    edit itself shows at once to queries."""
    registry.register("test.Editor")(type("Editor", (_Editor,), {"edit": edit}))
    with GraphStage(registry=registry) as stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", TICK), ("E", "test.Editor"), ("A", "test.Record"),
                                ("B", "test.Record"), ("Late", "test.Record")],
            keys.CONNECT: [("Tick.outputs:tick", "E.inputs:execIn"),
                           ("E.outputs:execOut", "A.inputs:execIn"),
                           ("Tick.outputs:tick", "B.inputs:execIn")],
        })
        assert names(run_ticks(stage, 1)) == first
        graph = stage.graph("/G")
        if edit == "connect":
            assert [c.dst_node for c in graph.node("E").connections
                    if c.src_node == "E"] == ["A", "Late"]
        elif edit == "delete":
            assert not graph.has_node("B")
        assert names(run_ticks(stage, 1)) == then


def test_a_value_set_during_a_tick_is_read_from_the_next_tick(registry: Registry) -> None:
    registry.register("test.Editor")(type("Editor", (_Editor,), {"edit": "value"}))
    with GraphStage(registry=registry) as stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", TICK), ("E", "test.Editor"), ("B", "test.Record")],
            keys.CONNECT: [("Tick.outputs:tick", "E.inputs:execIn"),
                           ("Tick.outputs:tick", "B.inputs:execIn")],
            keys.SET_VALUES: [("B.inputs:value", "before")],
        })
        ctx = run_ticks(stage, 1)
        assert og.Controller.get("/G/B.inputs:value") == "set"  # the graph has it at once
        run_ticks(stage, 1, ctx)
        assert ctx.log == [("B", "before"), ("B", "set")]


def test_an_edit_of_a_later_graph_during_a_tick_takes_effect_at_the_next_tick(
        registry: Registry) -> None:
    """Every graph of the stage runs the program it had when the tick began, including a graph
    that evaluates after the one whose node edited it."""
    registry.register("test.Editor")(type("Editor", (_Editor,), {"edit": "other graph"}))
    with GraphStage(registry=registry) as stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", TICK), ("E", "test.Editor")],
            keys.CONNECT: [("Tick.outputs:tick", "E.inputs:execIn")],
        })
        og.Controller.edit("/H", {
            keys.CREATE_NODES: [("Tick", TICK), ("B", "test.Record"), ("C", "test.Record")],
            keys.CONNECT: [("Tick.outputs:tick", "B.inputs:execIn")],
        })
        assert names(run_ticks(stage, 1)) == ["B"]
        assert names(run_ticks(stage, 1)) == ["B", "C"]


def test_a_graph_compiles_one_program_per_edit(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("A", "test.Record")],
        keys.CONNECT: [("Tick.outputs:tick", "A.inputs:execIn")],
    })
    graph = stage.graph("/G")
    first = graph.program()
    run_ticks(stage, 2)
    assert graph.program() is first
    og.Controller.edit("/G", {keys.SET_VALUES: [("A.inputs:value", 1)]})
    assert graph.program() is not first


def test_each_node_keeps_one_db_across_ticks(stage: GraphStage) -> None:
    seen: list[int] = []

    class Keep(NodeType):
        kind = "action"
        inputs = (Attr("execIn", "execution"),)

        def compute(self, db: Database, ctx: Any) -> bool:
            seen.append(id(db))
            return True

    stage.registry.register("test.Keep")(Keep)
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("K", "test.Keep")],
        keys.CONNECT: [("Tick.outputs:tick", "K.inputs:execIn")],
    })
    run_ticks(stage, 3)
    og.Controller.edit("/G", {keys.CREATE_NODES: [("Other", "test.Record")]})  # drops plans
    run_ticks(stage, 1)
    assert len(seen) == 4 and len(set(seen)) == 1


def test_an_edit_by_a_node_with_no_targets_yet_fires_the_new_one_next_tick(
        registry: Registry) -> None:
    """A node whose execution output led nowhere connects a target: it runs from the next
    tick on."""
    registry.register("test.Editor")(type("Editor", (_Editor,), {"edit": "connect"}))
    with GraphStage(registry=registry) as stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", TICK), ("E", "test.Editor"), ("B", "test.Record"),
                                ("Late", "test.Record")],
            keys.CONNECT: [("Tick.outputs:tick", "E.inputs:execIn"),
                           ("Tick.outputs:tick", "B.inputs:execIn")],
        })
        assert names(run_ticks(stage, 1)) == ["B"]
        assert names(run_ticks(stage, 1)) == ["Late", "B"]


class _Keeper(NodeType):
    """Action: keeps ``db.inputs`` / ``db.outputs`` from its first compute and reads through
    them on every later one; logs ``value`` and the type of ``fn``."""

    kind = "action"
    inputs = (Attr("execIn", "execution"), Attr("value", "any"), Attr("fn", "any"),
              Attr("specialize", "int", 7), Attr("_plain", "int", 8))
    outputs = (Attr("execOut", "execution"), Attr("out", "double"))

    def __init__(self) -> None:
        self.kept: tuple[Any, Any] | None = None

    def compute(self, db: Database, ctx: Any) -> bool:
        if self.kept is None:
            self.kept = (db.inputs, db.outputs)
        inputs, outputs = self.kept
        outputs.out = 2  # an int, stored as the double's float
        ctx.log.append((inputs.value, inputs.fn, inputs.specialize, inputs._plain))
        return True


def test_db_kept_across_edits_sees_them_and_values_come_back_as_set(registry: Registry) -> None:
    """``db.inputs`` serves set values as they are (a function too, not bound as a method),
    names that are the db's own internals elsewhere, and a reference kept from an earlier
    tick sees later edits (a value set, a connection made)."""
    registry.register("test.Keeper")(_Keeper)

    def fn(x: int) -> int:
        return x

    with GraphStage(registry=registry) as stage:
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("Tick", TICK), ("K", "test.Keeper")],
            keys.CONNECT: [("Tick.outputs:tick", "K.inputs:execIn")],
            keys.SET_VALUES: [("K.inputs:value", 1), ("K.inputs:fn", fn)],
        })
        ctx = run_ticks(stage, 2)
        og.Controller.edit("/G", {keys.SET_VALUES: [("K.inputs:value", 2)]})
        run_ticks(stage, 1, ctx)
        og.Controller.edit("/G", {
            keys.CREATE_NODES: [("T", "omni.graph.nodes.ConstantDouble")],
            keys.SET_VALUES: [("T.inputs:value", 3.5)],
            keys.CONNECT: [("T.outputs:value", "K.inputs:value")],
        })
        run_ticks(stage, 1, ctx)
        assert [v for v, *_ in ctx.log] == [1, 1, 2, 3.5]
        assert [(f, rest) for _, f, *rest in ctx.log] == [(fn, [7, 8])] * 4
        assert og.Controller.get("/G/K.outputs:out") == 2.0
        assert type(og.Controller.get("/G/K.outputs:out")) is float
        with pytest.raises(GraphError, match=r"/G/K: no attribute 'outputs:nope'"):
            kept_outputs(stage).nope = 1


def kept_outputs(stage: GraphStage) -> Any:
    kept = stage.graph("/G").node("K").impl.kept  # type: ignore[attr-defined]
    assert kept is not None
    return kept[1]
