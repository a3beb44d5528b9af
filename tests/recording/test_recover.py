"""Recovering bags cut short (every cut point of a small real bag) and refusing hostile files.

The bags are written by the real recorder; read back with the independent reader (mcap +
mcap-ros2-support)."""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from harness.bus import TRANSIENT_LOCAL, Bus
from harness.cli import main
from harness.recording import Recorder
from harness.recording.bagfile import ChunkPolicy
from harness.recording.errors import BagError, NothingRecorded
from harness.recording.recorder import digest_update
from harness.recording.recover import recover_bag
from harness.serde.messages import clock, header, make, tf_message, transform_stamped
from tests.conftest import ModuleTmp

SPAN_NS = 250_000_000


def record(bag: Path, seconds: float = 2.0, hz: int = 60,
           policy: ChunkPolicy | None = None) -> Recorder:
    """/clock every tick, a 32x32 rgb8 image every other tick, /tf_static once."""
    now = [0]
    bus = Bus(lambda: now[0])
    bus.advertise("/tf_static", "tf2_msgs/msg/TFMessage", TRANSIENT_LOCAL)
    rec = Recorder(bag, chunks=policy or ChunkPolicy(max_span_ns=SPAN_NS))
    rec.open(bus.qos)
    bus.add_tap(rec)
    rng = np.random.default_rng(0)
    for k in range(round(seconds * hz)):
        now[0] = k * 1_000_000_000 // hz
        bus.publish("/clock", "rosgraph_msgs/msg/Clock", clock(now[0]))
        if k == 0:
            bus.publish("/tf_static", "tf2_msgs/msg/TFMessage", tf_message(
                [transform_stamped(0, "world", "odom", (1.0, 2.0, 0.0), (0, 0, 0, 1))]))
        if k % 2 == 0:
            bus.publish("/cam/rgb", "sensor_msgs/msg/Image", make(
                "sensor_msgs/msg/Image", header=header(now[0], "cam"), height=32, width=32,
                encoding="rgb8", step=96, data=rng.integers(0, 255, 32 * 32 * 3, np.uint8)))
    rec.close()
    return rec


def raw(path: Path) -> list[tuple[str, int, bytes]]:
    with path.open("rb") as f:
        return [(c.topic, m.log_time, m.data) for _, c, m in make_reader(f).iter_messages()]


def decoded_count(path: Path) -> int:
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return sum(1 for _ in reader.iter_decoded_messages())


@pytest.fixture(scope="module")
def small_bag(module_tmp: ModuleTmp) -> Path:
    bag = module_tmp("small") / "bag"
    record(bag)
    return bag


def test_chunks_are_bounded_by_span_and_size(tmp_path: Path) -> None:
    record(tmp_path / "t", policy=ChunkPolicy(max_span_ns=SPAN_NS))
    with (tmp_path / "t" / "t.mcap").open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    spans = [c.message_end_time - c.message_start_time for c in summary.chunk_indexes]
    assert len(spans) == 8 and max(spans) < SPAN_NS  # 2 s in chunks of < 0.25 s
    record(tmp_path / "b", policy=ChunkPolicy(max_bytes=20_000, max_span_ns=10**12))
    with (tmp_path / "b" / "b.mcap").open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    sizes = [c.uncompressed_size for c in summary.chunk_indexes]
    assert len(sizes) >= 8  # ~200 kB in chunks of ~20 kB
    assert max(sizes) < 20_000 + 3200  # closed once past the bound: at most one image over


