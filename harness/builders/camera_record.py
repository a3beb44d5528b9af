"""A camera's ``record`` block: its compressed topics and the helper nodes that publish them,
for fixed cameras (``cameras:``, :mod:`harness.builders.cameras`) and robot-mounted ones
(``robots[].sensors.camera``, :mod:`harness.builders.robot_camera`) alike.

A camera's raw image topics (rgb and, where it has one, depth) each get a
``CompressedCameraHelper`` per compressed format (:data:`COMPRESSED`): ``<rgb topic>/h264``
(foxglove_msgs/CompressedVideo), ``<rgb topic>/compressed`` (jpeg or png) and ``<depth
topic>/compressed`` (16-bit PNG millimetres), in the namespace of the raw topics. A raw
stream that ``record`` leaves out is still published (the systems under test read it in the
run) but not recorded: :func:`unrecorded_topics`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from harness.builders.base import BuildContext, GraphEdits, gate_step, render_product_helper
from harness.bus import resolve_topic
from harness.graph.nodes.ros_bridge import frame_of
from harness.graph.nodes.video import COMPRESSED_FORMATS
from harness.scenario import CameraRecordSpec, CameraSpec, H264Spec, RobotSpec, Scenario

__all__ = ["COMPRESSED", "CompressedStream", "RecordedCamera", "compressed_helpers",
           "compressed_streams", "fixed_camera", "h264_values", "recorded_cameras",
           "robot_camera", "unrecorded_topics"]

#: (stream, format) → (node name, topic suffix after the raw topic).
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


@dataclass(frozen=True)
class RecordedCamera:
    """A camera whose graph srr builds, as its ``record`` block sees it: ``raw`` maps each of
    its image streams (``rgb``, ``depth``) to its raw topic, relative to ``namespace``;
    ``field`` is the camera's block (``cameras[0]``, ``robots[1].sensors.camera``)."""

    name: str
    field: str
    record: CameraRecordSpec
    raw: Mapping[str, str]
    namespace: str
    frame_id: str
    fps: float


def fixed_camera(scenario: Scenario, camera: CameraSpec) -> RecordedCamera:
    """A ``cameras:`` entry: raw topics ``<cam>_rgb`` / ``<cam>_depth`` (those it outputs)."""
    return RecordedCamera(
        camera.name, f"cameras[{scenario.cameras.index(camera)}]", camera.record,
        {s: f"{camera.name}_{s}" for s in ("rgb", "depth") if s in camera.outputs}, "",
        frame_of(camera.prim), camera.fps)


def robot_camera(scenario: Scenario, robot: RobotSpec) -> RecordedCamera | None:
    """A robot's ``sensors.camera`` (None: none, disabled or without srr's graph): raw
    topics ``topic`` / ``depth_topic`` in the robot's namespace."""
    spec = robot.sensors.camera
    if spec is None or not spec.enabled or not spec.graph:
        return None
    raw = {"rgb": spec.topic}
    if spec.depth_topic:
        raw["depth"] = spec.depth_topic
    return RecordedCamera(robot.name,
                          f"robots[{scenario.robot_index(robot.name)}].sensors.camera",
                          spec.record, raw, robot.ns, robot.frame(spec.frame_id), spec.fps)


def recorded_cameras(scenario: Scenario) -> list[RecordedCamera]:
    """Every enabled camera srr builds a graph for: the robots' cameras, then ``cameras:``."""
    out = [c for r in scenario.robots if r.enabled
           if (c := robot_camera(scenario, r)) is not None]
    out += [fixed_camera(scenario, c) for c in scenario.cameras
            if c.enabled and c.outputs]
    return out


def _formats(camera: RecordedCamera) -> list[tuple[str, tuple[str, ...]]]:
    rec = camera.record
    return [(s, f) for s, f in (("rgb", rec.rgb), ("depth", rec.depth)) if s in camera.raw]


def compressed_streams(camera: RecordedCamera) -> list[CompressedStream]:
    """The camera's compressed topics, from its ``record`` block."""
    out = []
    for stream, formats in _formats(camera):
        raw = camera.raw[stream]
        for fmt in formats:
            if fmt == "raw":
                continue
            out.append(CompressedStream(
                camera.name, stream, fmt,
                resolve_topic(raw + COMPRESSED[(stream, fmt)][1], camera.namespace),
                resolve_topic(raw, camera.namespace), COMPRESSED_FORMATS[(stream, fmt)]))
    return out


def unrecorded_topics(scenario: Scenario) -> set[str]:
    """Raw camera topics published but, by their camera's ``record``, not recorded."""
    return {resolve_topic(cam.raw[stream], cam.namespace)
            for cam in recorded_cameras(scenario)
            for stream, formats in _formats(cam) if "raw" not in formats}


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
