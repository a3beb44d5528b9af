"""Ground-truth graph (/World/SRRGraph), built only with ``--srr-gt`` (or ``srr_gt: true``).

True poses for the scoring, every tick, parent frame ``world``::

    OnPlaybackTick ─┬▶ PublishGT_<robot>        ◀─ ReadPose_<robot> (base prim)
                    └▶ PublishGT_character_<i>  ◀─ ReadPose_character_<i> (worker prim)
    ReadSimulationTime ─▶ every publisher's timeStamp

* ``/gt/<robot>/tf``: child frame ``<robot>``, the pose of the robot's base prim (the chassis
  that odometry reads) with ``robot_front`` turned onto +X, exactly as
  ``IsaacComputeOdometry`` reports it. So ``world → odom`` (``/tf_static``) composed with
  odometry equals ground truth for a perfect odometry, and the forklift (whose chassis faces
  -X) reports the heading it drives along. That is why robots use ``ReadPrimPose`` +
  ``ROS2PublishRawTransformTree`` rather than the seed's ``ROS2PublishTransformTree``, which
  would name the frame after the prim and keep the asset's -X heading.
* ``/gt/character_<i>/tf``: child frame ``character_<i>`` (``i`` = index in
  ``scenario.workers``), the worker's live pose: floor point under its centre, +X facing.

Without ``srr_gt`` nothing here exists: no graph and no ``/gt`` topic.
"""

from __future__ import annotations

from typing import Any

from harness.builders.base import BuildContext, fresh_graph
from harness.builders.odometry import robot_front
from harness.graph import Controller

__all__ = ["GRAPH_PATH", "WORLD_FRAME", "build", "robot_topic", "worker_topic"]

GRAPH_PATH = "/World/SRRGraph"
WORLD_FRAME = "world"


def robot_topic(robot: str) -> str:
    return f"/gt/{robot}/tf"


def worker_topic(index: int) -> str:
    return f"/gt/character_{index}/tf"


def build(bc: BuildContext) -> str | None:
    if not bc.srr_gt:
        return None
    # (frame, topic, prim, robot front, scenario field) of everything with a ground truth
    targets: list[tuple[str, str, str, tuple[float, float, float], str]] = []
    for robot in bc.scenario.robots:
        if robot.enabled:
            targets.append((robot.name, robot_topic(robot.name),
                            bc.world.base_prim(robot.name), robot_front(bc, robot),
                            bc.robot_field(robot)))
    for worker in bc.world.workers():
        targets.append((worker.frame, worker_topic(worker.index), worker.prim, (1.0, 0.0, 0.0),
                        f"workers[{worker.index}]"))

    nodes: list[tuple[str, str]] = [
        ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
        ("ROS2Context", "isaacsim.ros2.bridge.ROS2Context"),
        ("ReadSimTime", "isaacsim.core.nodes.IsaacReadSimulationTime"),
    ]
    connect: list[tuple[str, str]] = []
    values: list[tuple[str, Any]] = []
    for frame, topic, prim, front, where in targets:
        read, pub = f"ReadPose_{frame}", f"PublishGT_{frame}"
        bc.annotate(GRAPH_PATH, pub, where)
        nodes += [(read, "srr.ReadPrimPose"),
                  (pub, "isaacsim.ros2.bridge.ROS2PublishRawTransformTree")]
        connect += [
            ("OnPlaybackTick.outputs:tick", f"{pub}.inputs:execIn"),
            ("ROS2Context.outputs:context", f"{pub}.inputs:context"),
            ("ReadSimTime.outputs:simulationTime", f"{pub}.inputs:timeStamp"),
            (f"{read}.outputs:translation", f"{pub}.inputs:translation"),
            (f"{read}.outputs:rotation", f"{pub}.inputs:rotation"),
        ]
        values += [
            (f"{read}.inputs:prim", [prim]),
            (f"{read}.inputs:robotFront", front),
            (f"{pub}.inputs:topicName", topic),
            (f"{pub}.inputs:parentFrameId", WORLD_FRAME),
            (f"{pub}.inputs:childFrameId", frame),
        ]
    keys = Controller.Keys
    Controller.edit(fresh_graph(GRAPH_PATH), {
        keys.CREATE_NODES: nodes,
        keys.CONNECT: connect,
        keys.SET_VALUES: values,
    })
    return GRAPH_PATH
