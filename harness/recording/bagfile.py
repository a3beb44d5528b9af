"""A rosbag2 bag (metadata version 9) on one MCAP file, written with the ``mcap`` library.

The file is what ``ros2 bag``, rosbags, Foxglove and the ``mcap`` tools read: header profile
``ros2``, one ``ros2msg`` schema per message type, channels with ``cdr`` encoding and the
offered QoS profiles (plus the type's RIHS01 hash) in their metadata, a ``rosbag2`` metadata
record, chunk and message indexes, statistics; and ``metadata.yaml`` beside it.

Crash safety: messages go into a chunk that is closed — compressed (not yet), CRC'd, written
and flushed to the operating system — as soon as it holds ``max_bytes`` or spans
``max_span_ns`` of log (simulation) time, whichever comes first. A killed process therefore
loses only the chunk being filled; ``harness.recording.recover`` rebuilds the index from the
complete chunks. The header is flushed on open, so even a run killed at once leaves a file
that says what it is. ``fsync`` (off by default) also forces each closed chunk to the disk,
which only matters for power loss: after SIGKILL the operating system still holds every
byte that was written.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from importlib.metadata import version
from pathlib import Path
from typing import IO, Any

import yaml
from mcap.writer import CompressionType

from harness import __version__, yamlio
from harness.atomic import write_text_atomic
from harness.recording.mcap_writer import McapWriter, Payload, payload_size

__all__ = [
    "MESSAGE_OVERHEAD",
    "ChunkPolicy",
    "McapBagWriter",
    "TopicMeta",
    "bag_metadata",
    "dump_metadata",
    "write_metadata",
]

# Bytes an MCAP file spends per message besides its payload: the Message record (opcode,
# length, channel id, sequence, log and publish time: 31 bytes) and its MessageIndex entry (16).
MESSAGE_OVERHEAD = 31 + 16
ROSBAG2_VERSION = 9


@dataclass(frozen=True)
class ChunkPolicy:
    """When a chunk is closed: at ``max_bytes`` of records (before compression) or when the
    next message would make it span ``max_span_ns`` of log time, whichever comes first;
    ``fsync`` each closed chunk; ``compression`` of each chunk (``none``, ``zstd``, ``lz4``:
    MCAP chunk compression, which every MCAP reader undoes; the messages are unchanged)."""

    max_bytes: int = 8_000_000
    max_span_ns: int = 1_000_000_000
    fsync: bool = False
    compression: str = "none"


_COMPRESSION = {"none": CompressionType.NONE, "zstd": CompressionType.ZSTD,
                "lz4": CompressionType.LZ4}


@dataclass(frozen=True)
class TopicMeta:
    """One topic as rosbag2 describes it (schema text, QoS as YAML, type hash)."""

    name: str
    msgtype: str
    schema: bytes  # the message definition (``ros2msg`` text)
    qos: str  # offered_qos_profiles as rosbag2 stores it in MCAP: a YAML list
    type_hash: str = ""  # RIHS01_...
    schema_encoding: str = "ros2msg"
    serialization_format: str = "cdr"
    # The channel's metadata, when not rosbag2's (QoS and type hash): the ros1 profile's
    # ``callerid`` and ``latching``.
    channel_metadata: tuple[tuple[str, str], ...] | None = None

    @property
    def qos_profiles(self) -> list[Any]:
        loaded = yamlio.load(self.qos) if self.qos else []
        return loaded if isinstance(loaded, list) else []


class McapBagWriter:
    """Writes one MCAP file of a rosbag2 bag in bounded chunks (see the module docstring).

    Not thread-safe: one thread calls :meth:`add_topic`, :meth:`write` and :meth:`finish`.
    """

    def __init__(self, path: Path, policy: ChunkPolicy = ChunkPolicy(), *,
                 profile: str = "ros2") -> None:
        self.path = Path(path)
        self.policy = policy
        self._max_span_ns, self._max_bytes = policy.max_span_ns, policy.max_bytes
        # Unbuffered: each closed chunk goes to the operating system in one writev, its large
        # payloads as they were handed over (see .mcap_writer).
        self._file: IO[bytes] = self.path.open("xb", buffering=0)
        # The bytes of the mcap library's Writer, cheaper per message and without copies (see
        # .mcap_writer); chunks are closed here, by close_chunk.
        self._mcap = McapWriter(self._file, _COMPRESSION[policy.compression])
        self._mcap.start(profile=profile,
                         library=f"srr-{__version__}; mcap-python-{version('mcap')}")
        self._schemas: dict[tuple[str, bytes], int] = {}
        self.topics: list[TopicMeta] = []
        self.chunks = 0
        self._chunk_bytes = 0
        self._chunk_start: int | None = None
        self._sync()  # the header is on disk before the first message

    def add_topic(self, topic: TopicMeta) -> int:
        """Register a topic (its schema once per type); returns its channel id."""
        key = (topic.msgtype, topic.schema)
        sid = self._schemas.get(key)
        if sid is None:
            sid = self._schemas[key] = self._mcap.register_schema(
                topic.msgtype, topic.schema_encoding, topic.schema)
            self._chunk_bytes += 32 + len(topic.msgtype) + len(topic.schema)
        meta = {"offered_qos_profiles": topic.qos}
        if topic.type_hash:
            meta["topic_type_hash"] = topic.type_hash
        if topic.channel_metadata is not None:
            meta = dict(topic.channel_metadata)
        cid = self._mcap.register_channel(topic.name, topic.serialization_format, sid, meta)
        self._chunk_bytes += 64 + len(topic.name) + len(topic.qos)
        self.topics.append(topic)
        assert cid == len(self.topics)
        return cid

    @property
    def counts(self) -> list[int]:
        """Messages written per topic, in the order of :attr:`topics`."""
        per_channel = self._mcap.message_counts()
        return [per_channel.get(cid, 0) for cid in range(1, len(self.topics) + 1)]

    @property
    def start_ns(self) -> int | None:
        """The smallest log time written (None: no message yet)."""
        span = self._mcap.message_span()
        return None if span is None else span[0]

    @property
    def end_ns(self) -> int | None:
        """The largest log time written (None: no message yet)."""
        span = self._mcap.message_span()
        return None if span is None else span[1]

    def write(self, channel: int, log_time: int, data: Payload) -> None:
        """Add one message; closes the chunk first if it would span too much log time, and
        after if it has grown past the size bound. Large buffers in ``data`` are written as
        they are when the chunk closes: they must not change after this call."""
        start = self._chunk_start
        if start is not None and log_time - start >= self._max_span_ns:
            self.close_chunk()
            start = None
        if start is None:
            self._chunk_start = log_time
        self._mcap.add_message(channel, log_time, data, log_time)
        self._chunk_bytes += MESSAGE_OVERHEAD + (payload_size(data) if isinstance(data, tuple)
                                                 else len(data))
        if self._chunk_bytes >= self._max_bytes:
            self.close_chunk()

    def close_chunk(self) -> None:
        """Write the chunk being filled (with its message indexes) and flush it."""
        if self._chunk_start is None:
            return
        self._mcap.flush()
        self.chunks += 1
        self._chunk_start = None
        self._chunk_bytes = 0
        self._sync()

    def finish(self, serialized_metadata: str | None) -> None:
        """Close the last chunk, write the ``rosbag2`` metadata record (unless None), the
        summary (schemas, channels, statistics, chunk indexes) and the footer, and close the
        file."""
        self.close_chunk()
        if serialized_metadata is not None:
            self._mcap.add_metadata("rosbag2", {"serialized_metadata": serialized_metadata})
        self._mcap.finish()
        self._file.flush()
        if self.policy.fsync:
            os.fsync(self._file.fileno())
        self._file.close()

    def abort(self) -> None:
        """Close the file as it is (no summary, no footer)."""
        self._file.close()

    def _sync(self) -> None:
        self._file.flush()
        if self.policy.fsync:
            os.fsync(self._file.fileno())


def bag_metadata(file_name: str, topics: Sequence[tuple[TopicMeta, int]],
                 start_ns: int | None, end_ns: int | None) -> dict[str, Any]:
    """The ``rosbag2_bagfile_information`` mapping of ``metadata.yaml`` (version 9), shaped as
    rosbag2 and rosbags write it; an empty bag starts at 2**63 - 1 as theirs do."""
    count = sum(n for _, n in topics)
    start = (2**63 - 1) if start_ns is None else start_ns
    duration = 0 if start_ns is None or end_ns is None else max(0, end_ns - start_ns)
    return {
        "version": ROSBAG2_VERSION,
        "storage_identifier": "mcap",
        "relative_file_paths": [file_name],
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": count,
        "topics_with_message_count": [
            {
                "topic_metadata": {
                    "name": t.name,
                    "type": t.msgtype,
                    "serialization_format": t.serialization_format,
                    "offered_qos_profiles": t.qos_profiles,
                    "type_description_hash": t.type_hash,
                },
                "message_count": n,
            }
            for t, n in topics
        ],
        "compression_format": "",
        "compression_mode": "",
        "files": [{
            "path": file_name,
            "starting_time": {"nanoseconds_since_epoch": start},
            "duration": {"nanoseconds": duration},
            "message_count": count,
        }],
        "custom_data": None,
        "ros_distro": "jazzy",
    }


def dump_metadata(info: dict[str, Any]) -> str:
    """YAML text of the ``rosbag2_bagfile_information`` mapping (as in the MCAP record)."""
    return str(yaml.safe_dump(info, default_flow_style=False, sort_keys=True)).strip()


def write_metadata(bag_dir: Path, info: dict[str, Any]) -> None:
    """Write ``<bag_dir>/metadata.yaml`` atomically."""
    write_text_atomic(Path(bag_dir) / "metadata.yaml", yaml.safe_dump(
        {"rosbag2_bagfile_information": info}, default_flow_style=False, sort_keys=True))
