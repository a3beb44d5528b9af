"""Read back any recording srr writes, ROS 2 or ROS 1, behind one small interface.

* a rosbag2 directory (``metadata.yaml`` + one MCAP file of CDR messages): rosbags' rosbag2
  reader;
* a ROS 1 ``.bag``: rosbags' rosbag1 reader;
* a plain MCAP file, ``ros2`` or ``ros1`` profile (a ROS 1 run's ``bag/bag.mcap``, a
  baseline's reference recording): through its chunk and message indexes
  (:class:`~harness.recording.mcapread.McapIndex`), in file order. :func:`open_indexed` reads a
  rosbag2 directory's one finished MCAP file so too (what scoring and the report's images
  read: only the payloads they want leave the disk).

A run's ``bag/`` directory holds the first, or (a ROS 1 run) no ``metadata.yaml`` and one
``.bag`` or ``ros1``-profile ``.mcap`` file: :func:`ros1_recording` finds it.

Every :class:`Connection` names its type as the bus does (ROS 2's ``pkg/msg/Name``, with
``tf/tfMessage`` read as ``tf2_msgs/msg/TFMessage``) and as recorded; :attr:`Recording.encoding`
says how the payloads are serialized (``cdr`` or ``ros1``), and :meth:`Recording.decode` turns
one into the bus's ROS 2 message.

This module is the one place where a recording's read errors are translated: what the readers
raise on a damaged, truncated or foreign file (:data:`READ_ERRORS`: rosbags', mcap's, the
decompressors', ``struct.error``, ``ValueError``, ``OSError``...) becomes one
:class:`~harness.recording.errors.BagReadError` line naming the file, raised ``from`` the
reader's error,
when the recording is opened and while its messages are read (:func:`mcap_records` for a
byte-for-byte copy of an MCAP file's records). A programming error (``TypeError``,
``AttributeError``, ``AssertionError``...) is not translated: it is a bug, with its traceback.
The few library behaviours that raise a broader exception on bad bytes are caught around that
library call alone (lz4, rosbags' ROS 1 and MCAP readers, mcap's reader:
:func:`harness.recording.mcapread.guarded`).
"""

from __future__ import annotations

import struct
from collections.abc import Collection, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass, field
from pathlib import Path, PurePath
from typing import Any, ClassVar, Literal

import yaml
import zstandard
from mcap.exceptions import EndOfFile, InvalidMagic, McapError, RecordLengthLimitExceeded
from mcap.reader import make_reader
from mcap.records import Channel, Message, Schema
from rosbags.rosbag1 import Reader as Rosbag1Reader
from rosbags.rosbag1 import ReaderError as Rosbag1ReaderError
from rosbags.rosbag2 import Reader as Rosbag2Reader
from rosbags.rosbag2.errors import ReaderError as Rosbag2ReaderError
from rosbags.serde import SerdeError
from rosbags.typesys.msg import denormalize_msgtype, normalize_msgtype

from harness import yamlio
from harness.errors import reason
from harness.recording.errors import BagReadError
from harness.recording.mcapread import McapIndex, check_index, check_start, guarded, lz4_failure
from harness.serde.messages import TYPESTORE
from harness.serde.ros1 import Ros1TypeError, deserialize_ros1, ros2_type, to_ros2

try:  # rosbags decompresses zstd with the standard library's module (Python 3.14) or its backport
    from compression.zstd import ZstdError as _StdZstdError  # type: ignore[import-not-found,unused-ignore]
except ImportError:
    from backports.zstd import ZstdError as _StdZstdError

__all__ = ["DATA_ERRORS", "DECODE_ERRORS", "READ_ERRORS", "Connection", "Encoding",
           "Recording", "deserialize", "mcap_profile", "mcap_records", "open_indexed",
           "open_recording", "reading", "ros1_recording", "rosbag2_metadata"]

Encoding = Literal["cdr", "ros1"]

#: What the parsers under a recording raise on bytes that do not parse (damaged, truncated,
#: foreign): rosbags' and mcap's own errors, ``struct.error`` and ``EOFError`` on a short
#: read, ``ValueError`` (among them ``UnicodeDecodeError`` and srr's MCAP index reader's),
#: the zstd decompressors' errors, ``OverflowError`` and ``MemoryError`` for a length field
#: larger than memory, a YAML error in ``metadata.yaml``. Not ``OSError``: an I/O error is not
#: a damaged byte (``srr recover`` must not cut a file where the disk failed).
DATA_ERRORS: tuple[type[Exception], ...] = (
    Rosbag2ReaderError, Rosbag1ReaderError, McapError, struct.error, EOFError, ValueError,
    zstandard.ZstdError, _StdZstdError, OverflowError, MemoryError, yaml.YAMLError)

