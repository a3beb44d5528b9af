"""Safety indicator graph (/World/<name>_SafetyGraph): ``/safety/is_muted`` recolours a disk.

::

    OnPlaybackTick ─┬▶ ROS2Subscriber (std_msgs/Bool on muted_topic)
                    └▶ Indicator (ScriptNode) ─▶ SetPrimColor
    ROS2Subscriber.outputs:data ─▶ Indicator.inputs:is_muted
    Indicator.outputs:prim, outputs:color ─▶ SetPrimColor.inputs:prim, inputs:color

The indicator script is the seed's, with ``INDICATOR_PRIM`` prepended by the builder: muted →
GREEN (0, 1, 0), alarm → ORANGE (1, 0.3, 0). Like the seed's, it polls the subscriber's
output every tick rather than running only on a new message, so the disk is ORANGE until the
first message and turns within one tick of a message being published (a message published
during tick ``k`` is read at tick ``k + 1``). Harness scripts see only ``db``, so instead of
writing the stage the script hands prim and colour to ``srr.SetPrimColor``.

The disk is ``safety_indicator.indicator_prim`` or the seed's default
``<articulation_prim>/body/body/safety_indicator`` (the forklift model has it).
"""

from __future__ import annotations

from harness.builders.base import BuildContext, fresh_graph
from harness.graph import Controller
from harness.graph.errors import GraphError
from harness.graph.nodes.ros_subscriber import define_message_outputs
from harness.scenario import RobotSpec
from harness.sim.prims import PrimKind
from harness.sim.robots.forklift import indicator_prim

__all__ = ["ALARM_COLOR", "INDICATOR_SCRIPT", "MUTED_COLOR", "build", "graph_path",
           "indicator_source"]

MUTED_COLOR = (0.0, 1.0, 0.0)
ALARM_COLOR = (1.0, 0.3, 0.0)

INDICATOR_SCRIPT = f'''
GREEN = {MUTED_COLOR!r}   # muted: loading allowed
ORANGE = {ALARM_COLOR!r}  # alarm


def compute(db):
    # Poll the subscriber's output each tick (ORANGE until the first message).
    is_muted = bool(db.inputs.is_muted)
    db.outputs.prim = INDICATOR_PRIM
    db.outputs.color = GREEN if is_muted else ORANGE
    return True
'''


def graph_path(robot: RobotSpec) -> str:
    return f"/World/{robot.name}_SafetyGraph"


def indicator_source(prim: str) -> str:
    """The indicator script with ``INDICATOR_PRIM`` prepended, as the seed's builder does."""
    return f"# Prepended by the builder.\nINDICATOR_PRIM = {prim!r}\n{INDICATOR_SCRIPT}"


def build(bc: BuildContext, robot: RobotSpec) -> str | None:
    spec = robot.safety_indicator
    if not spec.enabled:
        return None
    prim = indicator_prim(robot)
    field = f"robots.{robot.name}.safety_indicator." + (
        "indicator_prim" if spec.indicator_prim else "enabled")
    if not bc.world.has_prim(prim):
        raise GraphError(f"{field}: no indicator prim {prim} in the world "
                         "(set safety_indicator.indicator_prim)")
    kind = bc.world.prim_ref(prim).kind
    if kind is not PrimKind.GEOM:
        raise GraphError(f"{field}: {prim} is a {kind.value}, not a geom that can be recoloured")
    path = graph_path(robot)
    keys = Controller.Keys
    graph, _, _, nodes = Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: [
            ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
            ("ROS2Context", "isaacsim.ros2.bridge.ROS2Context"),
            ("ROS2Subscriber", "isaacsim.ros2.bridge.ROS2Subscriber"),
            ("Indicator", "omni.graph.scriptnode.ScriptNode"),
            ("SetPrimColor", "srr.SetPrimColor"),
        ],
        keys.CREATE_ATTRIBUTES: [
            ("Indicator.inputs:is_muted", "bool"),
            ("Indicator.outputs:prim", "target"),
            ("Indicator.outputs:color", "double[3]"),
        ],
        keys.SET_VALUES: [
            ("ROS2Subscriber.inputs:messagePackage", "std_msgs"),
            ("ROS2Subscriber.inputs:messageSubfolder", "msg"),
            ("ROS2Subscriber.inputs:messageName", "Bool"),
            ("ROS2Subscriber.inputs:topicName", spec.muted_topic),
            ("ROS2Subscriber.inputs:nodeNamespace", robot.ns),
        ],
    })
    bc.annotate(path, "ROS2Subscriber", bc.robot_field(robot, "safety_indicator"),
                topicName="muted_topic")
    # The message type is set: the subscriber grows outputs:data, which can now be connected.
    define_message_outputs(nodes["ROS2Subscriber"])
    Controller.edit(graph, {
        keys.CONNECT: [
            ("OnPlaybackTick.outputs:tick", "ROS2Subscriber.inputs:execIn"),
            ("OnPlaybackTick.outputs:tick", "Indicator.inputs:execIn"),
            ("ROS2Context.outputs:context", "ROS2Subscriber.inputs:context"),
            ("ROS2Subscriber.outputs:data", "Indicator.inputs:is_muted"),
            ("Indicator.outputs:execOut", "SetPrimColor.inputs:execIn"),
            ("Indicator.outputs:prim", "SetPrimColor.inputs:prim"),
            ("Indicator.outputs:color", "SetPrimColor.inputs:color"),
        ],
        keys.SET_VALUES: [
            ("Indicator.inputs:script", indicator_source(prim)),
        ],
    })
    return path
