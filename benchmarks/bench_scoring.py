"""Replay-and-scoring throughput: recorded messages per second read, decoded and scored.

DESIGN target: >= 100k messages/s. The bag is synthetic (``tests/metrics/synthbag.py``): a
forklift shuttling in and out of a trailer at 60 Hz with /clock, odom, tf, five ground-truth
TF streams, cmd_vel and /safety/is_muted at 20 Hz and a 30 Hz person tracker (MarkerArray
with a DELETEALL and up to five markers per message): about 9.2 messages per tick, so the
default 360 s give about 200k messages.

Measured side by side in one process, best of ``--repeats``:

* read:    ``rosbags`` Reader iterating every message, no decoding (the floor for any
           reader built on it);
* srr:     ``load_frames`` (columnar decoding) + control, perception, safety metrics +
           health gates: the figure the target is about;
* naive:   the same, decoding every message with ``rosbags``' ``deserialize_cdr``.

    python benchmarks/bench_scoring.py [--duration 360] [--repeats 3] [--bag DIR]
"""

from __future__ import annotations

import argparse
import platform
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from rosbags.rosbag2 import Reader

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from harness.frames import load_frames  # noqa: E402
from harness.metrics import (  # noqa: E402
    OutputSpec,
    Tripwire,
    control_metrics,
    health_gates,
    perception_metrics,
    safety_metrics,
)
from tests.metrics.synthbag import ROI, TRIPWIRE, SynthSpec, write_synthetic_bag  # noqa: E402


def read_only(bag: Path) -> int:
    n = 0
    with Reader(bag) as reader:
        for _ in reader.messages():
            n += 1
    return n


def score(bag: Path, *, fast: bool) -> int:
    f = load_frames(bag, fast=fast)
    results = control_metrics(f, robot="forklift", route=[(3.0, 0.0), (21.0, 0.0)])
    results += perception_metrics(f)
    results += safety_metrics(f, tripwire=Tripwire(*TRIPWIRE, inside="right"), roi=ROI)
    gates = health_gates(
        f, expected_hz={"/clock": 60, "/odom": 60, "/perception/tracks": 30},
        gt_expected=list(f.gt_names), robots={"forklift": "/odom"},
        outputs={"/cmd_vel": OutputSpec(first_within_s=1.0, max_silence_s=0.5),
                 "/safety/is_muted": OutputSpec(first_within_s=1.0, max_silence_s=0.5)})
    assert len(results) > 30 and gates
    return f.message_count


def best(fn: Callable[[], int], repeats: int) -> tuple[float, int]:
    times, n = [], 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        n = fn()
        times.append(time.perf_counter() - t0)
    return min(times), n


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=360.0, help="synthetic bag length, s")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--bag", type=Path, help="score this bag instead of a synthetic one")
    ap.add_argument("--skip-naive", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        bag = args.bag
        if bag is None:
            bag = Path(tmp) / "bag"
            t0 = time.perf_counter()
            n = write_synthetic_bag(bag, SynthSpec(duration_s=args.duration))
            print(f"wrote {n} messages ({args.duration:g} s simulated) in "
                  f"{time.perf_counter() - t0:.1f} s")
        score(bag, fast=True)  # warm up imports and caches
        rows = [("read only (rosbags Reader)", *best(lambda: read_only(bag), args.repeats)),
                ("srr: load_frames + all metrics",
                 *best(lambda: score(bag, fast=True), args.repeats))]
        if not args.skip_naive:
            rows.append(("naive: deserialize_cdr every message + all metrics",
                         *best(lambda: score(bag, fast=False), max(1, args.repeats // 2))))
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}")
    for label, secs, n in rows:
        print(f"{label:<52} {n:>8} msgs {secs:8.3f} s {n / secs / 1e3:9.1f} k msgs/s")
    srr = rows[1][2] / rows[1][1]
    print(f"scoring throughput: {srr / 1e3:.1f} k messages/s (target >= 100 k/s): "
          f"{'met' if srr >= 100e3 else 'NOT met'}")
    print(f"srr / read-only: {rows[0][1] / rows[1][1]:.2f} of the reader's own rate")
    if len(rows) > 2:
        print(f"srr / naive: {rows[2][1] / rows[1][1]:.1f}x faster")


if __name__ == "__main__":
    main()