#: :data:`DATA_ERRORS` and ``OSError`` (a file missing, unreadable, or a directory): every
#: error a reader raises for the file rather than for a bug, translated into
#: :class:`~harness.recording.errors.BagReadError`.
READ_ERRORS: tuple[type[Exception], ...] = (*DATA_ERRORS, OSError)

#: What decoding one recorded payload (:func:`deserialize`) raises when its bytes or its type
#: do not decode.
DECODE_ERRORS: tuple[type[Exception], ...] = (SerdeError, Ros1TypeError, *DATA_ERRORS)


#: What the mcap reader raises for a file that ends early (a run killed mid-write).
_CUT: tuple[type[Exception], ...] = (InvalidMagic, RecordLengthLimitExceeded, EndOfFile)
_CUT_WORDS = ("end magic is invalid", "unexpected end", "exceeds limit")


@contextmanager
def reading(file: object, what: str = "cannot read bag") -> Iterator[None]:
    """Translate :data:`READ_ERRORS` raised inside into one
    :class:`~harness.recording.errors.BagReadError` line, ``<file>: <what>: <reason>``."""
    try:
        yield
    except READ_ERRORS as err:
        said = reason(err)
        if isinstance(err, _CUT) or any(w in str(err).lower() for w in _CUT_WORDS):
            # what a file cut short reads as, mid-record or at its end (rosbags' own reader
            # says it in words)
            said = f"the file is cut short or damaged ({said}); `srr recover` rebuilds a " \
                   "bag cut short from its complete chunks"
        raise BagReadError(file, what, said) from err


_META = "not a rosbag2 metadata file"
# rosbag2_bagfile_information: key → (type, what it must be, required); what rosbags reads
_INFO_FIELDS: dict[str, tuple[type | tuple[type, ...], str, bool]] = {
    "version": (int, "an integer", True),
    "storage_identifier": (str, "a string", True),
    "relative_file_paths": (list, "a list", True),
    "compression_format": ((str, type(None)), "a string", False),
    "compression_mode": ((str, type(None)), "a string", False),
    "message_count": (int, "an integer", True),
    "duration": (dict, "a mapping", True),
    "starting_time": (dict, "a mapping", True),
    "topics_with_message_count": (list, "a list", True),
    "files": (list, "a list", False),
}
_TOPIC_FIELDS: dict[str, tuple[type | tuple[type, ...], str, bool]] = {
    "name": (str, "a string", True),
    "type": (str, "a string", True),
    "serialization_format": (str, "a string", True),
    "offered_qos_profiles": ((list, str), "a list", False),
    "type_description_hash": (str, "a string", False),
}


def _fields(node: dict[str, Any], where: str,
            fields: dict[str, tuple[type | tuple[type, ...], str, bool]]) -> str | None:
    """The first of ``fields`` that ``node`` lacks or holds as another type, said as
    ``<where>.<key>: ...``; None when all are right."""
    for key, (kind, said, required) in fields.items():
        if key not in node:
            if required:
                return f"{where}.{key}: missing"
            continue
        value = node[key]
        if not isinstance(value, kind) or (isinstance(value, bool) and kind is int):
            return f"{where}.{key}: {value!r} is not {said}"
    return None


