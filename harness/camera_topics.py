"""What a camera's ``record`` block records: its compressed topics, their message types and the
raw topics it leaves out — for fixed cameras (``cameras:``) and robot-mounted ones
(``robots[].sensors.camera``) alike. Pure functions of the scenario: the graph builders
(:mod:`harness.builders.camera_record`) add the nodes that publish these topics, and scoring,
the report and replays read the same topics without building a graph.

A camera's raw image topics (rgb and, where it has one, depth) each get one compressed topic
per format: ``<rgb topic>/h264`` (foxglove_msgs/CompressedVideo), ``<rgb topic>/compressed``
(jpeg or png) and ``<depth topic>/compressed`` (16-bit PNG millimetres), in the namespace of
the raw topics. A raw stream that ``record`` leaves out is still published (the systems under
test read it in the run) but not recorded: :func:`unrecorded_topics`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from harness.bus.names import resolve_topic
from harness.scenario import CameraRecordSpec, CameraSpec, RobotSpec, Scenario
from harness.scenario.prims import frame_of

__all__ = ["COMPRESSED_FORMATS", "TOPIC_SUFFIX", "CompressedStream", "RecordedCamera",
           "compressed_streams", "fixed_camera", "record_formats", "recorded_cameras",
           "robot_camera", "unrecorded_topics"]

#: (``type``, ``format``) → message type.
COMPRESSED_FORMATS: dict[tuple[str, str], str] = {
    ("rgb", "h264"): "foxglove_msgs/msg/CompressedVideo",
    ("rgb", "jpeg"): "sensor_msgs/msg/CompressedImage",
    ("rgb", "png"): "sensor_msgs/msg/CompressedImage",
    ("depth", "png"): "sensor_msgs/msg/CompressedImage",
}

#: (stream, format) → the compressed topic's suffix after the raw topic.
TOPIC_SUFFIX: dict[tuple[str, str], str] = {
    ("rgb", "h264"): "/h264",
    ("rgb", "jpeg"): "/compressed",
    ("rgb", "png"): "/compressed",
    ("depth", "png"): "/compressed",
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


def record_formats(camera: RecordedCamera) -> list[tuple[str, tuple[str, ...]]]:
    """(stream, formats) of each image stream the camera has, from its ``record`` block."""
    rec = camera.record
    return [(s, f) for s, f in (("rgb", rec.rgb), ("depth", rec.depth)) if s in camera.raw]


def compressed_streams(camera: RecordedCamera) -> list[CompressedStream]:
    """The camera's compressed topics, from its ``record`` block."""
    out = []
    for stream, formats in record_formats(camera):
        raw = camera.raw[stream]
        for fmt in formats:
            if fmt == "raw":
                continue
            out.append(CompressedStream(
                camera.name, stream, fmt,
                resolve_topic(raw + TOPIC_SUFFIX[(stream, fmt)], camera.namespace),
                resolve_topic(raw, camera.namespace), COMPRESSED_FORMATS[(stream, fmt)]))
    return out


def unrecorded_topics(scenario: Scenario) -> set[str]:
    """Raw camera topics published but, by their camera's ``record``, not recorded."""
    return {resolve_topic(cam.raw[stream], cam.namespace)
            for cam in recorded_cameras(scenario)
            for stream, formats in record_formats(cam) if "raw" not in formats}
