"""srr's MCAP writer writes the mcap library's bytes: the same calls give the same file, and the
independent reader reads it back."""

from __future__ import annotations

import io
import itertools
import random
from pathlib import Path
from typing import IO

import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from harness.recording.mcap_writer import McapWriter, Payload
from harness.serde.pieces import LARGE


def _calls(seed: int) -> list[tuple[str, tuple[object, ...]]]:
    """A random session: schemas and channels registered along the way (some between
    chunks, some within), messages with times that may go backwards, chunk closes (some
    with nothing in the chunk), metadata at the end."""
    rng = random.Random(seed)
    calls: list[tuple[str, tuple[object, ...]]] = [("start", ("ros2", "lib-x"))]
    schemas = channels = 0
    t = 1_000
    for _ in range(rng.randint(20, 300)):
        r = rng.random()
        if r < 0.04 or not channels:
            if not schemas or rng.random() < 0.5:
                schemas += 1
                calls.append(("register_schema", (f"pkg/msg/T{schemas}", "ros2msg",
                                                  rng.randbytes(rng.randint(0, 40)))))
            channels += 1
            calls.append(("register_channel", (f"/topic_{channels}", "cdr",
                                               rng.randint(1, schemas),
                                               {"offered_qos_profiles": "- depth: 10",
                                                "k": "é" * rng.randint(0, 3)})))
        elif r < 0.12:
            calls.append(("flush", ()))
        else:
            t += rng.randint(-3_000, 20_000_000)
            t = max(t, 0)
            size = rng.randint(0, 300) if rng.random() < 0.9 else rng.randint(60_000, 200_000)
            calls.append(("add_message", (rng.randint(1, channels), t, rng.randbytes(size), t)))
    if rng.random() < 0.5:
        calls.append(("flush", ()))
    calls.append(("add_metadata", ("rosbag2", {"serialized_metadata": "version: 9"})))
    calls.append(("finish", ()))
    return calls


def _library(calls: list[tuple[str, tuple[object, ...]]],
             compression: CompressionType) -> bytes:
    out = io.BytesIO()
    writer = Writer(out, chunk_size=1 << 62, compression=compression)
    for name, args in calls:
        if name == "start":
            writer.start(profile=str(args[0]), library=str(args[1]))
        else:
            getattr(writer, name)(*args)
    return out.getvalue()


def _in_pieces(data: bytes, rng: random.Random) -> Payload:
    """``data`` as srr hands a payload over: as it is, as a view, or cut into pieces."""
    form = rng.choice(["bytes", "view", "pieces"])
    if form == "bytes":
        return data
    if form == "view":
        return memoryview(bytearray(data)).toreadonly()
    cuts = sorted(rng.randint(0, len(data)) for _ in range(rng.randint(0, 3)))
    bounds = [0, *cuts, len(data)]
    return tuple(memoryview(data)[a:b] if rng.random() < 0.5 else data[a:b]
                 for a, b in itertools.pairwise(bounds))


def _ours(calls: list[tuple[str, tuple[object, ...]]], compression: CompressionType,
          stream: IO[bytes] | None = None) -> bytes:
    out = stream if stream is not None else io.BytesIO()
    writer = McapWriter(out, compression)
    rng = random.Random(len(calls))
    for name, args in calls:
        if name == "add_message":
            channel, t, data, publish = args
            assert isinstance(data, bytes)
            writer.add_message(channel, t, _in_pieces(data, rng), publish)  # type: ignore[arg-type]
        else:
            getattr(writer, name)(*args)
    if stream is not None:
        return b""
    assert isinstance(out, io.BytesIO)
    return out.getvalue()


@pytest.mark.parametrize("compression", [CompressionType.NONE, CompressionType.ZSTD,
                                         CompressionType.LZ4])
@pytest.mark.parametrize("seed", range(6))
def test_same_calls_give_the_libraries_bytes(seed: int, compression: CompressionType) -> None:
    calls = _calls(seed)
    ours = _ours(calls, compression)
    assert ours == _library(calls, compression)
    sent = [args for name, args in calls if name == "add_message"]
    got = [(m.channel_id, m.log_time, m.data)
           for _, _, m in make_reader(io.BytesIO(ours)).iter_messages(log_time_order=False)]
    assert got == [(c, t, d) for c, t, d, _ in sent]


@pytest.mark.parametrize("compression", [CompressionType.NONE, CompressionType.ZSTD])
def test_a_file_written_with_writev_has_the_same_bytes(tmp_path: Path,
                                                       compression: CompressionType) -> None:
    """On an unbuffered file each chunk goes out in one ``os.writev`` of its pieces (large
    payloads as handed over): the file is the library's bytes too."""
    calls = _calls(11)
    assert any(name == "add_message" and len(args[2]) >= LARGE  # type: ignore[arg-type]
               for name, args in calls)
    path = tmp_path / "x.mcap"
    with path.open("xb", buffering=0) as f:
        _ours(calls, compression, f)
    assert path.read_bytes() == _library(calls, compression)


def test_writev_writes_more_pieces_than_one_call_takes(tmp_path: Path) -> None:
    from harness.recording.mcap_writer import _writev

    pieces = [bytes([i % 251]) * (i % 7) for i in range(5000)]
    path = tmp_path / "p"
    with path.open("xb", buffering=0) as f:
        _writev(f.fileno(), pieces)
    assert path.read_bytes() == b"".join(pieces)
