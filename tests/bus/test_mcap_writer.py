"""srr's MCAP writer writes the mcap library's bytes: the same calls give the same file, and the
independent reader reads it back."""

from __future__ import annotations

import io
import random

import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from harness.bus.mcap_writer import McapWriter


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
            calls.append(("add_message", (rng.randint(1, channels), t,
                                          rng.randbytes(rng.randint(0, 300)), t)))
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


def _ours(calls: list[tuple[str, tuple[object, ...]]], compression: CompressionType) -> bytes:
    out = io.BytesIO()
    writer = McapWriter(out, compression)
    for name, args in calls:
        getattr(writer, name)(*args)
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
