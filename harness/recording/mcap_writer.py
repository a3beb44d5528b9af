"""A chunked MCAP writer whose per-message path is a few bytes appended, not a dozen calls,
and which never copies a large payload.

It writes the bytes the ``mcap`` library's ``Writer`` writes with the settings srr uses
(chunked, every index, schemas and channels repeated in the summary, statistics, summary
offsets, CRCs of chunks and summary; no data-section CRC), for the same calls in the same
order: a test checks that byte for byte. What differs is the cost:

* per message: the library builds a record object and makes some twenty calls, here the
  Message record's head is one ``struct`` pack appended to the chunk being filled, and its
  index entry one tuple;
* per byte of a large payload (an image: megabytes a frame): the library copies it into a
  ``BytesIO`` chunk and twice more while building the Chunk record, all holding the GIL. Here a
  chunk is a list of *pieces* (:class:`~harness.serde.pieces.Pieces`): small records are
  appended to a ``bytearray``, a payload of 64 KiB or more (or each large piece of a payload
  handed over in pieces, see :data:`Payload`) is kept as the caller's buffer. The chunk's
  CRC is computed piece by piece and the chunk goes to the file with ``os.writev``; the CRC
  and the write release the GIL, so the payload's bytes are never touched by Python code.
  The CRC-32 is ISA-L's (the ``isal`` package) where installed: the same checksum as zlib's
  at ten times its speed (22 against 2.1 GB/s on the H200 host; at 4 × 640×480 rgb + depth a
  camera set is 8.6 MB, so zlib's CRC alone held the writer thread 4 ms a set), else
  zlib's. A
  caller must not change a buffer after handing it over. A compressed chunk is joined once and
  compressed.

The records written once per chunk or per file (header, schemas, channels, message indexes,
metadata, summary, footer) are written with the library's own record classes.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Sequence
from io import FileIO
from typing import IO, Any

from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (
    Channel,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    McapRecord,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.writer import MCAP0_MAGIC, CompressionType

from harness.serde.pieces import Piece, Pieces

try:  # the same CRC-32 as zlib.crc32, with SIMD (see the module docstring)
    from isal.isal_zlib import crc32
except ImportError:  # pragma: no cover - a platform without isal's wheels
    from zlib import crc32

__all__ = ["McapWriter", "Payload", "payload_size"]

#: A message's bytes: one buffer, or its pieces in order (a header and an image's pixels).
Payload = bytes | memoryview | tuple[Piece, ...]

# A Message record's head: opcode, record length, channel id, sequence, log and publish time.
_MESSAGE_HEAD = struct.Struct("<BQHIQQ")
_MESSAGE_FIELDS = 2 + 4 + 8 + 8
_MESSAGE = int(Opcode.MESSAGE)
# A Chunk record up to its compression name: opcode, record length, message start and end
# time, uncompressed size and CRC.
_CHUNK_HEAD = struct.Struct("<BQQQQI")
_IOV_MAX = min(1024, os.sysconf("SC_IOV_MAX")) if hasattr(os, "sysconf") else 16


def _message_index(channel_id: int, records: list[int]) -> bytes:
    """A MessageIndex record of ``records``, flat (log time, offset) pairs, packed at once
    (the library's ``MessageIndex.write`` makes two calls per entry)."""
    n = len(records)
    return struct.pack(f"<BQHI{n}Q", Opcode.MESSAGE_INDEX, 2 + 4 + 8 * n, channel_id, 8 * n,
                       *records)


def payload_size(data: Payload) -> int:
    """The number of bytes in ``data``."""
    if isinstance(data, tuple):
        return sum(len(piece) for piece in data)
    return len(data)


def _take(builder: RecordBuilder) -> bytes:
    """What ``builder`` holds, emptying it."""
    return bytes(builder.end())  # type: ignore[no-untyped-call]


def _record(record: McapRecord) -> bytes:
    builder = RecordBuilder()
    record.write(builder)
    return _take(builder)


def _compress(data: bytes, compression: CompressionType) -> tuple[str, bytes]:
    if compression == CompressionType.ZSTD:
        import zstandard

        return "zstd", zstandard.compress(data)
    if compression == CompressionType.LZ4:
        import lz4.frame

        return "lz4", bytes(lz4.frame.compress(data))
    return "", data


def _writev(fd: int, pieces: Sequence[Piece]) -> None:
    """Write every piece to ``fd`` in order, resuming after partial writes."""
    todo = [p for p in pieces if len(p)]
    i = 0
    while i < len(todo):
        batch = todo[i:i + _IOV_MAX]
        done = os.writev(fd, batch)
        for piece in batch:
            if done < len(piece):
                todo[i] = memoryview(piece)[done:]
                break
            done -= len(piece)
            i += 1


class McapWriter:
    """Writes one MCAP file to ``stream`` (see the module docstring). Chunks are closed only
    by :meth:`flush` and :meth:`finish`; the caller decides when (see
    :class:`~harness.recording.bagfile.McapBagWriter`).

    ``stream`` is written from its current position. An unbuffered file (``open(...,
    buffering=0)``) gets each chunk with ``os.writev`` on its descriptor; any other binary
    stream gets ``write`` calls.
    """

    def __init__(self, stream: IO[bytes], compression: CompressionType = CompressionType.NONE,
                 ) -> None:
        self._stream = stream
        self._fd = stream.fileno() if isinstance(stream, FileIO) else None
        self._pos = stream.tell()
        self._compression = compression
        self._records = RecordBuilder()  # records outside chunks, written out by _flush
        self._schemas: list[Schema] = []
        self._channels: list[Channel] = []
        self._chunk_indexes: list[ChunkIndex] = []
        self._metadata_indexes: list[MetadataIndex] = []
        # statistics of the closed chunks (a chunk's are folded in when it closes)
        self._message_count = 0
        self._message_start = 0
        self._message_end = 0
        self._channel_counts: dict[int, int] = {}
        self._chunk_count = 0
        self._metadata_count = 0
        # the chunk being filled: its records, large payloads kept as handed over
        self._chunk = Pieces()
        self._chunk_messages = 0
        self._chunk_start = 0
        self._chunk_end = 0
        # per channel, its messages' (log time, offset in the chunk) pairs, flat
        self._indexes: dict[int, list[int]] = {}

    # -- the file ----------------------------------------------------------------------------

    def start(self, profile: str, library: str) -> None:
        # One write: a file killed now is empty or holds the whole header, never the magic alone
        Header(profile, library).write(self._records)
        self._write((MCAP0_MAGIC, _take(self._records)))

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        schema = Schema(id=len(self._schemas) + 1, data=data, encoding=encoding, name=name)
        self._schemas.append(schema)
        self._chunk += _record(schema)
        return schema.id

    def register_channel(self, topic: str, message_encoding: str, schema_id: int,
                         metadata: dict[str, str]) -> int:
        channel = Channel(id=len(self._channels) + 1, topic=topic,
                          message_encoding=message_encoding, schema_id=schema_id,
                          metadata=metadata)
        self._channels.append(channel)
        self._chunk += _record(channel)
        return channel.id

    def add_message(self, channel_id: int, log_time: int, data: Payload,
                    publish_time: int) -> None:
        """Append one message (sequence 0) to the chunk being filled. Large buffers in
        ``data`` are kept, not copied: they must not change afterwards.

        This is the per-message path, so it does only the chunk's bookkeeping (its time span,
        its index entry); the file's statistics are summed from each chunk when it closes."""
        if self._chunk_messages == 0:
            self._chunk_start = self._chunk_end = log_time
        elif log_time < self._chunk_start:
            self._chunk_start = log_time
        elif log_time > self._chunk_end:
            self._chunk_end = log_time
        self._chunk_messages += 1
        if isinstance(data, tuple):
            offset = self._chunk.append(_MESSAGE_HEAD.pack(
                _MESSAGE, _MESSAGE_FIELDS + payload_size(data), channel_id, 0, log_time,
                publish_time))
            for piece in data:
                self._chunk.keep(piece)
        else:
            offset = self._chunk.append(_MESSAGE_HEAD.pack(
                _MESSAGE, _MESSAGE_FIELDS + len(data), channel_id, 0, log_time,
                publish_time), data)
        index = self._indexes.get(channel_id)
        if index is None:
            self._indexes[channel_id] = [log_time, offset]
        else:
            index += (log_time, offset)

    def message_counts(self) -> dict[int, int]:
        """Messages added so far per channel id (in the order of each channel's first)."""
        counts = dict(self._channel_counts)
        for channel_id, index in self._indexes.items():
            counts[channel_id] = counts.get(channel_id, 0) + len(index) // 2
        return counts

    def message_span(self) -> tuple[int, int] | None:
        """The smallest and largest log time of the messages added so far (None: none)."""
        spans = [(self._message_start, self._message_end)] if self._message_count else []
        if self._chunk_messages:
            spans.append((self._chunk_start, self._chunk_end))
        if not spans:
            return None
        return min(a for a, _ in spans), max(b for _, b in spans)

    def flush(self) -> None:
        """Close the chunk being filled (if it holds a message) and flush the stream."""
        self._finish_chunk()
        self._flush()
        self._stream.flush()

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        self._flush()
        offset = self._pos
        self._metadata_count += 1
        Metadata(name=name, metadata=data).write(self._records)
        self._metadata_indexes.append(
            MetadataIndex(offset=offset, length=self._records.count, name=name))
        self._flush()

    def finish(self) -> None:
        """Close the last chunk; write the data end, the summary and the footer."""
        self._finish_chunk()
        DataEnd(0).write(self._records)
        self._flush()
        start = self._pos
        summary = RecordBuilder()
        offsets: list[SummaryOffset] = []

        def group(opcode: Opcode, records: list[Any]) -> None:
            first = summary.count
            for record in records:
                record.write(summary)
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=start + first,
                                         group_length=summary.count - first))

        group(Opcode.SCHEMA, self._schemas)
        group(Opcode.CHANNEL, self._channels)
        group(Opcode.STATISTICS, [Statistics(
            attachment_count=0, channel_count=len(self._channels),
            channel_message_counts=self._channel_counts, chunk_count=self._chunk_count,
            message_count=self._message_count, metadata_count=self._metadata_count,
            message_start_time=self._message_start, message_end_time=self._message_end,
            schema_count=len(self._schemas))])
        group(Opcode.CHUNK_INDEX, self._chunk_indexes)
        group(Opcode.ATTACHMENT_INDEX, [])
        group(Opcode.METADATA_INDEX, self._metadata_indexes)
        offsets_start = start + summary.count
        for offset in offsets:
            offset.write(summary)
        data = _take(summary)
        crc = crc32(data)
        crc = crc32(struct.pack("<BQQQ", Opcode.FOOTER, 8 + 8 + 4,
                                     0 if not data else start, offsets_start), crc)
        self._write((data,))
        Footer(summary_start=0 if not data else start, summary_offset_start=offsets_start,
               summary_crc=crc).write(self._records)
        self._flush()
        self._write((MCAP0_MAGIC,))

    # -- chunks ------------------------------------------------------------------------------

    def _finish_chunk(self) -> None:
        if self._chunk_messages == 0:
            return  # schema and channel records stay for the next chunk, as in the library
        self._chunk_count += 1
        pieces, size = self._chunk.pieces(), len(self._chunk)
        body: Sequence[Piece]
        if self._compression == CompressionType.NONE:
            crc = 0
            for piece in pieces:
                crc = crc32(piece, crc)
            compression, body = "", pieces
        else:
            raw = b"".join(pieces)
            crc = crc32(raw)
            compression, packed = _compress(raw, self._compression)
            body = (packed,)
        stored = sum(len(piece) for piece in body)
        name = compression.encode()
        length = 8 + 8 + 8 + 4 + 4 + len(name) + 8 + stored
        self._flush()
        chunk_offset = self._pos
        self._write((_CHUNK_HEAD.pack(Opcode.CHUNK, length, self._chunk_start,
                                      self._chunk_end, size, crc)
                     + struct.pack("<I", len(name)) + name + struct.pack("<Q", stored),
                     *body))
        index = ChunkIndex(
            message_start_time=self._chunk_start, message_end_time=self._chunk_end,
            chunk_start_offset=chunk_offset, chunk_length=self._pos - chunk_offset,
            message_index_offsets={}, message_index_length=0, compression=compression,
            compressed_size=stored, uncompressed_size=size)
        indexes_offset = self._pos
        for channel_id, records in self._indexes.items():
            index.message_index_offsets[channel_id] = indexes_offset + self._records.count
            self._records.write(_message_index(channel_id, records))
        index.message_index_length = self._records.count
        self._flush()
        self._chunk_indexes.append(index)
        if self._message_count == 0 or self._chunk_start < self._message_start:
            self._message_start = self._chunk_start
        if self._chunk_end > self._message_end:
            self._message_end = self._chunk_end
        self._message_count += self._chunk_messages
        counts = self._channel_counts
        for channel_id, records in self._indexes.items():
            counts[channel_id] = counts.get(channel_id, 0) + len(records) // 2
        self._chunk = Pieces()
        self._chunk_messages = 0
        self._chunk_start = self._chunk_end = 0
        self._indexes = {}

    def _flush(self) -> None:
        if self._records.count:
            self._write((_take(self._records),))

    def _write(self, pieces: Sequence[Piece]) -> None:
        if self._fd is not None:
            _writev(self._fd, pieces)
        else:
            for piece in pieces:
                self._stream.write(piece)
        self._pos += sum(len(piece) for piece in pieces)
