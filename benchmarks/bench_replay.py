"""Open-loop replay against the closed-loop run that recorded the same scene.

Measured side by side in one process:

* run:     ``api.run_scenario`` of the scene (physics, rendering, graphs, systems under test,
           recording, scoring, report);
* replay:  ``api.replay`` of that run into its own systems under test (read in publication
           order, decode what a plug-in subscribes to, play, record, score, report);
* bare:    the ``mcap`` reader iterating the same bag and decoding every message with the
           rosbags typestore (no playing, recording or scoring).

Prints wall times, run ÷ replay, and messages per second of replay and of the bare read.
The recorded and replayed digests are checked equal (a replay that is fast but wrong counts
for nothing).

    python benchmarks/bench_replay.py [--scenario scenarios/dock_worker_crossing.yaml]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MUJOCO_GL", "egl")

from mcap.reader import make_reader  # noqa: E402

from harness import api  # noqa: E402
from harness.replay import Playback  # noqa: E402
from harness.serde.messages import TYPESTORE  # noqa: E402


def bare_read_decode(bag: Path) -> int:
    types = Playback(bag).topics
    (mcap,) = bag.glob("*.mcap")
    n = 0
    with mcap.open("rb") as f:
        for _schema, channel, message in make_reader(f).iter_messages(log_time_order=False):
            TYPESTORE.deserialize_cdr(message.data, types[channel.topic].msgtype)
            n += 1
    return n


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenario", type=Path, default=ROOT / "scenarios" /
                    "dock_worker_crossing.yaml")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        sc = api.load(args.scenario)
        t0 = time.perf_counter()
        run = api.run_scenario(sc, source=str(args.scenario), out=Path(tmp) / "run")
        t_run = time.perf_counter() - t0
        t0 = time.perf_counter()
        rep = api.replay(run.run_dir, out=Path(tmp) / "replay")
        t_rep = time.perf_counter() - t0
        t0 = time.perf_counter()
        n = bare_read_decode(run.run_dir / "bag")
        t_bare = time.perf_counter() - t0
        assert rep.summary["digest"] == run.summary["digest"], "replay differs from the run"
        msgs = sum(v["count"] for v in rep.summary["topics"].values())
        mb = sum(v["bytes"] for v in rep.summary["topics"].values()) / 1e6
    print(f"{platform.machine()}, Python {platform.python_version()}, "
          f"MUJOCO_GL={os.environ['MUJOCO_GL']}, {os.cpu_count()} CPUs")
    print(f"scene {args.scenario.name}: {run.summary['simulated_s']:.0f} s simulated, "
          f"{msgs} messages, {mb:.1f} MB")
    print(f"closed-loop run                {t_run:8.2f} s")
    print(f"open-loop replay (same SUTs)   {t_rep:8.2f} s   {msgs / t_rep / 1e3:8.1f} k msgs/s"
          "  (read + decode subscribed + play + record + score + report)")
    print(f"bare mcap read + decode all    {t_bare:8.2f} s   {n / t_bare / 1e3:8.1f} k msgs/s")
    print(f"replay is {t_run / t_rep:.1f}x faster than the run (goal >= 5x); digests equal")


if __name__ == "__main__":
    main()
