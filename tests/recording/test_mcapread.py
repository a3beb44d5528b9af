"""McapIndex against the ``mcap`` library's own reader, on files it writes: chunks compressed
or not, with or without message indexes, no chunks at all; and damage named in one line."""

from __future__ import annotations

import shutil
import struct
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, IndexType, Writer

from harness.frames import load_frames
from harness.recording.bagread import open_indexed
from harness.recording.errors import BagError
from harness.recording.mcapread import McapIndex
from tests.metrics.synthbag import SynthSpec, write_synthetic_bag

SMALL, LARGE, OTHER = 1, 2, 3  # channel ids as the writer numbers them


def write(path: Path, compression: CompressionType, index: IndexType, chunked: bool) -> None:
    """Three channels over 2 s: 100 Hz small messages, 10 Hz 100 kB images, 1 Hz others,
    in chunks of about 64 kB."""
    with path.open("wb") as f:
        w = Writer(f, chunk_size=64 * 1024, compression=compression, index_types=index,
                   use_chunking=chunked)
        w.start(profile="ros2")
        sid = w.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        for topic in ("/small", "/large", "/other"):
            w.register_channel(topic, "cdr", sid)
        for i in range(200):
            t = 1_000_000_000 + i * 10_000_000
            w.add_message(SMALL, t, struct.pack("<II", 0x100, i), t, i)
            if i % 10 == 0:
                w.add_message(LARGE, t, bytes([i % 251]) * 100_000, t, i)
            if i % 100 == 0:
                w.add_message(OTHER, t, b"other%d" % i, t, i)
        w.finish()


def reference(path: Path) -> list[tuple[int, int, bytes]]:
    with path.open("rb") as f:
        return [(c.id, m.log_time, m.data)
                for _, c, m in make_reader(f).iter_messages(log_time_order=False)]


KINDS = {
    "plain": (CompressionType.NONE, IndexType.ALL, True),
    "zstd": (CompressionType.ZSTD, IndexType.ALL, True),
    "lz4": (CompressionType.LZ4, IndexType.ALL, True),
    "no-message-index": (CompressionType.ZSTD, IndexType.CHUNK, True),
    "unchunked": (CompressionType.NONE, IndexType.ALL, False),
}


@pytest.mark.parametrize("kind", list(KINDS))
def test_messages_and_scan_agree_with_the_mcap_reader(tmp_path: Path, kind: str) -> None:
    path = tmp_path / "f.mcap"
    write(path, *KINDS[kind])
    ref = reference(path)
    assert len(ref) == 200 + 20 + 2
    index = McapIndex(path)
    ids = {cid: cid for cid in index.summary.channels}
    assert list(index.messages(ids)) == ref
    lo, hi = 1_500_000_000, 1_800_000_000  # [lo, hi)
    assert list(index.messages(ids, [SMALL, OTHER], lo, hi)) == [
        r for r in ref if r[0] != LARGE and lo <= r[1] < hi]
    assert list(index.messages(ids, [LARGE], stop=lo)) == [
        r for r in ref if r[0] == LARGE and r[1] < lo]
    assert list(index.messages(ids, [OTHER])) == [r for r in ref if r[0] == OTHER]
    # every message's log time, only the wanted payloads (a chunk with none of them: its
    # log times from its message index; few among images: read one by one)
    for wanted in ({SMALL}, {OTHER}, {SMALL, LARGE, OTHER}):
        assert list(index.scan(ids, wanted)) == [
            (cid, t, raw if cid in wanted else None) for cid, t, raw in ref]


def test_a_message_index_pointing_off_its_records_is_one_line(tmp_path: Path) -> None:
    """A few wanted messages among images are read through the message index: a damaged
    index is named, not read as data."""
    path = tmp_path / "f.mcap"
    write(path, CompressionType.NONE, IndexType.ALL, True)
    ci = min(McapIndex(path).summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    data = bytearray(path.read_bytes())
    # the /small channel's MessageIndex: opcode, length, channel id, pairs length, pairs
    at = ci.message_index_offsets[SMALL] + 1 + 8 + 2 + 4
    _, offset = struct.unpack_from("<QQ", data, at)
    struct.pack_into("<Q", data, at + 8, offset + 1)  # into the record's length field
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=rf"chunk at byte {ci.chunk_start_offset}: its "
                       rf"message index points at {offset + 1}, not a message record"):
        list(McapIndex(path).scan({1: 1, 2: 2, 3: 3}, {SMALL}))


def test_scoring_a_damaged_bag_names_it_in_one_line(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    write_synthetic_bag(bag, SynthSpec(duration_s=1.0))
    good = load_frames(bag)
    with open_indexed(bag) as rec:  # a rosbag2 directory of one finished MCAP file
        assert type(rec).__name__ == "_Mcap"
    (mcap,) = bag.glob("*.mcap")
    ci = min(McapIndex(mcap).summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    data = bytearray(mcap.read_bytes())
    # the chunk's first record (past the Chunk record's fields): a length past its end
    struct.pack_into("<Q", data, ci.chunk_start_offset + 9 + 8 + 8 + 8 + 4 + 4
                     + len(ci.compression) + 8 + 1, 10**9)
    damaged = tmp_path / "damaged"
    shutil.copytree(bag, damaged)
    (damaged / mcap.name).write_bytes(bytes(data))
    with pytest.raises(BagError) as err:
        load_frames(damaged)
    assert str(err.value) == (f"{damaged}: cannot read bag: chunk at byte "
                              f"{ci.chunk_start_offset}: its records overrun it")
    assert good.message_count > 0
    cut = tmp_path / "cut"
    shutil.copytree(bag, cut)
    (cut / mcap.name).write_bytes(mcap.read_bytes()[: len(data) // 2])
    with pytest.raises(BagError, match=rf"^{cut}: cannot read bag: "):
        load_frames(cut)
