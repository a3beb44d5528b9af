"""Recorder throughput against a bare MCAP writer on the same messages.

DESIGN target: the recorder writes at >= 0.8 x a bare mcap writer's throughput, zero drops.

The messages are those of a real run: the benchmark runs each ``--scenario`` once (``srr``'s
Python API), reads its bag back and decodes every message into the typestore's message
objects. Then, side by side in one process, alternating, best of ``--repeats``:

* bare mcap: serialize each message (rosbags CDR) and ``mcap.writer.Writer.add_message`` it
  (1 MiB chunks, no compression, schemas and channels registered on first use), then
  ``finish``: the floor for any recorder that serializes and writes MCAP in Python;
* bare rosbags: the same with ``rosbags.rosbag2.Writer`` (MCAP storage), the writer srr used
  before it wrote MCAP itself;
* srr Recorder: ``Recorder.write`` for each message (serialize on the caller's thread, write,
  hash and close chunks on its background thread; default chunks, 8 MB / 1 s), then
  ``close``; its counts are checked against the message count (zero drops);
* with fsync: the same with ``recording.fsync: true`` (each closed chunk forced to disk);
* bare mcap zstd / lz4 and srr zstd / lz4: the same with chunk compression, each srr figure
  compared with the bare writer using the same codec.

    python benchmarks/bench_recorder.py [--scenario scenarios/camera_publishing.yaml ...]
                                        [--duration 3] [--repeats 5]
"""

from __future__ import annotations

import argparse
import platform
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as RosbagsWriter

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from harness import api  # noqa: E402
from harness.bus import Envelope  # noqa: E402
from harness.recording import Recorder  # noqa: E402
from harness.recording.bagfile import ChunkPolicy  # noqa: E402
from harness.serde.messages import TYPESTORE, serialize  # noqa: E402

Msg = tuple[str, str, int, Any]  # topic, type, log time, message object


def messages_of(scenario: Path, duration: float, out: Path) -> list[Msg]:
    res = api.run_scenario(api.load(scenario, duration=duration), source=str(scenario),
                           out=out)
    (path,) = sorted((res.run_dir / "bag").glob("*.mcap"))
    msgs: list[Msg] = []
    with path.open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            assert schema is not None
            msgs.append((channel.topic, schema.name, message.log_time,
                         TYPESTORE.deserialize_cdr(message.data, schema.name)))
    return msgs


def bare_mcap(msgs: list[Msg], out: Path, compression: str = "none") -> int:
    channels: dict[str, int] = {}
    schemas: dict[str, int] = {}
    with (out / "bare.mcap").open("wb") as f:
        w = Writer(f, chunk_size=1 << 20, compression={
            "none": CompressionType.NONE, "zstd": CompressionType.ZSTD,
            "lz4": CompressionType.LZ4}[compression])
        w.start(profile="ros2", library="bench")
        for topic, msgtype, stamp, msg in msgs:
            cid = channels.get(topic)
            if cid is None:
                sid = schemas.get(msgtype)
                if sid is None:
                    text, _ = TYPESTORE.generate_msgdef(msgtype, ros_version=2)
                    sid = schemas[msgtype] = w.register_schema(msgtype, "ros2msg",
                                                               text.encode())
                cid = channels[topic] = w.register_channel(topic, "cdr", sid)
            w.add_message(cid, stamp, serialize(msg, msgtype), stamp)
        w.finish()
    return len(msgs)


def bare_rosbags(msgs: list[Msg], out: Path) -> int:
    w = RosbagsWriter(out / "rosbags", version=9, storage_plugin=StoragePlugin.MCAP)
    w.open()
    conns: dict[str, Any] = {}
    for topic, msgtype, stamp, msg in msgs:
        conn = conns.get(topic)
        if conn is None:
            conn = conns[topic] = w.add_connection(topic, msgtype, typestore=TYPESTORE)
        w.write(conn, stamp, serialize(msg, msgtype))
    w.close()
    return len(msgs)


def recorder(msgs: list[Msg], out: Path, fsync: bool = False, compression: str = "none") -> int:
    rec = Recorder(out / "srr", chunks=ChunkPolicy(fsync=fsync, compression=compression))
    rec.open()
    for seq, (topic, msgtype, stamp, msg) in enumerate(msgs):
        rec.write(Envelope(topic, msgtype, stamp, seq, msg))
    stats = rec.close()
    written = sum(s.count for s in stats.values())
    assert written == len(msgs), f"dropped {len(msgs) - written} messages"
    return written


def best(fn: Callable[[list[Msg], Path], int], msgs: list[Msg], repeats: int,
         results: dict[str, float], name: str) -> None:
    for _ in range(repeats):
        with tempfile.TemporaryDirectory(prefix="srr-bench-rec-") as tmp:
            t0 = time.perf_counter()
            fn(msgs, Path(tmp))
            dt = time.perf_counter() - t0
        results[name] = min(results.get(name, float("inf")), dt)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", type=Path, action="append", default=None)
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    scenarios = args.scenario or [ROOT / "scenarios" / "camera_publishing.yaml",
                                  ROOT / "scenarios" / "forklift_warehouse.yaml"]
    print(f"python {platform.python_version()}, {platform.machine()}, "
          f"{platform.processor() or '?'}")
    for sc in scenarios:
        with tempfile.TemporaryDirectory(prefix="srr-bench-run-") as tmp:
            msgs = messages_of(sc, args.duration, Path(tmp) / "run")
            shutil.rmtree(Path(tmp) / "run")
        nbytes = sum(len(serialize(m, t)) for _, t, _, m in msgs)
        results: dict[str, float] = {}
        contenders = [("bare mcap", bare_mcap), ("bare rosbags", bare_rosbags),
                      ("srr Recorder", recorder),
                      ("  with fsync", lambda m, o: recorder(m, o, fsync=True)),
                      ("bare mcap zstd", lambda m, o: bare_mcap(m, o, "zstd")),
                      ("srr zstd", lambda m, o: recorder(m, o, compression="zstd")),
                      ("bare mcap lz4", lambda m, o: bare_mcap(m, o, "lz4")),
                      ("srr lz4", lambda m, o: recorder(m, o, compression="lz4"))]
        for _ in range(args.repeats):  # alternate so drift hits every contender alike
            for name, fn in contenders:
                best(fn, msgs, 1, results, name)
        print(f"\n{sc.name}, {args.duration:g} s: {len(msgs)} messages, "
              f"{nbytes / 1e6:.1f} MB serialized")
        for name, _ in contenders:
            dt = results[name]
            same = next((f"bare mcap {c}" for c in ("zstd", "lz4") if name.endswith(c)),
                        "bare mcap")  # compared with the bare writer using the same codec
            print(f"  {name:14s} {dt:7.3f} s  {len(msgs) / dt:9.0f} msgs/s  "
                  f"{nbytes / dt / 1e6:7.1f} MB/s  "
                  f"{results[same] / dt:5.2f} x {same}")


if __name__ == "__main__":
    main()
