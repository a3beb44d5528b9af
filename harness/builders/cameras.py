"""Fixed-camera graphs (/World/<camera>_CameraGraph, one per enabled ``cameras:`` entry).

Seed 001's publishing pattern: the camera's streams run behind a simulation gate whose step
sets the rate (``step = round(tick_hz / fps)``; 2 for 30 fps on the 60 Hz tick)::

    OnPlaybackTick ─▶ IsaacSimulationGate ─▶ IsaacCreateRenderProduct ─┬▶ CameraHelperRgb
                                             cameraPrim, width, height  ├▶ CameraHelperDepth
                                                       renderProductPath ├▶ CameraHelperPointCloud
                                                                         └▶ CameraHelperInfo

One helper per entry of the camera's ``outputs`` (rgb, depth, pointcloud, camera_info), on
topics ``<camera>_rgb``, ``<camera>_depth``, ``<camera>_pointcloud`` and
``<camera>_camera_info`` (seed 001's names), frame id = the last component of the camera's
prim path, which is the optical frame :mod:`harness.builders.camera_tf` publishes. One graph
per camera keeps each camera's gate and ``enabled`` flag its own, and adding a camera a
config change. The helpers of one camera share one render per gated tick.

The camera's ``record`` block adds a ``CompressedCameraHelper`` per compressed format
(:mod:`harness.builders.camera_record`): ``<camera>_rgb/h264``, ``<camera>_rgb/compressed``
and ``<camera>_depth/compressed``.
"""

from __future__ import annotations

from harness.builders.base import (
    BuildContext,
    fresh_graph,
    gate_step,
    gated_render_product,
    render_product_helper,
)
from harness.builders.camera_record import (
    COMPRESSED,
    CompressedStream,
    compressed_helpers,
    fixed_camera,
    h264_values,
    unrecorded_topics,
)
from harness.graph import Controller
from harness.scenario import CameraSpec
from harness.scenario.prims import frame_of

__all__ = ["COMPRESSED", "HELPERS", "CompressedStream", "build", "gate_step", "graph_path",
           "h264_values", "topic_names", "unrecorded_topics"]

#: ``outputs`` entry → (node name, node type, CameraHelper ``type``).
HELPERS: dict[str, tuple[str, str, str | None]] = {
    "rgb": ("CameraHelperRgb", "isaacsim.ros2.bridge.ROS2CameraHelper", "rgb"),
    "depth": ("CameraHelperDepth", "isaacsim.ros2.bridge.ROS2CameraHelper", "depth"),
    "pointcloud": ("CameraHelperPointCloud", "isaacsim.ros2.bridge.ROS2CameraHelper",
                   "depth_pcl"),
    "camera_info": ("CameraHelperInfo", "isaacsim.ros2.bridge.ROS2CameraInfoHelper", None),
}


def graph_path(camera: CameraSpec) -> str:
    return f"/World/{camera.name}_CameraGraph"


def topic_names(camera: CameraSpec) -> dict[str, str]:
    """``outputs`` entry → topic name (relative, as seed 001 names them)."""
    return {out: f"{camera.name}_{out}" for out in camera.outputs}


def build(bc: BuildContext, camera: CameraSpec) -> str | None:
    if not camera.enabled or not camera.outputs:
        return None  # a camera that only streams (RTSP) has no camera graph
    path = graph_path(camera)
    keys = Controller.Keys
    nodes, connect, values = gated_render_product(bc.scenario.physics.tick_hz, camera.fps,
                                                  camera.prim, camera.resolution)
    where = f"cameras[{bc.scenario.cameras.index(camera)}]"
    for out, topic in topic_names(camera).items():
        name, type_name, stream = HELPERS[out]
        nodes.append((name, type_name))
        bc.annotate(path, name, where, topicName="name")
        connect += render_product_helper(name)
        values += [
            (f"{name}.inputs:topicName", topic),
            (f"{name}.inputs:frameId", frame_of(camera.prim)),
        ]
        if stream is not None:
            values.append((f"{name}.inputs:type", stream))
    more_nodes, more_connect, more_values = compressed_helpers(
        bc, path, fixed_camera(bc.scenario, camera))
    nodes += more_nodes
    connect += more_connect
    values += more_values
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: nodes,
        keys.CONNECT: connect,
        keys.SET_VALUES: values,
    })
    return path

