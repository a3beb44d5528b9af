"""Reading recorded bags back: topic table for ``srr inspect``, with clear errors (a ROS 2
rosbag2 directory, or a ROS 1 recording: a ``.bag``, or an MCAP file with the ``ros1``
profile, alone or in a run's ``bag/`` directory)."""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import yaml
import zstandard
from mcap.exceptions import McapError
from rosbags.rosbag1 import ReaderError as Rosbag1ReaderError
from rosbags.rosbag2 import Reader
from rosbags.rosbag2.errors import ReaderError

from harness import yamlio
from harness.bus.bagread import open_recording, ros1_recording
from harness.errors import BagError, reason

__all__ = ["BAG_READ_ERRORS", "BagInfo", "BagTopic", "inspect_bag"]

#: What the bag readers (rosbags, mcap and the decompressors under them) raise on a damaged,
#: truncated or foreign file. Every reader in srr turns these into one BagError line.
BAG_READ_ERRORS: tuple[type[BaseException], ...] = (
    ReaderError, Rosbag1ReaderError, McapError, OSError, EOFError, struct.error, ValueError,
    KeyError, IndexError, TypeError, AttributeError, AssertionError, OverflowError, MemoryError,
    zstandard.ZstdError, RuntimeError, yaml.YAMLError)


@dataclass(frozen=True)
class BagTopic:
    name: str
    msgtype: str
    count: int
    durability: str


@dataclass(frozen=True)
class BagInfo:
    path: Path
    storage: str
    message_count: int
    start_ns: int
    end_ns: int
    topics: tuple[BagTopic, ...]


def inspect_bag(path: str | Path) -> BagInfo:
    """Open a rosbag2 directory (or a run directory holding ``bag/``, or a ROS 1 recording)
    and list its topics, counting messages by reading every record (so truncation is
    noticed). ``storage`` is ``mcap`` for ROS 2, ``rosbag1`` or ``mcap (ros1)`` for ROS 1."""
    p = Path(path)
    if (p / "bag" / "metadata.yaml").exists() or ros1_recording(p / "bag") is not None:
        p = p / "bag"
    if not p.exists():
        raise BagError(f"{path}: no such bag directory")
    ros1 = p if p.is_file() and p.suffix in (".bag", ".mcap") else ros1_recording(p)
    if ros1 is not None:
        return _inspect_ros1(path, ros1)
    if not (p / "metadata.yaml").exists():
        if any(p.glob("*.mcap")):
            raise BagError(f"{path}: metadata.yaml: missing (the recording did not finish; "
                           "`srr recover` rebuilds the bag)")
        raise BagError(f"{path}: metadata.yaml: missing (not a rosbag2 directory)")
    try:
        with Reader(p) as reader:
            counts: dict[str, int] = {}
            for conn, _, _ in reader.messages():
                counts[conn.topic] = counts.get(conn.topic, 0) + 1
            topics = []
            for conn in reader.connections:
                qos = getattr(conn.ext, "offered_qos_profiles", []) or []
                durability = qos[0].durability.name.lower() if qos else "volatile"
                topics.append(BagTopic(conn.topic, conn.msgtype, counts.get(conn.topic, 0),
                                       durability))
            meta = yamlio.load((p / "metadata.yaml").read_text(encoding="utf-8"))
            storage = str(meta["rosbag2_bagfile_information"]["storage_identifier"])
            return BagInfo(p, storage,
                           sum(counts.values()), reader.start_time, reader.end_time,
                           tuple(sorted(topics, key=lambda t: t.name)))
    except BAG_READ_ERRORS as err:
        raise BagError(f"{path}: cannot read bag: {reason(err)}") from err


def _inspect_ros1(shown: str | Path, file: Path) -> BagInfo:
    """:func:`inspect_bag` of a ROS 1 recording (or any plain MCAP file); types as recorded
    (``sensor_msgs/Image``), latched topics as ``transient_local``."""
    try:
        with open_recording(file) as rec:
            counts: dict[str, int] = {}
            for conn, _, _ in rec.messages():
                counts[conn.topic] = counts.get(conn.topic, 0) + 1
            topics = [BagTopic(c.topic, c.recorded_type, counts.get(c.topic, 0),
                               "transient_local" if c.latched else "volatile")
                      for c in rec.connections]
            storage = "rosbag1" if rec.kind == "bag" else f"mcap ({rec.profile})"
            return BagInfo(file, storage, sum(counts.values()), rec.start_time, rec.end_time,
                           tuple(sorted(topics, key=lambda t: t.name)))
    except BAG_READ_ERRORS as err:
        raise BagError(f"{shown}: cannot read bag: {reason(err)}") from err
