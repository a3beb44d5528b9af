"""Read back any recording srr writes, ROS 2 or ROS 1, behind one small interface.

* a rosbag2 directory (``metadata.yaml`` + one MCAP file of CDR messages): rosbags' rosbag2
  reader;
* a ROS 1 ``.bag``: rosbags' rosbag1 reader;
* a plain MCAP file, ``ros2`` or ``ros1`` profile (a ROS 1 run's ``bag/bag.mcap``, a
  baseline's reference recording): through its chunk and message indexes
  (:class:`~harness.bus.mcapread.McapIndex`), in file order. :func:`open_indexed` reads a
  rosbag2 directory's one finished MCAP file so too (what scoring and the report's images
  read: only the payloads they want leave the disk).

A run's ``bag/`` directory holds the first, or (a ROS 1 run) no ``metadata.yaml`` and one
``.bag`` or ``ros1``-profile ``.mcap`` file: :func:`ros1_recording` finds it.

Every :class:`Connection` names its type as the bus does (ROS 2's ``pkg/msg/Name``, with
``tf/tfMessage`` read as ``tf2_msgs/msg/TFMessage``) and as recorded; :attr:`Recording.encoding`
says how the payloads are serialized (``cdr`` or ``ros1``), and :meth:`Recording.decode` turns
one into the bus's ROS 2 message. Readers raise their own errors on damaged files (rosbags',
mcap's, ``OSError``...): callers turn them into one :class:`~harness.errors.BagError` line
with :data:`harness.bag.BAG_READ_ERRORS`.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Literal

from mcap.reader import make_reader
from rosbags.rosbag1 import Reader as Rosbag1Reader
from rosbags.rosbag2 import Reader as Rosbag2Reader
from rosbags.typesys.msg import denormalize_msgtype, normalize_msgtype

from harness import yamlio
from harness.bus.mcapread import McapIndex
from harness.bus.messages import TYPESTORE
from harness.bus.ros1 import deserialize_ros1, ros2_type, to_ros2

__all__ = ["Connection", "Encoding", "Recording", "mcap_profile", "open_indexed",
           "open_recording", "ros1_recording"]

Encoding = Literal["cdr", "ros1"]


@dataclass(frozen=True)
class Connection:
    """One topic of a recording. ``msgtype``: the bus's (ROS 2) name of its type;
    ``recorded_type``: the name in the file (``sensor_msgs/Image`` in a ROS 1 bag)."""

    id: int
    topic: str
    msgtype: str
    recorded_type: str
    latched: bool = False
    count: int | None = None  # from the file's index, where it has one
    schema: bytes = b""
    schema_encoding: str = ""
    metadata: dict[str, str] = field(default_factory=dict)


def mcap_profile(path: Path) -> str | None:
    """The header profile of an MCAP file (``ros1``, ``ros2``), None when it has none."""
    try:
        with Path(path).open("rb") as f:
            return str(make_reader(f).get_header().profile)
    except Exception:  # not MCAP, empty, unreadable: not a ROS 1 recording
        return None


def ros1_recording(bag_dir: Path) -> Path | None:
    """The ROS 1 recording in a run's ``bag/`` directory (no ``metadata.yaml``, one ``.bag``
    or one ``ros1``-profile ``.mcap`` file), or None."""
    p = Path(bag_dir)
    if not p.is_dir() or (p / "metadata.yaml").exists():
        return None
    bags = sorted(p.glob("*.bag"))
    if len(bags) == 1:
        return bags[0]
    mcaps = sorted(p.glob("*.mcap"))
    if not bags and len(mcaps) == 1 and mcap_profile(mcaps[0]) == "ros1":
        return mcaps[0]
    return None


class Recording:
    """An open recording: ``connections``, ``start_time`` (first log time), ``end_time``
    (after the last, as rosbags reports it), :meth:`messages` and :meth:`decode`."""

    kind: Literal["rosbag2", "bag", "mcap"]
    encoding: Encoding

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.connections: list[Connection] = []
        self.start_time = 2**63 - 1
        self.end_time = 0
        self.profile = ""

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        return None

    def messages(self, connections: Collection[Connection] = (), start: int | None = None,
                 stop: int | None = None) -> Iterator[tuple[Connection, int, bytes]]:
        """(connection, log time, payload) of ``connections`` (all when empty) with log times
        in [start, stop)."""
        raise NotImplementedError

    def scan(self, wanted: Collection[int]) -> Iterator[tuple[Connection, int, bytes | None]]:
        """Every message in file order: (connection, log time, payload), the payload certain
        only for the connection ids in ``wanted`` (an MCAP file leaves the others unread:
        None). For a reader that needs every topic's log times but few topics' payloads."""
        return self.messages()

    def decode(self, raw: bytes, conn: Connection) -> Any:
        """The bus's (ROS 2) message for one payload of ``conn``."""
        if self.encoding == "cdr":
            return TYPESTORE.deserialize_cdr(raw, conn.msgtype)
        return to_ros2(deserialize_ros1(raw, conn.recorded_type), conn.recorded_type)


