"""ROS 1 output against ROS 2, side by side in one process (best of ``--repeats``):

* serialize: microseconds per message to turn a bus message into recorded bytes: ROS 2 CDR
  (``harness.serde.messages.serialize``) and ROS 1 (``Ros1Encoder.encode``: conversion to the
  Noetic message, header seq, rosbags' ``serialize_ros1``);
* score: messages per second read, decoded and scored (``load_frames`` + every metric family
  + health gates, as ``bench_scoring.py``) from the synthetic bag as recorded (ROS 2) and the
  same messages recorded again as a ROS 1 ``.bag`` and as ``ros1`` MCAP;
* run: wall time of ``api.run_scenario`` on seed 000's TurtleBot3 scene (its graphs as a
  ``graphs:`` builder; one 1280 x 720 camera, lidar, IMU, odometry, TF; ``--seconds`` of
  simulated time) recording ROS 2, ROS 1 MCAP and a ROS 1 bag, alternating.

    python benchmarks/bench_ros1.py [--duration 120] [--seconds 2] [--repeats 3]
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag2 import Reader

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.bench_scoring import score  # noqa: E402
from harness import api  # noqa: E402
from harness.bus import TRANSIENT_LOCAL, Envelope, Qos  # noqa: E402
from harness.recording.ros1bag import Ros1Recorder  # noqa: E402
from harness.serde import messages as m  # noqa: E402
from harness.serde.messages import TYPESTORE, serialize  # noqa: E402
from harness.serde.ros1 import Ros1Encoder  # noqa: E402
from tests.metrics.synthbag import SynthSpec, write_synthetic_bag  # noqa: E402

SEED000 = ROOT / "tests" / "e2e" / "seed000_graphs.yaml"


def samples() -> dict[str, tuple[str, Any]]:
    rng = np.random.default_rng(0)

    def image(w: int, h: int) -> Any:
        return m.make("sensor_msgs/msg/Image", header=m.header(1, "camera"), height=h, width=w,
                      encoding="rgb8", step=3 * w,
                      data=rng.integers(0, 255, 3 * w * h).astype(np.uint8))

    marker = m.make("visualization_msgs/msg/Marker", header=m.header(1, "world"), ns="person")
    return {
        "Clock": ("rosgraph_msgs/msg/Clock", m.clock(1)),
        "Odometry": ("nav_msgs/msg/Odometry", m.odometry(1, "odom", "base_footprint",
                                                          [1, 2, 0], [0, 0, 0, 1], [0.1, 0, 0],
                                                          [0, 0, 0.2])),
        "TFMessage (3 transforms)": ("tf2_msgs/msg/TFMessage", m.tf_message(
            [m.transform_stamped(1, "a", f"b{i}", [0, 0, 0], [0, 0, 0, 1]) for i in range(3)])),
        "LaserScan (360 beams)": ("sensor_msgs/msg/LaserScan", m.make(
            "sensor_msgs/msg/LaserScan", header=m.header(1, "laser"),
            ranges=rng.random(360).astype(np.float32),
            intensities=np.zeros(360, np.float32))),
        "MarkerArray (5 markers)": ("visualization_msgs/msg/MarkerArray", m.make(
            "visualization_msgs/msg/MarkerArray", markers=[marker] * 5)),
        "Image 640x480 rgb8": ("sensor_msgs/msg/Image", image(640, 480)),
        "Image 1280x720 rgb8": ("sensor_msgs/msg/Image", image(1280, 720)),
    }


def per_message_us(fn: Callable[[], Any], repeats: int) -> float:
    n = 1
    while True:  # enough calls for ~0.1 s
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        if time.perf_counter() - t0 > 0.1:
            break
        n *= 4
    best_s = min(_timed(fn, n) for _ in range(repeats))
    return best_s / n * 1e6


def _timed(fn: Callable[[], Any], n: int) -> float:
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return time.perf_counter() - t0


def as_ros1(ros2_bag: Path, bag_dir: Path, fmt: str) -> None:
    rec = Ros1Recorder(bag_dir, "bag" if fmt == "bag" else "mcap")
    rec.open(lambda topic: TRANSIENT_LOCAL if topic == "/tf_static" else Qos())
    with Reader(ros2_bag) as reader:
        for i, (conn, t, raw) in enumerate(reader.messages()):
            rec.write(Envelope(conn.topic, conn.msgtype, t, i,
                               TYPESTORE.deserialize_cdr(raw, conn.msgtype)))
    rec.close()


def best(fn: Callable[[], int], repeats: int) -> tuple[float, int]:
    times, n = [], 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        n = fn()
        times.append(time.perf_counter() - t0)
    return min(times), n


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=120.0, help="synthetic bag length, s")
    ap.add_argument("--seconds", type=float, default=2.0, help="seed 000 run length, s")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}")

    print("\nserialize (best of repeats, microseconds per message)")
    print(f"{'message':<28} {'ROS 2 CDR':>10} {'ROS 1':>10} {'ROS 1 / ROS 2':>14}")
    for label, (msgtype, msg) in samples().items():
        enc = Ros1Encoder()
        cdr = per_message_us(lambda t=msgtype, x=msg: serialize(x, t), args.repeats)
        ros1 = per_message_us(lambda e=enc, t=msgtype, x=msg: e.encode("/t", t, x),
                              args.repeats)
        print(f"{label:<28} {cdr:10.1f} {ros1:10.1f} {ros1 / cdr:14.2f}")

    with tempfile.TemporaryDirectory() as tmp:
        ros2 = Path(tmp) / "ros2"
        n = write_synthetic_bag(ros2, SynthSpec(duration_s=args.duration))
        bags = {"ROS 2 (rosbag2, MCAP)": ros2}
        for fmt in ("bag", "mcap"):
            as_ros1(ros2, Path(tmp) / fmt / "bag", fmt)
            bags[f"ROS 1 ({fmt})"] = Path(tmp) / fmt
        for bag in bags.values():
            score(bag, fast=True)  # warm up
        print(f"\nscore: {n} messages ({args.duration:g} s synthetic), best of "
              f"{args.repeats}")
        rates = {}
        for label, bag in bags.items():
            secs, count = best(lambda bag=bag: score(bag, fast=True), args.repeats)
            rates[label] = count / secs
            print(f"{label:<24} {count:>8} msgs {secs:7.3f} s "
                  f"{count / secs / 1e3:8.1f} k msgs/s")
        base = rates["ROS 2 (rosbag2, MCAP)"]
        print("relative to ROS 2: " + ", ".join(f"{k} {v / base:.2f}" for k, v in rates.items()))

        outputs = {"ROS 2": ["output.ros=2"], "ROS 1 MCAP": [],
                   "ROS 1 bag": ["output.format=bag"]}
        walls: dict[str, list[float]] = {k: [] for k in outputs}
        for r in range(args.repeats + 1):  # the first round warms up
            for label, sets in outputs.items():
                sc = api.load(SEED000, duration=args.seconds, overrides=sets)
                out = Path(tmp) / f"run-{r}-{label.replace(' ', '_')}"
                t0 = time.perf_counter()
                api.run_scenario(sc, source=str(SEED000), out=out)
                if r:
                    walls[label].append(time.perf_counter() - t0)
        print(f"\nrun: seed 000, {args.seconds:g} s simulated, best / median of "
              f"{args.repeats}")
        ref = min(walls["ROS 2"])
        for label, ts in walls.items():
            print(f"{label:<12} {min(ts):7.2f} s / {statistics.median(ts):7.2f} s "
                  f"({min(ts) / ref:.2f} x ROS 2)")


if __name__ == "__main__":
    main()
