"""A camera's ``record`` block in a graph: the helper nodes that publish its compressed topics,
for fixed cameras (``cameras:``, :mod:`harness.builders.cameras`) and robot-mounted ones
(``robots[].sensors.camera``, :mod:`harness.builders.robot_camera`) alike.

Which topics those are is :mod:`harness.camera_topics` (pure, no graph): each gets one
``CompressedCameraHelper`` (:data:`COMPRESSED`). The names of that module are re-exported
here for the builders.
"""

from __future__ import annotations

from typing import Any

from harness.builders.base import BuildContext, GraphEdits, gate_step, render_product_helper
from harness.camera_topics import (
    TOPIC_SUFFIX,
    CompressedStream,
    RecordedCamera,
    compressed_streams,
    fixed_camera,
    recorded_cameras,
    robot_camera,
    unrecorded_topics,
)
from harness.scenario import H264Spec

__all__ = ["COMPRESSED", "CompressedStream", "RecordedCamera", "compressed_helpers",
           "compressed_streams", "fixed_camera", "h264_values", "recorded_cameras",
           "robot_camera", "unrecorded_topics"]

_NODE: dict[tuple[str, str], str] = {
    ("rgb", "h264"): "CameraHelperRgbH264",
    ("rgb", "jpeg"): "CameraHelperRgbJpeg",
    ("rgb", "png"): "CameraHelperRgbPng",
    ("depth", "png"): "CameraHelperDepthPng",
}
#: (stream, format) → (node name, topic suffix after the raw topic).
COMPRESSED: dict[tuple[str, str], tuple[str, str]] = {
    key: (node, TOPIC_SUFFIX[key]) for key, node in _NODE.items()}


def compressed_helpers(bc: BuildContext, path: str, camera: RecordedCamera) -> GraphEdits:
    """The ``CompressedCameraHelper`` nodes of ``camera``'s ``record`` block, fed by the
    ``CreateRenderProduct`` and ``ROS2Context`` of the camera graph at ``path`` (as
    (nodes, connections, values) to add to it)."""
    nodes: list[tuple[str, str]] = []
    connect: list[tuple[str, str]] = []
    values: list[tuple[str, Any]] = []
    tick_hz = bc.scenario.physics.tick_hz
    for cs in compressed_streams(camera):
        name, suffix = COMPRESSED[(cs.stream, cs.format)]
        nodes.append((name, "srr.CompressedCameraHelper"))
        bc.annotate(path, name, camera.field, topicName=f"record.{cs.stream}")
        connect += render_product_helper(name)
        values += [
            (f"{name}.inputs:topicName", camera.raw[cs.stream] + suffix),
            (f"{name}.inputs:frameId", camera.frame_id),
            (f"{name}.inputs:type", cs.stream),
            (f"{name}.inputs:format", cs.format),
            (f"{name}.inputs:fps", tick_hz / gate_step(tick_hz, camera.fps)),
        ]
        if camera.namespace:
            values.append((f"{name}.inputs:nodeNamespace", camera.namespace))
        if cs.format == "h264":
            values += h264_values(name, camera.record.h264)
        if cs.format == "jpeg":
            values.append((f"{name}.inputs:jpegQscale", camera.record.jpeg_qscale))
    return nodes, connect, values


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
