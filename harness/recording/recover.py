"""Rebuild a rosbag2 bag whose MCAP file was cut short (a crash) from its complete chunks.

A recording killed at any moment leaves an MCAP file that is a clean prefix of what it would
have been: the header, every chunk closed so far (each with its CRC) and perhaps part of the
next record. :func:`recover_bag` reads the file record by record with the ``mcap`` library's
stream reader, keeps every chunk that is whole and passes its CRC, and writes a new indexed
file from their messages (the same writer as the recorder), then ``metadata.yaml`` with the
kept counts. The original is kept beside it as ``<name>.mcap.damaged``; the new file is
written under a temporary name and renamed into place, so the bag directory never holds a
half-written ``.mcap``. The file's length is measured once, before it is read, and nothing
after it is read: a file that something still appends to cannot make the two passes disagree.

What is refused (:class:`~harness.recording.errors.BagError`, nothing written): an empty
file, a file that is not MCAP, one cut inside its header, one cut before its first chunk was
complete (:class:`~harness.recording.errors.NothingRecorded`: no message to recover), and a
file that is corrupt rather than cut short
— a chunk that fails its CRC with readable chunks after it, or any damage in a file that ends
with a footer (it was finished, so the damage did not come from a crash). A file that is
whole is reported as valid and left alone (``metadata.yaml`` is rewritten only if it is
missing or disagrees with the file); given the per-topic counts and digests a run's summary
recorded, a whole file that does not hold them is refused, nothing written (the summary belongs
to another recording, which recover cannot make consistent).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import struct
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO, Literal

import yaml
from mcap.reader import make_reader
from mcap.records import Channel, Chunk, Footer, Header, Message, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import MCAP0_MAGIC

from harness.atomic import discard_partial
from harness.recording.bagfile import (
    ChunkPolicy,
    McapBagWriter,
    TopicMeta,
    bag_metadata,
    dump_metadata,
    write_metadata,
)
from harness.recording.bagread import (
    DATA_ERRORS,
    mcap_profile,
    ros1_recording,
    rosbag2_metadata,
)
from harness.recording.errors import BagError, NothingRecorded
from harness.recording.mcapread import check_index, check_start, lz4_failure
from harness.recording.recorder import TopicStats, digest_update
from harness.recording.verify import check_read_back

__all__ = ["RecoveredBag", "locate_mcap", "recover_bag"]

_FOOTER_HEAD = bytes([0x02]) + struct.pack("<Q", 20)
# What the mcap reader raises on bytes that do not parse (short reads, bad lengths, bad text,
# a chunk that does not decompress); not OSError: a read that fails is not a cut in the file.
_UNREADABLE = DATA_ERRORS
# mcap's summary parsing also raises KeyError on a damaged summary section
_SUMMARY_UNREADABLE: tuple[type[Exception], ...] = (*DATA_ERRORS, KeyError)


@dataclass(frozen=True)
class RecoveredBag:
    """What :func:`recover_bag` found and did.

    ``status``: ``valid`` (nothing to do), ``metadata`` (the MCAP file was whole; only
    ``metadata.yaml`` was rewritten) or ``rebuilt`` (a new MCAP file from the complete chunks).
    """

    bag_dir: Path
    mcap: Path
    status: Literal["valid", "metadata", "rebuilt"]
    topics: dict[str, TopicStats]
    chunks: int  # complete chunks kept
    dropped_bytes: int  # bytes of the original after the last whole record
    damaged: Path | None = None  # where the original file was kept


@dataclass
class _Topic:
    meta: TopicMeta
    count: int = 0
    bytes: int = 0
    digest: Any = field(default_factory=hashlib.sha256)
    first_ns: int | None = None
    last_ns: int | None = None

    def stats(self) -> TopicStats:
        profiles = self.meta.qos_profiles
        durability = str(profiles[0].get("durability", "volatile")) if profiles and isinstance(
            profiles[0], dict) else "volatile"
        return TopicStats(self.meta.name, self.meta.msgtype, self.count, self.bytes,
                          self.digest.hexdigest(), self.first_ns, self.last_ns, durability)


@dataclass
class _Scan:
    finished: bool = False  # the footer was read
    chunks: int = 0
    tail_start: int = 0  # offset after the last record read whole
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, _Topic] = field(default_factory=dict)


def locate_mcap(path: str | Path) -> tuple[Path, Path]:
    """``(bag directory, its .mcap file)`` for a run directory, its ``bag/`` or the file."""
    p = Path(path)
    if p.is_file():
        return p.parent, p
    if (p / "bag").is_dir():
        p = p / "bag"
    if not p.is_dir():
        raise BagError(f"{path}: no such bag directory")
    files = sorted(p.glob("*.mcap"))
    if not files:
        raise BagError(f"{p}: no .mcap file (not a rosbag2 directory with MCAP storage)")
    if len(files) > 1:
        raise BagError(f"{p}: {len(files)} .mcap files; a bag recorded by srr has one")
    return p, files[0]


def _check_start(path: Path, size: int) -> None:
    try:
        check_start(path, size)  # what every reader says of such a file
    except ValueError as err:
        raise BagError(f"{path}: {err}: nothing to recover") from err


def _ends_with_footer(path: Path, size: int) -> bool:
    if size < 2 * len(MCAP0_MAGIC) + 29:
        return False
    with path.open("rb") as f:
        f.seek(size - 37)
        tail = f.read(37)
    return tail[-8:] == MCAP0_MAGIC and tail[:9] == _FOOTER_HEAD


class _Prefix:
    """The first ``size`` bytes of a binary file, read as a stream (the end of the file is
    where the caller measured it, whatever is appended later)."""

    def __init__(self, f: BinaryIO, size: int) -> None:
        self._f = f
        self._left = size

    def read(self, n: int = -1) -> bytes:
        data = self._f.read(self._left if n < 0 else min(n, self._left))
        self._left -= len(data)
        return data

    def tell(self) -> int:
        return self._f.tell()


def _scan(path: Path, visit: Callable[[_Scan, list[Any]], None], size: int) -> _Scan:
    """Read the first ``size`` bytes of ``path`` record by record; ``visit`` gets the records
    of each whole, CRC-valid chunk (or a top-level message) in file order, up to the first
    unreadable byte."""
    _check_start(path, size)
    finished_file = _ends_with_footer(path, size)
    scan = _Scan()
    bad: str | None = None  # the first chunk that could not be used
    with path.open("rb") as raw:
        f = _Prefix(raw, size)
        records = iter(StreamReader(f, emit_chunks=True,  # type: ignore[arg-type]
                                    record_size_limit=size).records)
        first = True
        while True:
            try:
                rec = next(records)
            except StopIteration:
                break
            except _UNREADABLE as err:
                if first:
                    raise BagError(f"{path}: cut inside the MCAP header ({size} bytes): "
                                   "nothing to recover") from err
                if finished_file:
                    raise BagError(f"{path}: corrupt after byte {scan.tail_start} "
                                   f"({_describe(err)}); the file was finished, so this is not "
                                   "a crash: not recovered") from err
                scan.finished = False  # cut inside the closing magic: rebuild all the same
                break
            if first and not isinstance(rec, Header):
                raise BagError(f"{path}: not an MCAP file (no header record)")
            first = False
            offset = scan.tail_start
            if bad is None:  # what is kept ends here
                scan.tail_start = f.tell()
            if isinstance(rec, Chunk):
                try:
                    inner = _breakup(rec)
                except _UNREADABLE as err:
                    bad = bad or f"the chunk at byte {offset} is unreadable ({_describe(err)})"
                    continue
                if bad is not None:
                    raise BagError(f"{path}: corrupt, not cut short: {bad}, but chunks after "
                                   "it are whole; not recovered")
                scan.chunks += 1
                _visit(path, visit, scan, inner)
            elif isinstance(rec, Message | Schema | Channel):
                if bad is None:
                    _visit(path, visit, scan, [rec])
            elif isinstance(rec, Footer):
                scan.finished = True
    if bad is not None and (scan.finished or finished_file):
        raise BagError(f"{path}: corrupt: {bad}; the file was finished, so this is not a "
                       "crash: not recovered")
    if scan.finished:
        _check_summary(path, scan, size)
    return scan


def _breakup(chunk: Chunk) -> list[Any]:
    """The records of a chunk, its CRC checked (mcap's ``breakup_chunk``), with the library's
    broader exceptions on bad bytes as ``ValueError``: ``KeyError`` from its record parsing,
    lz4's ``RuntimeError`` for a chunk that does not decompress."""
    try:
        return breakup_chunk(chunk, validate_crc=True)
    except KeyError as err:  # mcap's record parsing of a damaged chunk
        raise ValueError(str(err)) from err
    except RuntimeError as err:
        if not lz4_failure(err):
            raise
        raise ValueError(str(err)) from err


def _visit(path: Path, visit: Callable[[_Scan, list[Any]], None], scan: _Scan,
           records: list[Any]) -> None:
    try:
        visit(scan, records)
    except BagError as err:
        raise BagError(f"{path}: {err}") from err


def _describe(err: BaseException) -> str:
    return str(err) or type(err).__name__


def _check_summary(path: Path, scan: _Scan, size: int) -> None:
    """A finished file's summary must pass its CRC (when it has one) and its index must agree
    with its chunks (:func:`~harness.recording.mcapread.check_index`, as every reader checks)
    and with what was read from them."""
    try:
        check_index(path, size)  # what every reader checks of a finished file
    except ValueError as err:
        raise BagError(f"{path}: corrupt: {err}; not recovered") from err
    total = sum(t.count for t in scan.channels.values())
    try:
        with path.open("rb") as f:
            summary = make_reader(f).get_summary()
    except _SUMMARY_UNREADABLE as err:
        raise BagError(f"{path}: corrupt summary section ({err}): not recovered") from err
    stats = summary.statistics if summary is not None else None
    chunks = len(summary.chunk_indexes) if summary is not None else -1
    if stats is None or stats.message_count != total or chunks != scan.chunks:
        raise BagError(f"{path}: corrupt: the file's index does not agree with its chunks "
                       f"({total} messages in {scan.chunks} chunks read): not recovered")


def _topic(scan: _Scan, channel: Channel) -> _Topic:
    schema = scan.schemas.get(channel.schema_id)
    msgtype = schema.name if schema is not None else ""
    meta = TopicMeta(
        name=channel.topic, msgtype=msgtype,
        schema=schema.data if schema is not None else b"",
        qos=channel.metadata.get("offered_qos_profiles", ""),
        type_hash=channel.metadata.get("topic_type_hash", ""),
        schema_encoding=schema.encoding if schema is not None else "",
        serialization_format=channel.message_encoding)
    return _Topic(meta)


def _collect(on_message: Callable[[int, _Topic, Message], None] | None = None
             ) -> Callable[[_Scan, list[Any]], None]:
    def visit(scan: _Scan, records: list[Any]) -> None:
        for rec in records:
            if isinstance(rec, Schema):
                scan.schemas.setdefault(rec.id, rec)
            elif isinstance(rec, Channel):
                if rec.id not in scan.channels:
                    scan.channels[rec.id] = _topic(scan, rec)
            elif isinstance(rec, Message):
                topic = scan.channels.get(rec.channel_id)
                if topic is None:
                    raise BagError(f"message on channel {rec.channel_id}, which the file never "
                                   "defines")
                topic.count += 1
                topic.bytes += len(rec.data)
                digest_update(topic.digest, rec.log_time, rec.data)
                if topic.first_ns is None:
                    topic.first_ns = rec.log_time
                topic.last_ns = rec.log_time
                if on_message is not None:
                    on_message(rec.channel_id, topic, rec)
    return visit


def _metadata_agrees(bag_dir: Path, mcap: Path, scan: _Scan) -> bool:
    """Whether ``metadata.yaml`` reads as every reader reads it (its fields' types checked:
    :func:`~harness.recording.bagread.rosbag2_metadata`) and counts what the MCAP file holds."""
    try:
        info = rosbag2_metadata(bag_dir)
        counts = {t["topic_metadata"]["name"]: int(t["message_count"])
                  for t in info["topics_with_message_count"]}
        return bool(info["relative_file_paths"] == [mcap.name]
                    and counts == {t.meta.name: t.count for t in scan.channels.values()})
    except (BagError, OSError, yaml.YAMLError, KeyError, TypeError, ValueError):
        return False


def _metadata_of(mcap_name: str, topics: list[_Topic]) -> dict[str, Any]:
    firsts = [t.first_ns for t in topics if t.first_ns is not None]
    lasts = [t.last_ns for t in topics if t.last_ns is not None]
    return bag_metadata(mcap_name, [(t.meta, t.count) for t in topics],
                        min(firsts) if firsts else None, max(lasts) if lasts else None)


def _free_name(path: Path, suffix: str) -> Path:
    candidate, n = path.with_name(path.name + suffix), 1
    while candidate.exists():
        n += 1
        candidate = path.with_name(f"{path.name}{suffix}.{n}")
    return candidate


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _refuse_ros1(p: Path) -> None:
    for cand in (p, p / "bag"):
        found = (cand if cand.is_file() and (cand.suffix == ".bag"
                                              or mcap_profile(cand) == "ros1")
                 else ros1_recording(cand))
        if found is not None:
            raise BagError(f"{found}: a ROS 1 recording; srr recover rebuilds ROS 2 bags "
                           "(rosbag2, MCAP) only (ROS 1's `rosbag reindex` rebuilds a .bag "
                           "cut short)")


def recover_bag(path: str | Path, *, recorded: Mapping[str, Any] | None = None) -> RecoveredBag:
    """Check a bag and, if its MCAP file was cut short, rebuild it from its complete chunks
    (see the module docstring). Raises :class:`BagError` for what cannot be recovered,
    among it a ROS 1 recording (its own tools rebuild a ``.bag``: ``rosbag reindex``), and,
    when ``recorded`` (a finished run's summary ``topics``, each with its ``count`` and
    ``sha256``) is given, a whole file that does not hold what it says (nothing written)."""
    _refuse_ros1(Path(path))
    bag_dir, mcap = locate_mcap(path)
    try:
        size = mcap.stat().st_size  # once: both passes read this much, no more
        scan = _scan(mcap, _collect(), size)
    except OSError as err:
        raise BagError(f"{mcap}: cannot read: {err.strerror or err}") from err
    stats = {t.meta.name: t.stats() for t in scan.channels.values()}
    if not scan.finished and not any(t.count for t in scan.channels.values()):
        raise NothingRecorded(mcap, size)  # nothing written: an empty bag is no recording
    if scan.finished:
        if recorded is not None:
            check_read_back(mcap, recorded, {n: (t.count, t.sha256) for n, t in stats.items()
                                             if t.count})
        if _metadata_agrees(bag_dir, mcap, scan):
            return RecoveredBag(bag_dir, mcap, "valid", stats, scan.chunks, 0)
        write_metadata(bag_dir, _metadata_of(mcap.name, list(scan.channels.values())))
        return RecoveredBag(bag_dir, mcap, "metadata", stats, scan.chunks, 0)

    tmp = mcap.with_name(mcap.name + ".recovering")
    writer: McapBagWriter | None = None
    try:
        tmp.unlink(missing_ok=True)  # left by a recovery that was itself interrupted
        writer = McapBagWriter(tmp, ChunkPolicy(fsync=True))
        ids: dict[int, int] = {}

        def write(channel: int, topic: _Topic, msg: Message) -> None:
            assert writer is not None
            new = ids.get(channel)
            if new is None:
                new = ids[channel] = writer.add_topic(topic.meta)
            writer.write(new, msg.log_time, msg.data)

        again = _scan(mcap, _collect(write), size)
        topics = [t for t in again.channels.values() if t.count]
        info = _metadata_of(mcap.name, [again.channels[c] for c in ids])
        writer.finish(dump_metadata(info))
        writer = None
        damaged = _free_name(mcap, ".damaged")
        try:
            os.link(mcap, damaged)
        except OSError:
            shutil.copy2(mcap, damaged)
        os.replace(tmp, mcap)
        _fsync_dir(bag_dir)
    except BaseException as err:
        if writer is not None:
            writer.abort()
        discard_partial(tmp)
        if isinstance(err, OSError):
            raise BagError(f"{mcap}: cannot write the recovered bag: "
                           f"{err.strerror or err}") from err
        raise
    write_metadata(bag_dir, info)
    return RecoveredBag(bag_dir, mcap, "rebuilt", {t.meta.name: t.stats() for t in topics},
                        again.chunks, size - again.tail_start, damaged)
