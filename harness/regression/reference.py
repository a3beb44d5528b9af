"""A baseline's reference recording: the blessed run's small, non-image topics in one MCAP.

Blessing writes ``baselines/<name>.mcap`` next to ``<name>.json``: ground truth
(``/gt/*/tf``), odometry, velocity commands, Bool states (``/safety/is_muted``), tracked
objects (MarkerArray), ``/clock`` and ``/tf_static`` — everything the report overlays as the
baseline's trajectories and time series — copied byte for byte with their schemas and log
times, in zstd-compressed chunks. Images, point clouds, scans, IMU and the dynamic ``/tf`` are
left out (they are the bulk and the overlays do not need them). It is a plain MCAP file:
Foxglove opens it, and :func:`harness.frames.load_frames` reads it like a bag. A run that
recorded ROS 1 gets a ``ros1``-profile reference (from its ``.bag`` or MCAP file) with the ROS 1
definitions and bytes as they are.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from mcap.writer import CompressionType, Writer

from harness.bus.endpoints import is_static_tf_topic
from harness.errors import reason
from harness.recording.errors import BagError
from harness.serde.ros1 import ros2_type

__all__ = ["KEPT_TYPES", "ReferenceInfo", "kept", "reference_path", "write_reference"]

KEPT_TYPES = frozenset({
    "rosgraph_msgs/msg/Clock", "nav_msgs/msg/Odometry", "geometry_msgs/msg/Twist",
    "std_msgs/msg/Bool", "visualization_msgs/msg/MarkerArray",
})


@dataclass(frozen=True)
class ReferenceInfo:
    path: Path
    bytes: int
    counts: dict[str, int]


def kept(topic: str, msgtype: str) -> bool:
    """Whether a topic goes into the reference recording (``msgtype`` as ROS 2 or ROS 1
    spells it)."""
    if "/msg/" not in msgtype:
        msgtype = ros2_type(msgtype)
    if msgtype == "tf2_msgs/msg/TFMessage":
        return topic.startswith("/gt/") or is_static_tf_topic(topic)
    return msgtype in KEPT_TYPES


def reference_path(baseline_json: Path) -> Path:
    """``baselines/<name>.mcap`` for ``baselines/<name>.json``."""
    return baseline_json.with_suffix(".mcap")


def write_reference(bag_dir: Path, path: Path) -> ReferenceInfo:
    """Copy the kept topics of the run's bag (rosbag2 directory with one MCAP, or a ROS 1
    run's ``.bag`` or ``ros1`` MCAP) to ``path``, atomically (a temporary file renamed into
    place)."""
    # imported here: the bag readers (rosbags, mcap's reader) are needed only when a run is
    # blessed, not by every importer of the regression layer
    from harness.recording.bagread import mcap_records, ros1_recording

    ros1 = ros1_recording(Path(bag_dir))
    if ros1 is not None and ros1.suffix == ".bag":
        return _reference_from_bag(ros1, path)
    mcaps = [ros1] if ros1 is not None else sorted(Path(bag_dir).glob("*.mcap"))
    if len(mcaps) != 1:
        raise BagError(f"{bag_dir}: expected one .mcap file to take the reference recording "
                       f"from, found {len(mcaps)}")
    tmp = path.with_name(path.name + ".tmp")
    counts: dict[str, int] = {}
    what = f"cannot write the reference recording {path}"
    try:
        with tmp.open("wb") as dst:
            writer = Writer(dst, compression=CompressionType.ZSTD, chunk_size=1 << 20)
            writer.start(profile="ros1" if ros1 is not None else "ros2",
                         library="srr reference recording")
            schemas: dict[int, int] = {}
            channels: dict[int, int] = {}
            for schema, channel, message in mcap_records(mcaps[0], what=what):
                if schema is None or not kept(channel.topic, schema.name):
                    continue
                if channel.id not in channels:
                    if schema.id not in schemas:
                        schemas[schema.id] = writer.register_schema(
                            schema.name, schema.encoding, schema.data)
                    channels[channel.id] = writer.register_channel(
                        channel.topic, channel.message_encoding, schemas[schema.id],
                        dict(channel.metadata))
                writer.add_message(channels[channel.id], message.log_time, message.data,
                                   message.publish_time, message.sequence)
                counts[channel.topic] = counts.get(channel.topic, 0) + 1
            writer.finish()  # type: ignore[no-untyped-call]  # mcap leaves it unannotated
        os.replace(tmp, path)
    except OSError as err:
        raise BagError(f"{mcaps[0]}: {what}: {reason(err)}") from err
    finally:
        tmp.unlink(missing_ok=True)
    return ReferenceInfo(path, path.stat().st_size, dict(sorted(counts.items())))


def _reference_from_bag(bag: Path, path: Path) -> ReferenceInfo:
    """:func:`write_reference` of a ROS 1 ``.bag``: the kept connections as ``ros1msg``
    schemas and ``ros1`` channels (callerid, latching), messages byte for byte."""
    from harness.recording.bagread import open_recording  # as in write_reference

    tmp = path.with_name(path.name + ".tmp")
    counts: dict[str, int] = {}
    what = f"cannot write the reference recording {path}"
    try:
        with open_recording(bag, what=what) as rec, tmp.open("wb") as dst:
            writer = Writer(dst, compression=CompressionType.ZSTD, chunk_size=1 << 20)
            writer.start(profile="ros1", library="srr reference recording")
            conns = [c for c in rec.connections if kept(c.topic, c.recorded_type)]
            schemas: dict[str, int] = {}
            channels: dict[int, int] = {}
            for c in conns:
                if c.recorded_type not in schemas:
                    schemas[c.recorded_type] = writer.register_schema(
                        c.recorded_type, "ros1msg", c.schema)
                channels[c.id] = writer.register_channel(
                    c.topic, "ros1", schemas[c.recorded_type],
                    {"callerid": c.metadata.get("callerid", ""),
                     "latching": "true" if c.latched else "false"})
            for conn, t, raw in rec.messages(conns) if conns else ():
                writer.add_message(channels[conn.id], t, raw, t, 0)
                counts[conn.topic] = counts.get(conn.topic, 0) + 1
            writer.finish()  # type: ignore[no-untyped-call]  # mcap leaves it unannotated
        os.replace(tmp, path)
    except OSError as err:
        raise BagError(f"{bag}: {what}: {reason(err)}") from err
    finally:
        tmp.unlink(missing_ok=True)
    return ReferenceInfo(path, path.stat().st_size, dict(sorted(counts.items())))