def rosbag2_metadata(bag_dir: Path) -> dict[str, Any]:
    """The ``rosbag2_bagfile_information`` mapping of a rosbag2 directory's ``metadata.yaml``,
    each field rosbags reads checked for its type first: a :class:`BagReadError` naming the
    file and the field (``.../metadata.yaml: not a rosbag2 metadata file:
    rosbag2_bagfile_information.version: 'nine' is not an integer``), not rosbags'
    ``Invalid bag metadata: '>' not supported between instances of 'str' and 'int'``."""
    file = Path(bag_dir) / "metadata.yaml"
    with reading(file, _META):
        meta = yamlio.load(file.read_text(encoding="utf-8"))
    top = "rosbag2_bagfile_information"
    info = meta.get(top) if isinstance(meta, dict) else None
    problem = f"{top}: missing" if not isinstance(meta, dict) or top not in meta else \
        f"{top}: {info!r} is not a mapping" if not isinstance(info, dict) else \
        _fields(info, top, _INFO_FIELDS)
    if problem is None:
        assert isinstance(info, dict)
        for name, key in (("duration", "nanoseconds"),
                          ("starting_time", "nanoseconds_since_epoch")):
            problem = problem or _fields(info[name], f"{top}.{name}",
                                         {key: (int, "an integer", True)})
        for i, entry in enumerate(info["topics_with_message_count"]):
            where = f"{top}.topics_with_message_count[{i}]"
            if problem is not None:
                break
            if not isinstance(entry, dict):
                problem = f"{where}: {entry!r} is not a mapping"
                break
            t = entry.get("topic_metadata")
            problem = _fields(entry, where, {"topic_metadata": (dict, "a mapping", True),
                                             "message_count": (int, "an integer", True)}) \
                or (_fields(t, f"{where}.topic_metadata", _TOPIC_FIELDS)
                    if isinstance(t, dict) else None)
        for i, path in enumerate(info["relative_file_paths"]):
            if problem is None and not isinstance(path, str):
                problem = f"{top}.relative_file_paths[{i}]: {path!r} is not a string"
    if problem is not None:
        raise BagReadError(file, _META, problem)
    assert isinstance(info, dict)
    return info


def deserialize(raw: bytes, msgtype: str, encoding: Encoding) -> Any:
    """The bus's (ROS 2) message of one recorded payload: CDR of the ROS 2 type ``msgtype``,
    or (``ros1``) ROS 1 bytes of the ROS 1 type ``msgtype``, converted. Raises
    :data:`DECODE_ERRORS`."""
    try:
        msg = (TYPESTORE.deserialize_cdr(raw, msgtype) if encoding == "cdr"
               else deserialize_ros1(raw, msgtype))
    except KeyError as err:  # rosbags' typestores: a type name (read from the file) unknown
        raise ValueError(str(err)) from err
    return msg if encoding == "cdr" else to_ros2(msg, msgtype)


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
    durability: str = "volatile"  # of its first offered QoS profile (ROS 1: latched or not)


def mcap_profile(path: Path) -> str | None:
    """The header profile of an MCAP file (``ros1``, ``ros2``), None when it has none."""
    try:
        with Path(path).open("rb") as f:
            return str(make_reader(f).get_header().profile)
    except READ_ERRORS:  # not MCAP, empty, unreadable: not a ROS 1 recording
        return None


def mcap_records(file: Path, shown: object = None, what: str = "cannot read bag"
                 ) -> Iterator[tuple[Schema | None, Channel, Message]]:
    """Every message of an MCAP file with its schema and channel, in file order, as the
    ``mcap`` library reads them (publish times and sequence numbers included: what a
    byte-for-byte copy needs); read errors become :class:`~harness.recording.errors.BagReadError`
    naming ``shown`` (default: the file)."""
    with reading(file if shown is None else shown, what), Path(file).open("rb") as f:
        yield from guarded(make_reader(f).iter_messages(log_time_order=False))


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

    def __init__(self, path: Path, shown: object = None, what: str = "cannot read bag") -> None:
        self.path = Path(path)
        self.shown = self.path if shown is None else shown  # the file as its errors name it
        self.what = what
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
        """The bus's (ROS 2) message for one payload of ``conn``; raises
        :data:`DECODE_ERRORS`."""
        return deserialize(raw, conn.msgtype if self.encoding == "cdr" else conn.recorded_type,
                           self.encoding)

    def _read(self) -> AbstractContextManager[None]:
        """The translation of read errors for this recording (:func:`reading`)."""
        return reading(self.shown, self.what)


