"""The built-in node types: ticks, time, gate, script node and the small data helpers."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import harness.graph as og
from harness.graph import GraphStage

from .conftest import run_ticks

keys = og.Controller.Keys
TICK = "omni.graph.action.OnPlaybackTick"


@pytest.mark.parametrize(("step", "fired"), [
    (1, list(range(12))),
    (2, [0, 2, 4, 6, 8, 10]),
    (3, [0, 3, 6, 9]),
    (0, []),
])
def test_simulation_gate_passes_every_step_ticks(
    stage: GraphStage, step: int, fired: list[int]
) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK),
                            ("Gate", "omni.isaac.core_nodes.IsaacSimulationGate"),
                            ("A", "test.Record")],
        keys.CONNECT: [("Tick.outputs:tick", "Gate.inputs:execIn"),
                       ("Gate.outputs:execOut", "A.inputs:execIn"),
                       ("Tick.outputs:frame", "A.inputs:value")],
        keys.SET_VALUES: [("Gate.inputs:step", step)],
    })
    ctx = run_ticks(stage, 12)
    assert [int(v) for _, v in ctx.log] == fired


def test_on_playback_tick_outputs(stage: GraphStage) -> None:
    og.Controller.create_node("/G/Tick", TICK)
    run_ticks(stage, 4, hz=8)
    tick = og.Controller.node("/G/Tick")
    assert tick.canonical_type == "srr.OnPlaybackTick"
    assert og.Controller.get("/G/Tick.outputs:time") == 0.375
    assert og.Controller.get("/G/Tick.outputs:frame") == 3.0
    assert og.Controller.get("/G/Tick.outputs:deltaSeconds") == 0.125


def test_on_tick_frame_period(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("OnTick", "omni.graph.action.OnTick"), ("A", "test.Record")],
        keys.CONNECT: [("OnTick.outputs:tick", "A.inputs:execIn"),
                       ("OnTick.outputs:frame", "A.inputs:value")],
        keys.SET_VALUES: [("OnTick.inputs:framePeriod", 2)],
    })
    ctx = run_ticks(stage, 8, hz=10)
    assert [v for _, v in ctx.log] == [0.0, 3.0, 6.0]
    assert og.Controller.get("/G/OnTick.outputs:deltaSeconds") == pytest.approx(0.3)


def test_read_simulation_time_aliases(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [
            ("Tick", TICK),
            ("Old", "omni.isaac.core_nodes.IsaacReadSimulationTime"),
            ("New", "isaacsim.core.nodes.IsaacReadSimulationTime"),
            ("A", "test.Record"), ("B", "test.Record"),
        ],
        keys.CONNECT: [("Tick.outputs:tick", "A.inputs:execIn"),
                       ("A.outputs:execOut", "B.inputs:execIn"),
                       ("Old.outputs:simulationTime", "A.inputs:value"),
                       ("New.outputs:simulationTime", "B.inputs:value")],
    })
    ctx = run_ticks(stage, 3, hz=50)
    assert ctx.log == [("A", 0.0), ("B", 0.0), ("A", 0.02), ("B", 0.02), ("A", 0.04),
                       ("B", 0.04)]
    assert {n.canonical_type for n in stage.graph("/G").nodes[1:3]} == {"srr.ReadSimulationTime"}


def test_break_vector_construct_array_context(stage: GraphStage) -> None:
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [
            ("Tick", TICK), ("Break", "omni.graph.nodes.BreakVector3"),
            ("Array", "omni.graph.nodes.ConstructArray"),
            ("Ctx", "isaacsim.ros2.bridge.ROS2Context"),
            ("Token", "omni.graph.nodes.ConstantToken"),
            ("A", "test.Record"), ("B", "test.Record"),
        ],
        keys.CONNECT: [
            ("Tick.outputs:tick", "A.inputs:execIn"),
            ("A.outputs:execOut", "B.inputs:execIn"),
            ("Break.outputs:z", "Array.inputs:input0"),
            ("Token.outputs:value", "Array.inputs:input1"),
            ("Ctx.outputs:context", "Array.inputs:input2"),
            ("Break.outputs:x", "A.inputs:value"),
            ("Array.outputs:array", "B.inputs:value"),
        ],
        keys.SET_VALUES: [
            ("Break.inputs:tuple", (1.0, 2.0, 3.0)),
            ("Array.inputs:arraySize", 3),
            ("Token.inputs:value", "left"),
            ("Ctx.inputs:domain_id", 7),
        ],
    })
    ctx = run_ticks(stage, 1)
    assert ctx.log == [("A", 1.0), ("B", (3.0, "left", 0))]


SWIVEL_IK_BODY = '''
import math

MIN_COS = 1e-3
MIN_SPEED = 1e-4

def compute(db):
    lin = db.inputs.linearVelocity
    ang = db.inputs.angularVelocity

    # Vehicle-frame vs ROS-frame sign flips (control.reverse_logic.*).
    linear_x = -lin[0] if FLIP_LINEAR_X else lin[0]
    angular_z = -ang[2] if FLIP_ANGULAR_Z else ang[2]

    heading_speed = max(abs(linear_x), MIN_SPEED)
    steer = math.atan2(angular_z * WHEELBASE, heading_speed)
    steer = max(min(steer, MAX_STEER), -MAX_STEER)

    if linear_x < 0.0:                     # reverse
        steer = 0.0 if abs(angular_z) < MIN_SPEED else -steer
        drive = -heading_speed / max(math.cos(steer), MIN_COS)
    else:
        drive = heading_speed / max(math.cos(steer), MIN_COS)

    wheel_ang = drive / WHEEL_RADIUS       # m/s -> rad/s

    db.outputs.jointNames = [DRIVE_JOINT, SWIVEL_JOINT]
    db.outputs.positionCommand = [0.0, steer]      # swivel = steering angle
    db.outputs.velocityCommand = [wheel_ang, 0.0]  # drive  = wheel angular vel
    return True
'''

SWIVEL_IK_CONSTANTS = '''import math
DRIVE_JOINT = 'back_wheel_drive'
SWIVEL_JOINT = 'back_wheel_swivel'
WHEELBASE = 1.49
WHEEL_RADIUS = 0.15
MAX_STEER = math.radians(45)
FLIP_LINEAR_X = True
FLIP_ANGULAR_Z = True
'''


def build_swivel_ik(stage: GraphStage) -> None:
    og.Controller.edit({"graph_path": "/World/forklift_b_ControlGraph",
                        "evaluator_name": "execution"}, {
        keys.CREATE_NODES: [("OnPlaybackTick", TICK),
                            ("SwivelIK", "omni.graph.scriptnode.ScriptNode"),
                            ("After", "test.Record")],
        keys.CREATE_ATTRIBUTES: [
            ("SwivelIK.inputs:linearVelocity", "double[3]"),
            ("SwivelIK.inputs:angularVelocity", "double[3]"),
            ("SwivelIK.outputs:jointNames", "token[]"),
            ("SwivelIK.outputs:positionCommand", "double[]"),
            ("SwivelIK.outputs:velocityCommand", "double[]"),
        ],
        keys.CONNECT: [
            ("OnPlaybackTick.outputs:tick", "SwivelIK.inputs:execIn"),
            ("SwivelIK.outputs:execOut", "After.inputs:execIn"),
            ("SwivelIK.outputs:velocityCommand", "After.inputs:value"),
        ],
        keys.SET_VALUES: [("SwivelIK.inputs:script", SWIVEL_IK_CONSTANTS + SWIVEL_IK_BODY)],
    })


def _steer(angular_z: float) -> float:
    """Independent check of the expected steering angle (before the reverse flip)."""
    return max(min(math.atan(angular_z * 1.49), math.pi / 4), -math.pi / 4)


@pytest.mark.parametrize(("lin", "ang", "steer", "wheel"), [
    # ROS forward 1 m/s is vehicle reverse (flip): straight back, no steer.
    ((1.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, -1 / 0.15),
    # ROS reverse with a left turn: vehicle forward, steer = atan(-0.5 * 1.49).
    ((-1.0, 0.0, 0.0), (0.0, 0.0, 0.5), _steer(-0.5), 1 / math.cos(_steer(-0.5)) / 0.15),
    # Sharp turn: steering clamps at 45 degrees.
    ((-1.0, 0.0, 0.0), (0.0, 0.0, 2.0), -math.pi / 4, math.sqrt(2) / 0.15),
    # Vehicle reverse while turning: the steer sign flips.
    ((1.0, 0.0, 0.0), (0.0, 0.0, 0.5), -_steer(-0.5), -1 / math.cos(_steer(-0.5)) / 0.15),
    # Stopped: heading speed floors at MIN_SPEED; the steer follows the (tiny) turn request.
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 1e-4 / 0.15),
])
def test_script_node_swivel_ik(
    stage: GraphStage, lin: tuple[float, ...], ang: tuple[float, ...], steer: float,
    wheel: float,
) -> None:
    build_swivel_ik(stage)
    og.Controller.edit("/World/forklift_b_ControlGraph", {
        keys.SET_VALUES: [("SwivelIK.inputs:linearVelocity", lin),
                          ("SwivelIK.inputs:angularVelocity", ang)],
    })
    ctx = run_ticks(stage, 1)
    base = "/World/forklift_b_ControlGraph/SwivelIK.outputs:"
    assert og.Controller.get(base + "jointNames") == ("back_wheel_drive", "back_wheel_swivel")
    position = og.Controller.get(base + "positionCommand")
    velocity = og.Controller.get(base + "velocityCommand")
    assert position == pytest.approx((0.0, steer))
    assert velocity == pytest.approx((wheel, 0.0))
    assert ctx.log == [("After", velocity)]


def test_script_node_compiles_once_and_keeps_its_namespace(stage: GraphStage) -> None:
    script = (
        "calls = []\n"
        "def setup(db):\n"
        "    calls.append('setup')\n"
        "def compute(db):\n"
        "    calls.append('compute')\n"
        "    db.outputs.n = len(calls)\n"
        "    return db.inputs.go\n"
    )
    og.Controller.edit("/G", {
        keys.CREATE_NODES: [("Tick", TICK), ("S", "omni.graph.scriptnode.ScriptNode"),
                            ("T", "omni.graph.scriptnode.ScriptNode"), ("A", "test.Record")],
        keys.CREATE_ATTRIBUTES: [("S.inputs:go", "bool"), ("S.outputs:n", "int"),
                                 ("T.inputs:go", "bool"), ("T.outputs:n", "int")],
        keys.CONNECT: [("Tick.outputs:tick", "S.inputs:execIn"),
                       ("Tick.outputs:tick", "T.inputs:execIn"),
                       ("S.outputs:execOut", "A.inputs:execIn")],
        keys.SET_VALUES: [("S.inputs:script", script), ("T.inputs:script", script),
                          ("S.inputs:go", False), ("T.inputs:go", True)],
    })
    ctx = run_ticks(stage, 3)
    assert og.Controller.get("/G/S.outputs:n") == 4  # setup + 3 computes, one namespace
    assert og.Controller.get("/G/T.outputs:n") == 4  # its own namespace, not shared with S
    assert ctx.log == []  # S returned a falsy value: execution stops there
    og.Controller.set("/G/S.inputs:go", True)
    assert len(run_ticks(stage, 1).log) == 1


def test_script_node_reads_a_script_file(stage: GraphStage, tmp_path: Path) -> None:
    script_file = tmp_path / "ik.py"
    script_file.write_text(SWIVEL_IK_CONSTANTS + SWIVEL_IK_BODY, encoding="utf-8")
    build_swivel_ik(stage)
    og.Controller.edit("/World/forklift_b_ControlGraph", {keys.SET_VALUES: [
        ("SwivelIK.inputs:script", ""),
        ("SwivelIK.inputs:usePath", True),
        ("SwivelIK.inputs:scriptPath", str(script_file)),
        ("SwivelIK.inputs:linearVelocity", (1.0, 0.0, 0.0)),
    ]})
    run_ticks(stage, 1)
    velocity = og.Controller.get(
        "/World/forklift_b_ControlGraph/SwivelIK.outputs:velocityCommand"
    )
    assert velocity == pytest.approx((-1 / 0.15, 0.0))