@pytest.mark.slow
def test_every_cut_keeps_exactly_the_complete_chunks(small_bag: Path, tmp_path: Path) -> None:
    src = small_bag / "bag.mcap"
    data = src.read_bytes()
    with src.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    chunks = summary.chunk_indexes
    everything = raw(src)
    header_end = chunks[0].chunk_start_offset
    cuts = sorted({*range(header_end, len(data) - 1, 4001), header_end,
                   *(c.chunk_start_offset + c.chunk_length for c in chunks),
                   *(c.chunk_start_offset + c.chunk_length - 1 for c in chunks),
                   len(data) - 1})
    for cut in cuts:
        bag = tmp_path / f"cut{cut}"
        bag.mkdir()
        (bag / "bag.mcap").write_bytes(data[:cut])
        complete = [c for c in chunks if c.chunk_start_offset + c.chunk_length <= cut]
        if not complete:  # no message on disk: nothing to recover, nothing written
            with pytest.raises(NothingRecorded, match="nothing was recorded: no complete chunk"):
                recover_bag(bag)
            assert [p.name for p in bag.iterdir()] == ["bag.mcap"], cut
            shutil.rmtree(bag)
            continue
        res = recover_bag(bag)
        assert res.status == "rebuilt" and res.chunks == len(complete), cut
        n = sum(1 for _, t, _ in everything if complete and t <= complete[-1].message_end_time)
        got = raw(bag / "bag.mcap")
        assert got == everything[:n], cut  # the same messages, in order: a prefix
        assert decoded_count(bag / "bag.mcap") == n
        assert (bag / "bag.mcap.damaged").read_bytes() == data[:cut]
        assert sum(t.count for t in res.topics.values()) == n
        meta = (bag / "metadata.yaml").read_text()
        assert f"message_count: {n}\n" in meta
        shutil.rmtree(bag)