class _Rosbags(Recording):
    """A recording read through one of rosbags' readers (``_reader``, with ``_raw``:
    connection id → rosbags' connection); subclasses say how one of its connections reads as
    ours (:meth:`_connection`)."""

    _open: ClassVar[Any]  # rosbags' Reader class
    #: What this rosbags reader raises on bad bytes beyond :data:`DATA_ERRORS` (caught
    #: around its own calls only, see :meth:`_quirk`).
    _quirks: ClassVar[tuple[type[Exception], ...]] = ()

    def __init__(self, path: Path, shown: object = None, what: str = "cannot read bag") -> None:
        super().__init__(path, shown, what)
        self.profile = "ros2" if self.encoding == "cdr" else "ros1"
        with self._read():
            self._check()
            self._reader = self._open(path)
            try:
                self._reader.open()
            except self._quirks as err:
                raise self._quirk(err) from err
        self._raw = {c.id: c for c in self._reader.connections}
        self.connections = [self._connection(c) for c in self._reader.connections]
        self._by_id = {c.id: c for c in self.connections}
        if self._reader.message_count:  # else rosbags' (max, 0), as ours
            self.start_time, self.end_time = self._reader.start_time, self._reader.end_time

    def _connection(self, c: Any) -> Connection:
        raise NotImplementedError

    def _check(self) -> None:
        """What the file holds beyond what rosbags' reader checks, raised as
        :data:`READ_ERRORS` (before the reader parses it: the precise reason first)."""

    def _quirk(self, err: Exception) -> Exception:
        """``err``, one of :attr:`_quirks` raised by rosbags' reader itself, as the
        ``ValueError`` it stands for (re-raised when it is not such a case)."""
        raise err

    def close(self) -> None:
        self._reader.close()

    def messages(self, connections: Collection[Connection] = (), start: int | None = None,
                 stop: int | None = None) -> Iterator[tuple[Connection, int, bytes]]:
        raw = [self._raw[c.id] for c in connections]
        by_id = self._by_id
        with self._read():
            it = iter(self._reader.messages(connections=raw, start=start, stop=stop))
            while True:
                try:
                    conn, t, data = next(it)
                except StopIteration:
                    return
                except self._quirks as err:  # rosbags' reader's own step only
                    raise self._quirk(err) from err
                yield by_id[conn.id], t, data


class _Rosbag2(_Rosbags):
    kind = "rosbag2"
    encoding: Encoding = "cdr"
    _open = Rosbag2Reader
    # rosbags' MCAP storage: KeyError for a channel's QoS profile missing a key, or a
    # schema it does not list; lz4's RuntimeError for a chunk that does not decompress
    _quirks = (KeyError, RuntimeError)

    def _check(self) -> None:
        # rosbags compares and indexes metadata.yaml's fields without checking their types
        info = rosbag2_metadata(self.path)
        # rosbags reads an MCAP file's summary without its CRC, and its chunks through it
        for file in _files_in(self.path, info["relative_file_paths"]):
            if file.suffix == ".mcap" and file.is_file():  # (rosbags names a missing one)
                try:
                    check_start(file)
                    check_index(file)
                except ValueError as err:
                    raise ValueError(f"{file.name}: {err}") from err

    def _quirk(self, err: Exception) -> Exception:
        if isinstance(err, RuntimeError) and not lz4_failure(err):
            raise err
        return ValueError(f"{'missing ' if isinstance(err, KeyError) else ''}{err}")

    def _connection(self, c: Any) -> Connection:
        qos = getattr(c.ext, "offered_qos_profiles", []) or []
        durability = qos[0].durability.name.lower() if qos else "volatile"
        latched = durability == "transient_local"
        return Connection(c.id, c.topic, c.msgtype, c.msgtype, latched, c.msgcount,
                          durability=durability)


class _Rosbag1(_Rosbags):
    kind = "bag"
    encoding: Encoding = "ros1"
    _open = Rosbag1Reader
    # rosbags' ROS 1 reader, on a damaged .bag, asserts that a record's time is its index
    # entry's (AssertionError) and looks a record's connection id up (KeyError)
    _quirks = (AssertionError, KeyError)

    def _quirk(self, err: Exception) -> Exception:
        if isinstance(err, AssertionError):
            return ValueError("a message record's time is not its index entry's")
        return ValueError(f"a message record names connection {err}, which the bag does "
                          "not define")

    def _connection(self, c: Any) -> Connection:
        latching = getattr(c.ext, "latching", None)
        return Connection(
            c.id, c.topic, ros2_type(c.msgtype), str(denormalize_msgtype(c.msgtype)),
            bool(latching), c.msgcount, c.msgdef.data.encode(), "ros1msg",
            {"md5sum": c.digest, "callerid": str(getattr(c.ext, "callerid", "") or ""),
             "latching": "true" if latching else "false"},
            "transient_local" if latching else "volatile")


