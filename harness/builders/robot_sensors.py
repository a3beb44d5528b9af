"""Lidar and IMU graphs of a robot (``robots[].sensors.lidar`` / ``.imu``).

/World/<name>_LidarGraph, the seed's ``add_lidar`` helper behind a rate gate::

    OnPlaybackTick ─▶ SimulationGate ─▶ CreateRenderProduct ─▶ RtxLidarHelper ─▶ scan
                       step = round(tick_hz / fps)  cameraPrim = lidar   ▲ renderProductPath
    ReadSimTime ───────────────────────────────────────────────────────┘ timeStamp

/World/<name>_ImuGraph, the seed's ``add_imu`` helper behind a rate gate::

    OnPlaybackTick ─▶ SimulationGate ─▶ ReadIMU ─▶ PublishImu ─▶ imu
                                         linAcc, angVel, orientation ─┘  ▲ timeStamp
    ReadSimTime ─────────────────────────────────────────────────────────┘

Topic, frame and rate come from the sensor block; the robot's namespace applies to the topic
and its frame prefix to the frame id.
The lidar prim is the site the world mounts on the block's link (``<link prim>/lidar``, e.g.
``/turtlebot3_waffle_pi/base_scan/lidar`` as in the seed).
"""

from __future__ import annotations

from typing import Any

from harness.builders.base import BuildContext, fresh_graph, gate_step, sensor_frame_tf
from harness.graph import Controller, usdrt
from harness.scenario import RobotSpec

__all__ = ["build_imu", "build_lidar", "gate_step", "imu_graph_path", "lidar_graph_path"]


def lidar_graph_path(robot: RobotSpec) -> str:
    return f"/World/{robot.name}_LidarGraph"


def imu_graph_path(robot: RobotSpec) -> str:
    return f"/World/{robot.name}_ImuGraph"


def build_lidar(bc: BuildContext, robot: RobotSpec) -> str | None:
    spec = robot.sensors.lidar
    if spec is None or not spec.enabled or not spec.graph:
        return None
    path = lidar_graph_path(robot)
    prim = bc.world.sensor_prim(robot.name, "lidar")
    keys = Controller.Keys
    nodes = [
        ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
        ("ReadSimTime", "isaacsim.core.nodes.IsaacReadSimulationTime"),
        ("SimulationGate", "isaacsim.core.nodes.IsaacSimulationGate"),
        ("CreateRenderProduct", "isaacsim.core.nodes.IsaacCreateRenderProduct"),
        ("LidarHelper", "isaacsim.ros2.bridge.ROS2RtxLidarHelper"),
    ]
    connect = [
        ("OnPlaybackTick.outputs:tick", "SimulationGate.inputs:execIn"),
        ("SimulationGate.outputs:execOut", "CreateRenderProduct.inputs:execIn"),
        ("CreateRenderProduct.outputs:execOut", "LidarHelper.inputs:execIn"),
        ("CreateRenderProduct.outputs:renderProductPath", "LidarHelper.inputs:renderProductPath"),
        ("ReadSimTime.outputs:simulationTime", "LidarHelper.inputs:timeStamp"),
    ]
    values: list[tuple[str, Any]] = [
        ("SimulationGate.inputs:step", gate_step(bc.scenario.physics.tick_hz, spec.fps)),
        ("CreateRenderProduct.inputs:cameraPrim", [usdrt.Sdf.Path(prim)]),
        ("LidarHelper.inputs:type", spec.type),
        ("LidarHelper.inputs:topicName", spec.topic),
        ("LidarHelper.inputs:frameId", robot.frame(spec.frame_id)),
        ("LidarHelper.inputs:nodeNamespace", robot.ns),
    ]
    tf_nodes, tf_connect, tf_values = sensor_frame_tf(bc, robot, "lidar", spec.frame_id, path,
                                                      "PublishLidarTF", read_time=False)
    nodes += tf_nodes
    connect += tf_connect
    values += tf_values
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: nodes,
        keys.CONNECT: connect,
        keys.SET_VALUES: values,
    })
    bc.annotate(path, "LidarHelper", bc.robot_field(robot, "sensors.lidar"), topicName="topic",
                type="type")
    return path


def build_imu(bc: BuildContext, robot: RobotSpec) -> str | None:
    spec = robot.sensors.imu
    if spec is None or not spec.enabled or not spec.graph:
        return None
    path = imu_graph_path(robot)
    keys = Controller.Keys
    tf_nodes, tf_connect, tf_values = sensor_frame_tf(bc, robot, "imu", spec.frame_id, path,
                                                      "PublishImuTF", read_time=False)
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: [
            ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
            ("ReadSimTime", "isaacsim.core.nodes.IsaacReadSimulationTime"),
            ("SimulationGate", "isaacsim.core.nodes.IsaacSimulationGate"),
            ("ReadIMU", "isaacsim.sensors.physics.IsaacReadIMU"),
            ("PublishIMU", "isaacsim.ros2.bridge.ROS2PublishImu"),
            *tf_nodes,
        ],
        keys.CONNECT: [
            ("OnPlaybackTick.outputs:tick", "SimulationGate.inputs:execIn"),
            ("SimulationGate.outputs:execOut", "ReadIMU.inputs:execIn"),
            ("ReadIMU.outputs:execOut", "PublishIMU.inputs:execIn"),
            ("ReadSimTime.outputs:simulationTime", "PublishIMU.inputs:timeStamp"),
            ("ReadIMU.outputs:linAcc", "PublishIMU.inputs:linearAcceleration"),
            ("ReadIMU.outputs:angVel", "PublishIMU.inputs:angularVelocity"),
            ("ReadIMU.outputs:orientation", "PublishIMU.inputs:orientation"),
            *tf_connect,
        ],
        keys.SET_VALUES: [
            ("SimulationGate.inputs:step", gate_step(bc.scenario.physics.tick_hz, spec.fps)),
            ("ReadIMU.inputs:imuPrim", [usdrt.Sdf.Path(bc.world.sensor_prim(robot.name,
                                                                             "imu"))]),
            ("PublishIMU.inputs:topicName", spec.topic),
            ("PublishIMU.inputs:frameId", robot.frame(spec.frame_id)),
            ("PublishIMU.inputs:nodeNamespace", robot.ns),
            *tf_values,
        ],
    })
    bc.annotate(path, "PublishIMU", bc.robot_field(robot, "sensors.imu"), topicName="topic")
    return path
