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
(:data:`COMPRESSED`): ``<camera>_rgb/h264`` (foxglove_msgs/CompressedVideo),
``<camera>_rgb/compressed`` (jpeg or png) and ``<camera>_depth/compressed`` (16-bit PNG
millimetres). A raw stream that ``record`` leaves out is still published (the systems under
test read it in the run) but not recorded: :func:`unrecorded_topics`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from harness.builders.base import BuildContext, fresh_graph, gate_step, gated_render_product
from harness.bus import resolve_topic
from harness.graph import Controller
from harness.graph.nodes.ros_bridge import frame_of
from harness.graph.nodes.video import COMPRESSED_FORMATS
from harness.scenario import CameraSpec, H264Spec, Scenario

__all__ = ["COMPRESSED", "HELPERS", "CompressedStream", "build", "compressed_streams",
           "gate_step", "graph_path", "h264_values", "topic_names", "unrecorded_topics"]

#: ``outputs`` entry → (node name, node type, CameraHelper ``type``).
HELPERS: dict[str, tuple[str, str, str | None]] = {
    "rgb": ("CameraHelperRgb", "isaacsim.ros2.bridge.ROS2CameraHelper", "rgb"),
    "depth": ("CameraHelperDepth", "isaacsim.ros2.bridge.ROS2CameraHelper", "depth"),
    "pointcloud": ("CameraHelperPointCloud", "isaacsim.ros2.bridge.ROS2CameraHelper",
                   "depth_pcl"),
    "camera_info": ("CameraHelperInfo", "isaacsim.ros2.bridge.ROS2CameraInfoHelper", None),
}


#: (stream, format) → (node name, topic suffix after ``<camera>_<stream>``).
COMPRESSED: dict[tuple[str, str], tuple[str, str]] = {
    ("rgb", "h264"): ("CameraHelperRgbH264", "/h264"),
    ("rgb", "jpeg"): ("CameraHelperRgbJpeg", "/compressed"),
    ("rgb", "png"): ("CameraHelperRgbPng", "/compressed"),
    ("depth", "png"): ("CameraHelperDepthPng", "/compressed"),
}


@dataclass(frozen=True)
class CompressedStream:
    """One compressed topic of a camera: ``topic`` (fully qualified) carries ``raw_topic``'s
    ``stream`` (rgb or depth) as ``format`` in ``msgtype``."""

    camera: str
    stream: str
    format: str
    topic: str
    raw_topic: str
    msgtype: str


def compressed_streams(camera: CameraSpec) -> list[CompressedStream]:
    """The camera's compressed topics, from its ``record`` block."""
    out = []
    for stream, formats in (("rgb", camera.record.rgb), ("depth", camera.record.depth)):
        for fmt in formats:
            if fmt == "raw":
                continue
            raw = f"{camera.name}_{stream}"
            out.append(CompressedStream(camera.name, stream, fmt,
                                        resolve_topic(raw + COMPRESSED[(stream, fmt)][1]),
                                        resolve_topic(raw), COMPRESSED_FORMATS[(stream, fmt)]))
    return out


def unrecorded_topics(scenario: Scenario) -> set[str]:
    """Raw camera topics published but, by their camera's ``record``, not recorded."""
    out = set()
    for cam in scenario.cameras:
        if not cam.enabled:
            continue
        for stream, formats in (("rgb", cam.record.rgb), ("depth", cam.record.depth)):
            if stream in cam.outputs and "raw" not in formats:
                out.add(resolve_topic(f"{cam.name}_{stream}"))
    return out


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
        connect += [
            ("CreateRenderProduct.outputs:execOut", f"{name}.inputs:execIn"),
            ("CreateRenderProduct.outputs:renderProductPath",
             f"{name}.inputs:renderProductPath"),
            ("ROS2Context.outputs:context", f"{name}.inputs:context"),
        ]
        values += [
            (f"{name}.inputs:topicName", topic),
            (f"{name}.inputs:frameId", frame_of(camera.prim)),
        ]
        if stream is not None:
            values.append((f"{name}.inputs:type", stream))
    h264 = camera.record.h264
    for cs in compressed_streams(camera):
        name = COMPRESSED[(cs.stream, cs.format)][0]
        nodes.append((name, "srr.CompressedCameraHelper"))
        bc.annotate(path, name, where, topicName=f"record.{cs.stream}")
        connect += [
            ("CreateRenderProduct.outputs:execOut", f"{name}.inputs:execIn"),
            ("CreateRenderProduct.outputs:renderProductPath",
             f"{name}.inputs:renderProductPath"),
            ("ROS2Context.outputs:context", f"{name}.inputs:context"),
        ]
        values += [
            (f"{name}.inputs:topicName", cs.topic.lstrip("/")),
            (f"{name}.inputs:frameId", frame_of(camera.prim)),
            (f"{name}.inputs:type", cs.stream),
            (f"{name}.inputs:format", cs.format),
            (f"{name}.inputs:fps", bc.scenario.physics.tick_hz
             / gate_step(bc.scenario.physics.tick_hz, camera.fps)),
        ]
        if cs.format == "h264":
            values += h264_values(name, h264)
        if cs.format == "jpeg":
            values.append((f"{name}.inputs:jpegQscale", camera.record.jpeg_qscale))
    Controller.edit(fresh_graph(path), {
        keys.CREATE_NODES: nodes,
        keys.CONNECT: connect,
        keys.SET_VALUES: values,
    })
    return path


def h264_values(node: str, h264: H264Spec) -> list[tuple[str, Any]]:
    """SET_VALUES of an encoding node's encoder inputs from an ``h264`` block."""
    return [
        (f"{node}.inputs:encoder", h264.encoder),
        (f"{node}.inputs:keyframeInterval", h264.keyframe_interval),
        (f"{node}.inputs:crf", h264.crf),
        (f"{node}.inputs:bitrateKbps", h264.bitrate_kbps or 0),
        (f"{node}.inputs:threads", h264.threads),
        (f"{node}.inputs:preset", h264.preset or ""),
    ]
