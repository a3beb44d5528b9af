"""Reading recorded bags back: topic table for ``srr inspect``, with clear errors (a ROS 2
rosbag2 directory, or a ROS 1 recording: a ``.bag``, or an MCAP file with the ``ros1``
profile, alone or in a run's ``bag/`` directory). The recording is opened, and its read errors
translated, by :func:`harness.recording.bagread.open_recording`."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from harness import runlock, yamlio
from harness.recording.bagread import open_recording, reading, ros1_recording
from harness.recording.errors import BagError

__all__ = ["BagInfo", "BagTopic", "inspect_bag"]


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
    noticed). ``storage`` is ``mcap`` for ROS 2, ``rosbag1`` or ``mcap (ros1)`` for ROS 1;
    types as recorded (``sensor_msgs/Image`` in a ROS 1 recording), latched ROS 1 topics as
    ``transient_local``. Raises :class:`~harness.recording.errors.BagError`, and
    :class:`~harness.errors.RunInUseError` for a run still being written (its lock is held,
    :mod:`harness.runlock`), as every command that reads a run does."""
    p = Path(path)
    base = p.parent if p.is_file() else p
    for cand in (base, base.parent):  # a run directory, or its bag/, being written
        runlock.refuse_if_live(cand)
    if (p / "bag").is_dir() and not (p / "metadata.yaml").exists():
        p = p / "bag"  # a run directory: its recording, finished or not
    if not p.exists():
        raise BagError(f"{path}: no such bag directory")
    ros1 = p if p.is_file() and p.suffix in (".bag", ".mcap") else ros1_recording(p)
    if ros1 is None and not (p / "metadata.yaml").exists():
        if any(p.glob("*.mcap")):
            raise BagError(f"{path}: metadata.yaml: missing (the recording did not finish; "
                           "`srr recover` rebuilds the bag)")
        raise BagError(f"{path}: metadata.yaml: missing (not a rosbag2 directory)")
    with open_recording(p if ros1 is None else ros1, shown=path) as rec:
        counts: dict[str, int] = {}
        for conn, _, _ in rec.messages():
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
        topics = [BagTopic(c.topic, c.recorded_type, counts.get(c.topic, 0), c.durability)
                  for c in rec.connections]
        if rec.kind == "rosbag2":
            with reading(path):  # rosbags has read it: the key is there
                meta = yamlio.load((p / "metadata.yaml").read_text(encoding="utf-8"))
            storage = str(meta["rosbag2_bagfile_information"]["storage_identifier"])
        else:
            storage = "rosbag1" if rec.kind == "bag" else f"mcap ({rec.profile})"
        return BagInfo(rec.path, storage, sum(counts.values()), rec.start_time, rec.end_time,
                       tuple(sorted(topics, key=lambda t: t.name)))
