"""Robot-mounted camera graph (/World/<robot>_CameraGraph), for robots with ``sensors.camera``.

Seed 000's camera graph (the TurtleBot3's ``camera/color`` and ``camera/camera_info``), with a
simulation gate for the block's ``fps`` and the optional depth stream::

    OnPlaybackTick ─▶ IsaacSimulationGate ─▶ IsaacCreateRenderProduct ─┬▶ CameraHelperRgb
                      step = round(tick_hz / fps)   cameraPrim = the    ├▶ CameraHelperInfo
                                                    mounted camera      └▶ CameraHelperDepth
    OnPlaybackTick ─▶ PublishCameraTF (static; with the robot's tf_tree, frame_id ≠ the link)

on ``topic``, ``info_topic`` and ``depth_topic`` (when set), in the robot's namespace; frame
ids carry the robot's frame prefix and the camera's TF goes to the root ``tf_static``.

The camera is the one the world mounts on ``sensors.camera.link`` (``<link prim>/camera``,
looking along the link's +X). Every stream carries ``frame_id``; unless that is the link's own
frame, ``PublishCameraTF`` puts it in the TF tree as the camera's ROS optical frame under the
link (``<link> → <frame_id>`` on the robot's static TF topic; the default ``camera`` gives
``camera_link → camera``), so the images, and a point cloud made from them, can be placed in
the world. A ``frame_id`` equal to the link (``camera_link``) publishes in the link's axes
(+X forward), which is not the optical convention ROS image consumers assume.

The camera's ``record`` block adds a ``CompressedCameraHelper`` per compressed format, as a
fixed camera's does (:mod:`harness.builders.camera_record`): ``<topic>/h264``,
``<topic>/compressed`` and ``<depth_topic>/compressed``, in the robot's namespace.
"""

from __future__ import annotations

from harness.builders.base import (
    BuildContext,
    fresh_graph,
    gated_render_product,
    render_product_helper,
    sensor_frame_tf,
)
from harness.builders.camera_record import compressed_helpers, robot_camera
from harness.graph import Controller
from harness.scenario import RobotSpec

__all__ = ["build", "graph_path"]

_HELPER = "isaacsim.ros2.bridge.ROS2CameraHelper"


def graph_path(robot: RobotSpec) -> str:
    return f"/World/{robot.name}_CameraGraph"


def build(bc: BuildContext, robot: RobotSpec) -> str | None:
    spec = robot.sensors.camera
    if spec is None or not spec.enabled or not spec.graph:
        return None
    path = graph_path(robot)
    camera_prim = bc.world.sensor_prim(robot.name, "camera")
    keys = Controller.Keys
    nodes, connect, values = gated_render_product(bc.scenario.physics.tick_hz, spec.fps,
                                                  camera_prim, spec.resolution)
    where = bc.robot_field(robot, "sensors.camera")
    streams = [("CameraHelperRgb", "rgb", spec.topic, "topic"),
               ("CameraHelperInfo", "camera_info", spec.info_topic, "info_topic")]
    if spec.depth_topic:
        streams.append(("CameraHelperDepth", "depth", spec.depth_topic, "depth_topic"))
    for name, stream, topic, topic_field in streams:
        bc.annotate(path, name, where, topicName=topic_field)
        nodes.append((name, _HELPER))
        connect += render_product_helper(name)
        values += [
            (f"{name}.inputs:type", stream),
            (f"{name}.inputs:topicName", topic),
            (f"{name}.inputs:nodeNamespace", robot.ns),
            (f"{name}.inputs:frameId", robot.frame(spec.frame_id)),
        ]
    recorded = robot_camera(bc.scenario, robot)
    assert recorded is not None
    rec_nodes, rec_connect, rec_values = compressed_helpers(bc, path, recorded)
    nodes += rec_nodes
    connect += rec_connect
    values += rec_values
    tf_nodes, tf_connect, tf_values = sensor_frame_tf(bc, robot, "camera", spec.frame_id, path,
                                                      "PublishCameraTF")
    nodes += tf_nodes
    connect += tf_connect
    values += tf_values
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: nodes,
        keys.CONNECT: connect,
        keys.SET_VALUES: values,
    })
    return path
