"""Reading recorded bags back: topic table for ``srr inspect``, with clear errors."""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import yaml
import zstandard
from mcap.exceptions import McapError
from rosbags.rosbag2 import Reader
from rosbags.rosbag2.errors import ReaderError

from harness.errors import BagError, reason

__all__ = ["BAG_READ_ERRORS", "BagInfo", "BagTopic", "inspect_bag"]

#: What the bag readers (rosbags, mcap and the decompressors under them) raise on a damaged,
#: truncated or foreign file. Every reader in srr turns these into one BagError line.
BAG_READ_ERRORS: tuple[type[BaseException], ...] = (
    ReaderError, McapError, OSError, EOFError, struct.error, ValueError, KeyError, IndexError,
    TypeError, AttributeError, AssertionError, OverflowError, MemoryError,
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
    """Open a rosbag2 directory (or a run directory holding ``bag/``) and list its topics,
    counting messages by reading every record (so truncation is noticed)."""
    p = Path(path)
    if (p / "bag" / "metadata.yaml").exists():
        p = p / "bag"
    if not p.exists():
        raise BagError(f"{path}: no such bag directory")
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
            meta = yaml.safe_load((p / "metadata.yaml").read_text(encoding="utf-8"))
            storage = str(meta["rosbag2_bagfile_information"]["storage_identifier"])
            return BagInfo(p, storage,
                           sum(counts.values()), reader.start_time, reader.end_time,
                           tuple(sorted(topics, key=lambda t: t.name)))
    except BAG_READ_ERRORS as err:
        raise BagError(f"{path}: cannot read bag: {reason(err)}") from err