def test_recovered_digests_are_those_of_the_prefix(small_bag: Path, tmp_path: Path) -> None:
    data = (small_bag / "bag.mcap").read_bytes()
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "bag.mcap").write_bytes(data[: len(data) * 2 // 3])
    res = recover_bag(bag)
    for topic, stats in res.topics.items():
        h = hashlib.sha256()
        for t, stamp, payload in raw(bag / "bag.mcap"):
            if t == topic:
                digest_update(h, stamp, payload)
        assert stats.sha256 == h.hexdigest()
    assert res.topics["/tf_static"].durability == "transient_local"


def test_a_valid_bag_is_left_alone(small_bag: Path, tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    bag = tmp_path / "bag"
    shutil.copytree(small_bag, bag)
    before = {p.name: p.read_bytes() for p in bag.iterdir()}
    assert main(["recover", str(bag)]) == 0
    out = capsys.readouterr().out
    assert "valid" in out and "nothing to recover" in out
    assert {p.name: p.read_bytes() for p in bag.iterdir()} == before


def test_a_missing_metadata_yaml_is_rewritten_without_touching_the_mcap(
        small_bag: Path, tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    shutil.copytree(small_bag, bag)
    meta = (bag / "metadata.yaml").read_text()
    (bag / "metadata.yaml").unlink()
    res = recover_bag(bag)
    assert res.status == "metadata" and res.damaged is None
    assert (bag / "metadata.yaml").read_text() == meta
    assert sorted(p.name for p in bag.iterdir()) == ["bag.mcap", "metadata.yaml"]


def _flip_in_chunk(data: bytes, path: Path) -> bytes:
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    c = summary.chunk_indexes[2]
    out = bytearray(data)
    out[c.chunk_start_offset + c.chunk_length // 2] ^= 0x04
    return bytes(out)


def _first_chunk(path: Path) -> tuple[int, int]:
    """(start, end) offsets of the file's first chunk."""
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    c = summary.chunk_indexes[0]
    return c.chunk_start_offset, c.chunk_start_offset + c.chunk_length


@pytest.mark.parametrize("kind", ["empty", "not-mcap", "cut-in-magic", "cut-in-header",
                                  "header-only", "cut-in-first-chunk", "bit-flip",
                                  "bit-flip-cut", "bit-flip-summary"])
def test_hostile_files_exit_2_with_one_line_and_nothing_written(
        small_bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str) -> None:
    src = small_bag / "bag.mcap"
    data = src.read_bytes()
    content = {
        "empty": b"",
        "not-mcap": b"rosbag2_bagfile_information:\n  version: 9\n" * 20,
        "cut-in-magic": data[:5],
        "cut-in-header": data[:20],
        "header-only": data[:_first_chunk(src)[0]],  # killed before its first chunk closed
        "cut-in-first-chunk": data[:_first_chunk(src)[1] - 1],
        "bit-flip": _flip_in_chunk(data, src),  # a finished file with a bad chunk
        "bit-flip-cut": _flip_in_chunk(data, src)[: len(data) * 3 // 4],  # valid chunks after
        "bit-flip-summary": data[:-60] + bytes([data[-60] ^ 0x01]) + data[-59:],
    }[kind]
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "bag.mcap").write_bytes(content)
    assert main(["recover", str(bag)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert str(bag / "bag.mcap") in err
    assert sorted(p.name for p in bag.iterdir()) == ["bag.mcap"]
    assert (bag / "bag.mcap").read_bytes() == content
    if kind in ("header-only", "cut-in-first-chunk"):  # an empty bag would be no recording
        assert "nothing was recorded: no complete chunk" in err, err
    with pytest.raises(BagError):
        recover_bag(bag)


@pytest.mark.parametrize("layout", ["missing", "no-mcap", "two-mcaps"])
def test_not_a_bag_directory(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                             layout: str) -> None:
    bag = tmp_path / "bag"
    if layout != "missing":
        bag.mkdir()
    if layout == "two-mcaps":
        (bag / "a.mcap").write_bytes(b"x")
        (bag / "b.mcap").write_bytes(b"y")
    assert main(["recover", str(bag)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(bag) in err


def test_a_message_on_an_undefined_channel_is_refused(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    from mcap.writer import CompressionType, Writer

    bag = tmp_path / "bag"
    bag.mkdir()
    with (bag / "bag.mcap").open("wb") as f:
        w = Writer(f, compression=CompressionType.NONE)
        w.start(profile="ros2")
        w.add_message(7, 0, b"\x00\x01\x00\x00", 0)  # channel 7 was never registered
        w.flush()  # cut short: no summary, no footer
    assert main(["recover", str(bag)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(bag / "bag.mcap") in err and "channel 7" in err
    assert sorted(p.name for p in bag.iterdir()) == ["bag.mcap"]


def test_what_is_appended_while_a_bag_is_read_is_not_read(small_bag: Path,
                                                          tmp_path: Path) -> None:
    """The file's length is measured once: a writer appending during the scan (the rest of the
    recording, here written by the scan's own visitor) changes neither what is kept nor the
    bytes said to be dropped, which are never negative."""
    from harness.recording.recover import _collect, _scan

    data = (small_bag / "bag.mcap").read_bytes()
    cut = len(data) // 2
    alone = tmp_path / "alone.mcap"
    alone.write_bytes(data[:cut])
    expected = _scan(alone, _collect(), cut)

    growing = tmp_path / "growing.mcap"
    growing.write_bytes(data[:cut])
    collect = _collect()
    appended: list[int] = []

    def visit(scan: object, records: list[object]) -> None:
        if not appended:  # the recorder writes on while the file is read
            with growing.open("ab") as f:
                appended.append(f.write(data[cut:]))
        collect(scan, records)  # type: ignore[arg-type]

    scan = _scan(growing, visit, cut)
    assert appended and growing.stat().st_size == len(data)
    assert not scan.finished and scan.chunks == expected.chunks < 8
    assert scan.tail_start == expected.tail_start <= cut
    assert {t.meta.name: t.count for t in scan.channels.values()} == {
        t.meta.name: t.count for t in expected.channels.values()}


@pytest.fixture
def tmpfs(tmp_path: Path) -> Iterator[Path]:
    """A fresh tmpfs mounted on a folder (for a real read-only filesystem: :func:`_seal`).
    Mounting needs root (CAP_SYS_ADMIN): skipped otherwise."""
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    if os.geteuid() != 0 or subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "size=8m", "tmpfs", str(mnt)],
            capture_output=True, check=False).returncode != 0:
        pytest.skip("cannot mount a tmpfs (needs root)")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", str(mnt)], check=False)


def _seal(mnt: Path) -> None:
    subprocess.run(["mount", "-o", "remount,ro", str(mnt)], check=True)


@pytest.mark.parametrize("damage", ["cut", "no-metadata"])
def test_a_bag_on_a_read_only_filesystem_is_one_line_exit_2(
        small_bag: Path, tmpfs: Path, capsys: pytest.CaptureFixture[str], damage: str) -> None:
    bag = tmpfs / "bag"
    shutil.copytree(small_bag, bag)
    if damage == "cut":
        data = (bag / "bag.mcap").read_bytes()
        (bag / "bag.mcap").write_bytes(data[: len(data) * 3 // 4])
    else:
        (bag / "metadata.yaml").unlink()
    before = {p.name: p.read_bytes() for p in bag.iterdir()}
    _seal(tmpfs)
    assert main(["recover", str(bag)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Read-only file system" in err, err
    assert str(bag) in err
    assert {p.name: p.read_bytes() for p in bag.iterdir()} == before
