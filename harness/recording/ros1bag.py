"""Record the bus as ROS 1: a ``.bag`` (rosbags' rosbag1 writer) or MCAP with the ``ros1``
profile.

:class:`Ros1Recorder` is the :class:`~harness.recording.recorder.Recorder` with the ROS 1 format:
each message is converted and serialized by :mod:`harness.serde.ros1` (Noetic definitions,
header ``seq`` per topic) on the caller's thread and written, in publication order, with the
simulation time as its time, into ``<bag_dir>/<name>.bag`` or ``<bag_dir>/<name>.mcap``.
Counts, bytes and digests are kept as for ROS 2, over the ROS 1 bytes.

* ``.bag`` (format 2.0): one connection per topic with its type (``sensor_msgs/Image``), MD5
  sum, full message definition, ``callerid`` ``/srr`` and ``latching`` 1 for transient-local
  topics (``/tf_static``), 0 otherwise. Chunks close at ``chunk_mb`` or when they span
  ``chunk_s`` of simulated time and are flushed then; ``compression: lz4`` compresses them.
  The index is written when the bag closes: a bag cut short has none (ROS 1's
  ``rosbag reindex`` rebuilds it; ``srr recover`` handles MCAP only).
* MCAP (``ros1`` profile): ``ros1msg`` schemas named ``pkg/Type`` holding the same
  definitions, ``ros1`` message encoding, channel metadata ``callerid`` and ``latching``
  (``true``/``false``), written by the same bounded-chunk writer as ROS 2 bags (so
  ``chunk_mb``, ``chunk_s``, ``fsync`` and ``compression`` apply alike). No
  ``metadata.yaml``: it is not a rosbag2 bag.

Static TF as ROS 1's ``tf2_ros::StaticTransformBroadcaster`` sends it: every message of a
latched ``tf2_msgs/TFMessage`` topic named ``tf_static`` (``/tf_static``,
``/<ns>/tf_static``) is written holding every transform sent on that topic so far
(:class:`StaticTfUnion`), because ``rosbag play`` re-latches only the last message of a
latched connection: a subscriber that joins late still gets the whole static tree. The bus
and its subscribers keep the messages as published; only the recorded bytes (and so the
topic's digest) carry the union. ROS 2 output keeps each message as published (its readers
get every one, transient local).
"""

from __future__ import annotations

import os
from collections.abc import Collection
from pathlib import Path
from typing import Any, Literal

from rosbags.rosbag1 import Writer as Rosbag1Writer
from rosbags.typesys.msg import normalize_msgtype

from harness.bus.bus import Envelope, Qos, resolved
from harness.bus.endpoints import is_static_tf_topic
from harness.recording.bagfile import ChunkPolicy, McapBagWriter, TopicMeta
from harness.recording.recorder import Recorder, TopicState
from harness.serde.messages import tf_message
from harness.serde.ros1 import (
    Ros1Encoder,
    deserialize_ros1,
    msgdef,
    ros1_name,
    ros1_type,
    ros1_typestore,
    to_ros2,
)

__all__ = ["CALLERID", "Ros1Recorder", "StaticTfUnion", "accumulates_static_tf", "ros1_file"]

CALLERID = "/srr"
Ros1Format = Literal["bag", "mcap"]
TF_MESSAGE = "tf2_msgs/msg/TFMessage"


def accumulates_static_tf(topic: str, msgtype: str, latched: bool) -> bool:
    """Whether ROS 1 output writes ``topic`` (bus type ``msgtype``) as a static TF
    broadcaster sends it, each message holding every transform sent so far
    (:class:`StaticTfUnion`): a latched ``tf2_msgs/msg/TFMessage`` topic named ``tf_static``.

    Only ``tf_static`` topics: tf2 (and srr's ``tf_tree`` gate) take the transforms of any
    other TF topic as dynamic, so sending one again, with its old stamp, would repeat it (a
    latched ``/tf``, from a ``staticPublisher`` on ``/tf``, is written as published)."""
    return latched and msgtype == TF_MESSAGE and is_static_tf_topic(topic)


class StaticTfUnion:
    """The static transforms sent on one topic so far, as ROS 1's
    ``tf2_ros::StaticTransformBroadcaster`` keeps them: by child frame, a new transform for a
    child frame replacing the one before it in its place, new child frames after the rest
    (the order stays the order in which each child frame was first sent)."""

    def __init__(self) -> None:
        self._by_child: dict[str, Any] = {}

    def add(self, msg: Any) -> None:
        """Take the transforms of ``msg`` (a ROS 2 ``tf2_msgs/msg/TFMessage``)."""
        by_child = self._by_child
        for tf in msg.transforms:
            by_child[tf.child_frame_id] = tf  # an existing key keeps its place

    def message(self) -> Any:
        """A ROS 2 ``tf2_msgs/msg/TFMessage`` of every transform held, in their order."""
        return tf_message(list(self._by_child.values()))


def ros1_file(bag_dir: Path, fmt: Ros1Format) -> Path:
    """Where a ROS 1 recording of ``bag_dir`` lives: ``<bag_dir>/<name>.bag`` or ``.mcap``."""
    return Path(bag_dir) / f"{Path(bag_dir).name}.{fmt}"