class _Mcap(Recording):
    """A finished MCAP file, ``ros2`` or ``ros1`` profile, read through its index
    (:class:`~harness.recording.mcapread.McapIndex`)."""

    kind = "mcap"

    def __init__(self, path: Path, shown: object = None, what: str = "cannot read bag") -> None:
        super().__init__(path, shown, what)
        with self._read():  # a file empty, cut in its header or of another kind says so
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
                schema.encoding if schema is not None else "", dict(c.metadata),
                "transient_local" if latched else "volatile"))
        self._by_id = {c.id: c for c in self.connections}
        if summary.statistics is not None and summary.statistics.message_count:
            self.start_time = summary.statistics.message_start_time
            # exclusive, as rosbags reports a bag's end: after the last message
            self.end_time = summary.statistics.message_end_time + 1

    def messages(self, connections: Collection[Connection] = (), start: int | None = None,
                 stop: int | None = None) -> Iterator[tuple[Connection, int, bytes]]:
        with self._read():
            yield from self._index.messages(self._by_id, [c.id for c in connections], start,
                                            stop)

    def scan(self, wanted: Collection[int]) -> Iterator[tuple[Connection, int, bytes | None]]:
        with self._read():
            yield from self._index.scan(self._by_id, wanted)


def open_recording(path: str | Path, *, shown: object = None, what: str = "cannot read bag"
                   ) -> Recording:
    """Open a rosbag2 directory, a ``.bag`` or ``.mcap`` file, or a run's ``bag/`` directory
    holding a ROS 1 recording. What is wrong with the file, when it is opened or while its
    messages are read, is raised as one :class:`~harness.recording.errors.BagReadError` line
    ``<shown>: <what>: <reason>`` (``shown``: the path as the user named it; default the
    file read); a ``path`` that holds none of these, or a bag directory that does not exist,
    is one too (``metadata.yaml: missing``)."""
    p = Path(path)
    if p.is_dir() or (not p.exists() and p.suffix not in (".bag", ".mcap")):
        if (p / "metadata.yaml").exists():
            return _Rosbag2(p, shown, what)
        found = ros1_recording(p)
        if found is None:
            raise BagReadError(p if shown is None else shown, what,
                               f"{p}: metadata.yaml: missing (not a rosbag2 directory)")
        p = found
    if p.suffix == ".bag":
        return _Rosbag1(p, shown, what)
    return _Mcap(p, shown, what)


def open_indexed(path: str | Path, *, shown: object = None, what: str = "cannot read bag"
                 ) -> Recording:
    """:func:`open_recording`, but a rosbag2 directory whose ``metadata.yaml`` names one MCAP
    file, finished, is read through that file's index as a ``.mcap`` file is: the same
    messages, without rosbags' parsing of ``metadata.yaml`` (~0.2 s of ruamel), and
    :meth:`Recording.scan` leaves unwanted payloads on disk. Any other directory, and one
    whose file is damaged, opens with :func:`open_recording` (rosbags says what is wrong)."""
    p = Path(path)
    if p.is_dir() and (p / "metadata.yaml").exists():
        file = _one_mcap(p)
        if file is not None:
            try:
                return _Mcap(file, shown, what)
            except BagReadError:  # damaged: rosbags' reader says why
                pass
    return open_recording(p, shown=shown, what=what)


def _named_files(bag_dir: Path) -> list[Path]:
    """The files a rosbag2 directory's ``metadata.yaml`` names, where rosbags looks for them
    (none for unreadable metadata)."""
    try:
        meta = yamlio.load((bag_dir / "metadata.yaml").read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return []
    info = meta.get("rosbag2_bagfile_information") if isinstance(meta, dict) else None
    files = info.get("relative_file_paths") if isinstance(info, dict) else None
    return _files_in(bag_dir, files) if isinstance(files, list) else []


def _files_in(bag_dir: Path, names: list[Any]) -> list[Path]:
    """Where rosbags looks for the files ``metadata.yaml`` names: by their base names, in the
    bag directory."""
    return [bag_dir / PurePath(str(f)).name for f in names]


def _one_mcap(bag_dir: Path) -> Path | None:
    """The one ``.mcap`` file a rosbag2 directory's ``metadata.yaml`` names, if it names one
    that exists (None for anything else, unreadable metadata included)."""
    files = _named_files(bag_dir)
    if len(files) != 1:
        return None
    return files[0] if files[0].suffix == ".mcap" and files[0].is_file() else None