class _Rosbags(Recording):
    """A recording read through one of rosbags' readers (``_reader``, with ``_raw``:
    connection id → rosbags' connection); subclasses say how one of its connections reads as
    ours (:meth:`_connection`)."""

    _open: ClassVar[Any]  # rosbags' Reader class

    def __init__(self, path: Path) -> None:
        super().__init__(path)
        self.profile = "ros2" if self.encoding == "cdr" else "ros1"
        self._reader = self._open(path)
        self._reader.open()
        self._raw = {c.id: c for c in self._reader.connections}
        self.connections = [self._connection(c) for c in self._reader.connections]
        self._by_id = {c.id: c for c in self.connections}
        if self._reader.message_count:  # else rosbags' (max, 0), as ours
            self.start_time, self.end_time = self._reader.start_time, self._reader.end_time

    def _connection(self, c: Any) -> Connection:
        raise NotImplementedError

    def close(self) -> None:
        self._reader.close()

    def messages(self, connections: Collection[Connection] = (), start: int | None = None,
                 stop: int | None = None) -> Iterator[tuple[Connection, int, bytes]]:
        raw = [self._raw[c.id] for c in connections]
        by_id = self._by_id
        for conn, t, data in self._reader.messages(connections=raw, start=start, stop=stop):
            yield by_id[conn.id], t, data


class _Rosbag2(_Rosbags):
    kind = "rosbag2"
    encoding: Encoding = "cdr"
    _open = Rosbag2Reader

    def _connection(self, c: Any) -> Connection:
        qos = getattr(c.ext, "offered_qos_profiles", []) or []
        latched = bool(qos) and qos[0].durability.name.lower() == "transient_local"
        return Connection(c.id, c.topic, c.msgtype, c.msgtype, latched, c.msgcount)


class _Rosbag1(_Rosbags):
    kind = "bag"
    encoding: Encoding = "ros1"
    _open = Rosbag1Reader

    def _connection(self, c: Any) -> Connection:
        latching = getattr(c.ext, "latching", None)
        return Connection(
            c.id, c.topic, ros2_type(c.msgtype), str(denormalize_msgtype(c.msgtype)),
            bool(latching), c.msgcount, c.msgdef.data.encode(), "ros1msg",
            {"md5sum": c.digest, "callerid": str(getattr(c.ext, "callerid", "") or ""),
             "latching": "true" if latching else "false"})


class _Mcap(Recording):
    """A finished MCAP file, ``ros2`` or ``ros1`` profile, read through its index
    (:class:`~harness.bus.mcapread.McapIndex`)."""

    kind = "mcap"

    def __init__(self, path: Path) -> None:
        super().__init__(path)
        self._index = index = McapIndex(self.path)
        self.profile, summary = index.profile, index.summary
        encodings = {c.message_encoding for c in summary.channels.values()}
        self.encoding = "ros1" if encodings == {"ros1"} or (
            not encodings and self.profile == "ros1") else "cdr"
        for c in summary.channels.values():
            schema = summary.schemas.get(c.schema_id)
            name = schema.name if schema is not None else ""
            latched = (c.metadata.get("latching") in ("true", "1")
                       or "transient_local" in c.metadata.get("offered_qos_profiles", ""))
            count = None if summary.statistics is None else \
                summary.statistics.channel_message_counts.get(c.id)
            bus_type = ros2_type(normalize_msgtype(name)) if self.encoding == "ros1" else name
            self.connections.append(Connection(
                c.id, c.topic, bus_type, name, latched, count,
                schema.data if schema is not None else b"",
                schema.encoding if schema is not None else "", dict(c.metadata)))
        self._by_id = {c.id: c for c in self.connections}
        if summary.statistics is not None and summary.statistics.message_count:
            self.start_time = summary.statistics.message_start_time
            # exclusive, as rosbags reports a bag's end: after the last message
            self.end_time = summary.statistics.message_end_time + 1

    def messages(self, connections: Collection[Connection] = (), start: int | None = None,
                 stop: int | None = None) -> Iterator[tuple[Connection, int, bytes]]:
        return self._index.messages(self._by_id, [c.id for c in connections], start, stop)

    def scan(self, wanted: Collection[int]) -> Iterator[tuple[Connection, int, bytes | None]]:
        return self._index.scan(self._by_id, wanted)


def open_recording(path: str | Path) -> Recording:
    """Open a rosbag2 directory, a ``.bag`` or ``.mcap`` file, or a run's ``bag/`` directory
    holding a ROS 1 recording. Raises the readers' own errors (see the module docstring);
    ``FileNotFoundError`` when ``path`` holds none of these."""
    p = Path(path)
    if p.is_dir():
        if (p / "metadata.yaml").exists():
            return _Rosbag2(p)
        found = ros1_recording(p)
        if found is None:
            raise FileNotFoundError(f"{p}: metadata.yaml: missing (not a rosbag2 directory)")
        p = found
    if p.suffix == ".bag":
        return _Rosbag1(p)
    return _Mcap(p)


def open_indexed(path: str | Path) -> Recording:
    """:func:`open_recording`, but a rosbag2 directory whose ``metadata.yaml`` names one MCAP
    file, finished, is read through that file's index as a ``.mcap`` file is: the same
    messages, without rosbags' parsing of ``metadata.yaml`` (~0.2 s of ruamel), and
    :meth:`Recording.scan` leaves unwanted payloads on disk. Any other directory, and one
    whose file is damaged, opens with :func:`open_recording` (rosbags says what is wrong)."""
    p = Path(path)
    if p.is_dir() and (p / "metadata.yaml").exists():
        try:
            info = yamlio.load((p / "metadata.yaml").read_text(encoding="utf-8"))[
                "rosbag2_bagfile_information"]
            files = [p / str(f) for f in info["relative_file_paths"]]
            if len(files) == 1 and files[0].suffix == ".mcap" and files[0].is_file():
                return _Mcap(files[0])
        except Exception:  # unreadable here: rosbags' reader says why
            pass
    return open_recording(p)