class _BagWriter:
    """rosbags' rosbag1 writer behind the recorder's writer interface, closing chunks at
    the policy's size or span (rosbags closes them at its size threshold only)."""

    def __init__(self, path: Path, policy: ChunkPolicy) -> None:
        if policy.compression not in ("none", "lz4"):
            raise ValueError(f"a ROS 1 bag cannot compress with {policy.compression}")
        self.path = path
        self.policy = policy
        self._bag = Rosbag1Writer(path)
        self._bag.chunk_threshold = max(1, policy.max_bytes)
        if policy.compression == "lz4":
            self._bag.set_compression(Rosbag1Writer.CompressionFormat.LZ4)
        self._bag.open()
        self._conns: list[Any] = []
        self._chunk_start: int | None = None
        self._sync()

    def add_topic(self, topic: str, msgtype: str, latched: bool) -> int:
        self._conns.append(self._bag.add_connection(
            topic, normalize_msgtype(msgtype), typestore=ros1_typestore(), callerid=CALLERID,
            latching=int(latched)))
        return len(self._conns) - 1

    def write(self, channel: int, log_time: int, data: bytes) -> None:
        start = self._chunk_start
        if start is not None and log_time - start >= self.policy.max_span_ns:
            self._bag.write_chunk(self._bag.chunks[-1])
            self._chunk_closed()
        if self._chunk_start is None:
            self._chunk_start = log_time
        chunks = len(self._bag.chunks)
        self._bag.write(self._conns[channel], log_time, data)
        if len(self._bag.chunks) != chunks:  # rosbags closed it at its size threshold
            self._chunk_closed()

    def _chunk_closed(self) -> None:
        self._chunk_start = None
        self._sync()

    def _sync(self) -> None:
        bio = self._bag.bio
        assert bio is not None
        bio.flush()
        if self.policy.fsync:
            os.fsync(bio.fileno())

    def finish(self) -> None:
        self._bag.close()

    def abort(self) -> None:
        if self._bag.bio is not None:
            self._bag.bio.close()


class Ros1Recorder(Recorder):
    """Writes the bus as ROS 1 into ``bag_dir`` (see the module docstring); ``fmt``:
    ``bag`` or ``mcap``."""

    _defer_ok = False  # a deferred image is built here and converted, like any message
    _recorded_encoding = "ros1"  # a replayed ROS 1 recording's bytes are recorded as they are

    def __init__(self, bag_dir: Path, fmt: Ros1Format, *, queue_size: int = 256,
                 chunks: ChunkPolicy | None = None, unrecorded: Collection[str] = ()) -> None:
        super().__init__(bag_dir, queue_size=queue_size, chunks=chunks, unrecorded=unrecorded)
        self.format: Ros1Format = fmt
        self._encoder = Ros1Encoder()
        # topic -> its static transforms so far (accumulates_static_tf); caller's thread
        self._static_tf: dict[str, StaticTfUnion] = {}

    @property
    def path(self) -> Path:
        """The recording's file."""
        return ros1_file(self.bag_dir, self.format)

    def _open_writer(self) -> Any:
        if self.format == "bag":
            return _BagWriter(self.path, self.chunks)
        return McapBagWriter(self.path, self.chunks, profile="ros1")

    def write(self, env: Envelope) -> None:
        """Record one message (see :meth:`Recorder.write`). A message of a static TF topic
        that comes as ROS 1 bytes (a replayed ROS 1 recording, whose messages already hold
        their union) is written as it is, and its transforms join the topic's union, so a
        message converted after it still carries them."""
        super().write(env)
        union = self._static_tf.get(env.topic)
        if union is not None and env.raw is not None and env.encoding == "ros1":
            msg = env.msg  # a replay decodes a latched topic's messages as it publishes them
            if msg is None:
                name = ros1_type(env.msgtype)
                msg = to_ros2(deserialize_ros1(env.raw, name), name)
            union.add(msg)

    __call__ = write

    def _first_of(self, env: Envelope) -> TopicState | None:
        st = super()._first_of(env)
        if st is not None and accumulates_static_tf(env.topic, env.msgtype,
                                                    st.qos.durability == "transient_local"):
            self._static_tf[env.topic] = StaticTfUnion()
        return st

    def _recorded_type(self, msgtype: str) -> str:
        return ros1_name(msgtype)

    def _serialize(self, env: Envelope) -> bytes:
        if env.raw is not None and env.encoding == "ros1":  # a replayed ROS 1 recording's
            return env.raw
        msg = resolved(env.msg)  # (CDR bytes: built)
        union = self._static_tf.get(env.topic)
        if union is not None:
            union.add(msg)
            msg = union.message()
        return self._encoder.encode(env.topic, env.msgtype, msg)

    def _add_topic(self, writer: Any, topic: str, msgtype: str, qos: Qos) -> int:
        latched = qos.durability == "transient_local"
        if isinstance(writer, _BagWriter):
            return writer.add_topic(topic, msgtype, latched)
        text, _md5 = msgdef(msgtype)
        meta = (("callerid", CALLERID), ("latching", "true" if latched else "false"))
        return int(writer.add_topic(TopicMeta(
            topic, msgtype, text.encode(), "", schema_encoding="ros1msg",
            serialization_format="ros1", channel_metadata=meta)))

    def _finish(self, writer: Any) -> None:
        if isinstance(writer, _BagWriter):
            writer.finish()
        else:
            writer.finish(None)
