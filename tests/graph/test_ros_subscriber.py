"""The generic ROS2Subscriber node: message fields as dynamic outputs, newest message wins."""

from __future__ import annotations

import pytest

from harness.bus import Bus
from harness.engine import EvalContext
from harness.graph import Controller, GraphStage, canonical_name
from harness.graph.errors import GraphError
from harness.graph.nodes.ros_subscriber import define_message_outputs, message_fields
from harness.serde.messages import msg_type, twist

K = Controller.Keys
COUNTER = "def compute(db):\n    db.outputs.count = db.outputs.count + 1\n    return True\n"


def make(stage: GraphStage, package: str = "geometry_msgs", name: str = "Twist",
         topic: str = "cmd") -> None:
    with stage:
        Controller.edit("/G", {
            K.CREATE_NODES: [("Tick", "omni.graph.action.OnPlaybackTick"),
                             ("Sub", "omni.isaac.ros2_bridge.ROS2Subscriber"),
                             ("Count", "omni.graph.scriptnode.ScriptNode")],
            K.CREATE_ATTRIBUTES: [("Count.outputs:count", "int")],
            K.CONNECT: [("Tick.outputs:tick", "Sub.inputs:execIn"),
                        ("Sub.outputs:execOut", "Count.inputs:execIn")],
            K.SET_VALUES: [("Sub.inputs:messagePackage", package),
                           ("Sub.inputs:messageName", name),
                           ("Sub.inputs:topicName", topic),
                           ("Count.inputs:script", COUNTER)],
        })


def tick(stage: GraphStage, ctx: EvalContext) -> None:
    with stage:
        stage.evaluate(ctx)
    ctx.tick += 1


def test_aliases_resolve_to_the_generic_subscriber() -> None:
    for alias in ("isaacsim.ros2.bridge.ROS2Subscriber", "omni.isaac.ros2_bridge.ROS2Subscriber"):
        assert canonical_name(alias) == "srr.Subscriber"


def test_fields_are_flattened_scalars_in_definition_order() -> None:
    assert message_fields("std_msgs/msg/Bool") == (("data", ("data",), "bool"),)
    assert message_fields("std_msgs/msg/Header") == (
        ("stamp_sec", ("stamp", "sec"), "int"),
        ("stamp_nanosec", ("stamp", "nanosec"), "uint"),
        ("frame_id", ("frame_id",), "string"),
    )
    scan = [name for name, _, _ in message_fields("sensor_msgs/msg/LaserScan")]
    assert "range_max" in scan and "ranges" not in scan  # sequences are left out
    with pytest.raises(KeyError):
        message_fields("std_msgs/msg/Nope")


def test_outputs_appear_on_first_compute_and_follow_the_newest_message() -> None:
    stage, bus = GraphStage(), Bus(lambda: 0)
    ctx = EvalContext(0, 0, None, bus)  # type: ignore[arg-type]
    make(stage)
    graph = stage.graph("/G")
    assert graph.node("Sub").attr("outputs:linear_x") is None
    tick(stage, ctx)
    names = [a.name for a in graph.node("Sub").output_attrs()]
    assert names == ["execOut", "linear_x", "linear_y", "linear_z", "angular_x", "angular_y",
                     "angular_z"]
    assert graph.get_value("Count", "outputs:count") == 0  # no message: execution stops
    pub = bus.advertise("/cmd", "geometry_msgs/msg/Twist")
    pub.publish(twist((1.0, 0.0, 0.0), (0.0, 0.0, 0.1)))
    pub.publish(twist((2.0, 0.0, 0.0), (0.0, 0.0, 0.2)))
    bus.spin()
    tick(stage, ctx)
    assert graph.get_value("Sub", "outputs:linear_x") == 2.0
    assert graph.get_value("Sub", "outputs:angular_z") == 0.2
    assert graph.get_value("Count", "outputs:count") == 1
    tick(stage, ctx)  # nothing new: outputs keep their values, execOut does not fire
    assert graph.get_value("Sub", "outputs:linear_x") == 2.0
    assert graph.get_value("Count", "outputs:count") == 1


def test_define_message_outputs_lets_builders_connect_before_the_first_tick() -> None:
    stage, bus = GraphStage(), Bus(lambda: 0)
    make(stage, "std_msgs", "Bool", "/safety/is_muted")
    graph = stage.graph("/G")
    assert define_message_outputs(graph.node("Sub")) == ("data",)
    assert define_message_outputs(graph.node("Sub")) == ("data",)  # idempotent
    with stage:
        Controller.edit("/G", {K.CREATE_NODES: [("Copy", "srr.ConstantBool")],
                               K.CONNECT: [("Sub.outputs:data", "Copy.inputs:value")]})
    bus.advertise("/safety/is_muted", "std_msgs/msg/Bool").publish(
        msg_type("std_msgs/msg/Bool")(data=True))
    ctx = EvalContext(0, 0, None, bus)  # type: ignore[arg-type]
    tick(stage, ctx)  # subscribes; the message was published before: volatile, not seen
    assert graph.get_value("Copy", "inputs:value") is False
    bus.advertise("/safety/is_muted", "std_msgs/msg/Bool").publish(
        msg_type("std_msgs/msg/Bool")(data=True))
    bus.spin()
    tick(stage, ctx)
    assert graph.get_value("Copy", "inputs:value") is True


def test_bad_types_are_refused_naming_the_node() -> None:
    bus = Bus(lambda: 0)
    ctx = EvalContext(0, 0, None, bus)  # type: ignore[arg-type]
    stage = GraphStage()
    make(stage, package="", name="")
    with pytest.raises(GraphError, match=r"/G/Sub: set inputs:messagePackage"):
        tick(stage, ctx)
    stage = GraphStage()
    make(stage, "std_msgs", "Nope")
    with pytest.raises(GraphError, match=r"/G/Sub: unknown message type 'std_msgs/msg/Nope'"):
        tick(stage, ctx)
    stage = GraphStage()
    make(stage, "std_msgs", "Boool")  # a typo: the closest known type is suggested
    with pytest.raises(GraphError, match=r"'std_msgs/msg/Boool'; did you mean "
                                         r"'std_msgs/msg/Bool'\?"):
        tick(stage, ctx)
    stage = GraphStage()
    make(stage, "std_msgs", "Bool")
    with stage:
        Controller.create_attribute("/G/Sub.outputs:data", "double")
    with pytest.raises(GraphError, match=r"outputs:data: is double, but std_msgs/msg/Bool"):
        define_message_outputs(stage.graph("/G").node("Sub"))
    stage = GraphStage()
    make(stage, "std_msgs", "Bool")
    with pytest.raises(GraphError, match="define_message_outputs"):
        stage.evaluate(EvalContext(0, 0, None, bus))  # type: ignore[arg-type]  # no stage
