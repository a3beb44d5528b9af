"""Safety indicator graph: /safety/is_muted (std_msgs/Bool) recolours the forklift's disk."""

from __future__ import annotations

import numpy as np
import pytest

from harness.builders.safety_indicator import ALARM_COLOR, MUTED_COLOR, graph_path
from harness.engine import Simulation
from harness.graph import stage_to_dict
from harness.graph.errors import GraphError
from harness.scenario.schema import Pose, RobotSpec, SafetyIndicatorSpec, Scenario
from harness.serde.messages import msg_type

DISK = "/World/forklift/body/body/safety_indicator"
TOPIC = "/safety/is_muted"


def simulation(indicator: SafetyIndicatorSpec, model: str = "forklift",
               name: str = "forklift") -> Simulation:
    robot = RobotSpec(name=name, model=model,  # type: ignore[arg-type]
                      spawn=Pose(position=(-5.0, 0.0, 0.0)), safety_indicator=indicator)
    return Simulation(Scenario(format_version=1, name="t", robots=(robot,)))


def rgba(sim: Simulation, prim: str = DISK) -> tuple[float, ...]:
    return tuple(float(v) for v in sim.world.model.geom_rgba[sim.world.prim_ref(prim).id])


def publish(sim: Simulation, value: bool) -> None:
    """Publish as a system under test does: after the graphs ran, delivered before the next
    tick (the engine spins the bus after the systems under test step)."""
    sim.bus.advertise(TOPIC, "std_msgs/msg/Bool").publish(msg_type("std_msgs/msg/Bool")(
        data=value))
    sim.bus.spin()


def test_disk_is_orange_then_green_one_tick_after_true_and_orange_after_false() -> None:
    sim = simulation(SafetyIndicatorSpec(enabled=True))
    assert graph_path(sim.scenario.robots[0]) in sim.graph_paths
    orange, green = (*ALARM_COLOR, 1.0), (*MUTED_COLOR, 1.0)
    assert orange == (1.0, 0.3, 0.0, 1.0) and green == (0.0, 1.0, 0.0, 1.0)  # the seed's
    for _ in range(3):
        sim.step_tick()
        assert rgba(sim) == pytest.approx(orange)
    publish(sim, True)
    sim.step_tick()
    assert rgba(sim) == pytest.approx(green)
    for _ in range(3):  # no new message: stays as last commanded
        sim.step_tick()
        assert rgba(sim) == pytest.approx(green)
    publish(sim, False)
    sim.step_tick()
    assert rgba(sim) == pytest.approx(orange)
    publish(sim, True)
    publish(sim, False)  # two in one tick: the newest wins
    sim.step_tick()
    assert rgba(sim) == pytest.approx(orange)


def test_graph_wires_the_subscribers_dynamic_data_output_to_the_indicator() -> None:
    sim = simulation(SafetyIndicatorSpec(enabled=True))
    path = "/World/forklift_SafetyGraph"
    graph = sim.stage.graph(path)
    sub = graph.node("ROS2Subscriber")
    assert sub.canonical_type == "srr.Subscriber"
    assert sub.dynamic_attributes["outputs:data"].type == "bool"
    conns = {(c.src, c.dst) for c in graph.connections}
    assert ("ROS2Subscriber.outputs:data", "Indicator.inputs:is_muted") in conns
    script = graph.get_value("Indicator", "inputs:script")
    assert script.startswith("# Prepended by the builder.\nINDICATOR_PRIM = " + repr(DISK))
    dumped = stage_to_dict(sim.stage)
    assert path in str(dumped)


def test_indicator_is_absent_when_disabled_and_the_disk_keeps_its_build_colour() -> None:
    sim = simulation(SafetyIndicatorSpec(enabled=False))
    assert not any(p.endswith("_SafetyGraph") for p in sim.graph_paths)
    before = rgba(sim)
    publish(sim, True)
    sim.step_tick()
    assert rgba(sim) == before


def test_configured_indicator_prim_is_recoloured_keeping_its_alpha() -> None:
    light = "/World/forklift/roof_light"  # the forklift's disk, relocated
    sim = simulation(SafetyIndicatorSpec(enabled=True, indicator_prim=light,
                                         muted_topic="/ops/muted"))
    assert not sim.world.has_prim(DISK)
    sim.world.model.geom_rgba[sim.world.prim_ref(light).id] = (0.2, 0.2, 0.2, 0.5)
    sim.step_tick()
    assert rgba(sim, light) == pytest.approx((*ALARM_COLOR, 0.5))  # polled before any message
    sim.bus.advertise("/ops/muted", "std_msgs/msg/Bool").publish(
        msg_type("std_msgs/msg/Bool")(data=True))
    sim.bus.spin()
    sim.step_tick()
    assert rgba(sim, light) == pytest.approx((*MUTED_COLOR, 0.5))
    sim.world.reset()  # reset restores the build colours
    np.testing.assert_allclose(rgba(sim, light), (*ALARM_COLOR, 1.0))


def test_a_robot_without_the_disk_is_refused_naming_the_field() -> None:
    tb3 = "turtlebot3_waffle_pi"
    with pytest.raises(GraphError, match=r"robots\.tb3\.safety_indicator\.enabled: .*"
                       r"no indicator prim /World/tb3/body/body/safety_indicator"):
        simulation(SafetyIndicatorSpec(enabled=True), model=tb3, name="tb3")
    with pytest.raises(GraphError, match=r"safety_indicator\.indicator_prim: .*/World/nope"):
        simulation(SafetyIndicatorSpec(enabled=True, indicator_prim="/World/nope"), model=tb3,
                   name="tb3")
    with pytest.raises(GraphError, match=r"indicator_prim: /World/tb3/base_link is a body, "
                       r"not a geom"):
        simulation(SafetyIndicatorSpec(enabled=True, indicator_prim="/World/tb3/base_link"),
                   model=tb3, name="tb3")
