"""Replaying a recording into an external ROS 2 node: srr's lockstep replay beside wall-clock
paced playback (what ``ros2 bag play --clock`` does; the PyPI wheels ship no rosbag2, so the
playback here is rclpy publishing each recorded message's bytes, with its recorded QoS, at its
recorded time divided by the rate).

1. record: a short dock run whose safety monitor is the external rclpy node of
   tests/ros2/ext_safety_node.py (``srr run --ros2``): the forklift enters the trailer, a
   worker crosses the loading area;
2. lockstep: ``srr replay --ros2`` of that recording, three times, into the same node made
   heavier (``--work-ms``: each answer takes that much more wall-clock time);
3. wall clock: the recording played at its recorded times, at 1× and 10×, three times each,
   into the same heavier node, its /safety/is_muted taken with the simulated time of the
   /clock last played (what ``ros2 bag record`` with use_sim_time would stamp).

For each: wall time, inputs the node missed (tracks messages it never answered: each one
gets exactly one /safety/is_muted from the node), and whether the outputs repeat over the
three playbacks (digest of the (time, bytes) sequence) and equal the recorded ones.

    python benchmarks/bench_replay_ros2.py [--duration 12] [--work-ms 40]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MUJOCO_GL", "egl")

from mcap.reader import make_reader  # noqa: E402

from harness import api  # noqa: E402

NODE = ROOT / "tests" / "ros2" / "ext_safety_node.py"
DOCK = ROOT / "scenarios" / "dock_worker_crossing.yaml"
OUTPUTS = ("/safety/is_muted", "/safety/alarm")
TRACKS = "/perception/tracks"


def record(out: Path, duration: float) -> Any:
    sc = api.load(DOCK, duration=duration, overrides=[
        "robots.forklift.spawn.position=[14.5, 0.0, 0.0]",
        "routes.dock_approach.waypoints=[[14.5, 0.0], [18.0, 0.0]]",
        "workers.0.start_delay=3.0",
        "systems_under_test.safety_monitor.enabled=false",
        "ros2.enabled=true",
        "ros2.outputs=[{topic: /safety/is_muted, type: std_msgs/msg/Bool, rate_hz: 5},"
        " {topic: /safety/alarm, type: std_msgs/msg/Bool, rate_hz: 5}]",
        f"ros2.external=[{{name: safety, cmd: {json.dumps([sys.executable, str(NODE)])}}}]",
    ])
    return api.run_scenario(sc, source=str(DOCK), out=out, baselines=out.parent / "baselines",
                            update_baseline=True)


def bag_messages(run_dir: Path, topic: str) -> list[tuple[int, bytes]]:
    (path,) = (run_dir / "bag").glob("*.mcap")
    with path.open("rb") as f:
        return [(m.log_time, bytes(m.data))
                for _s, _c, m in make_reader(f).iter_messages(topics=[topic])]


def digest(seq: list[tuple[int, bytes]]) -> str:
    h = hashlib.sha256()
    for t, raw in seq:
        h.update(t.to_bytes(8, "little") + raw)
    return h.hexdigest()[:12]


def wallclock_playback(run_dir: Path, rate: float, node_cmd: list[str]) -> dict[str, Any]:
    """The recording published at its recorded times ÷ ``rate`` into the node; its
    /safety/is_muted taken with the simulated time last played."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import Bool

    from harness.replay import Playback
    from harness.ros2.bridge import message_class, qos_profile
    from harness.ros2.domain import lease_domain
    from harness.ros2.processes import start_processes, stop_processes
    from harness.scenario.schema import Ros2ProcessSpec

    lease = lease_domain(None)
    env = dict(os.environ, ROS_DOMAIN_ID=str(lease.domain_id),
               ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    ctx = Context()
    rclpy.init(context=ctx, domain_id=lease.domain_id)
    node = rclpy.create_node("bench_player", context=ctx, start_parameter_services=False)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    playback = Playback(run_dir / "bag")
    pubs = {t: node.create_publisher(message_class(r.msgtype), t, qos_profile(r.qos))
            for t, r in playback.topics.items() if t not in OUTPUTS}
    sim_now = [0]
    got: list[tuple[int, bytes]] = []
    node.create_subscription(Bool, OUTPUTS[0], lambda raw: got.append((sim_now[0], bytes(raw))),
                             100, raw=True)
    log_dir = Path(tempfile.mkdtemp())
    procs = start_processes([Ros2ProcessSpec(cmd=tuple(node_cmd), name="safety")], env,
                            log_dir)
    try:
        # fair start: the node is up and matched with every publisher before the first message
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (
                node.count_publishers(OUTPUTS[0])
                and all(p.get_subscription_count() for t, p in pubs.items()
                        if t in ("/odom", "/tf_static", TRACKS))):
            ex.spin_once(timeout_sec=0.05)
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            ex.spin_once(timeout_sec=0.05)
        tracks = 0
        t0 = time.monotonic()
        for stamp, group in playback.by_time():
            due = t0 + stamp / 1e9 / rate
            while (left := due - time.monotonic()) > 0:
                ex.spin_once(timeout_sec=left)
            sim_now[0] = stamp
            for topic, _type, raw in group:
                if topic in pubs:
                    pubs[topic].publish(raw)
                    tracks += topic == TRACKS
        wall = time.monotonic() - t0
        quiet = time.monotonic() + 2.0  # stragglers: until 2 s without an output
        while time.monotonic() < quiet:
            n = len(got)
            ex.spin_once(timeout_sec=0.05)
            if len(got) != n:
                quiet = time.monotonic() + 2.0
    finally:
        stop_processes(procs, log_dir)
        ex.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=ctx)
        lease.release()
    return {"wall": wall, "missed": tracks - len(got), "seq": got}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=12.0)
    ap.add_argument("--work-ms", type=float, default=40.0)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    from harness.ros2.tf2_msgs import ensure_tf2_msgs

    ensure_tf2_msgs(build=True)
    heavy = [sys.executable, str(NODE), "--work-ms", f"{args.work_ms:g}"]
    print(f"machine: {platform.machine()}, {os.cpu_count()} CPUs, Python "
          f"{platform.python_version()}; dock recording of {args.duration:g} s, node answers "
          f"in +{args.work_ms:g} ms")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        rec = record(Path(tmp) / "nightly", args.duration)
        run_wall = time.perf_counter() - t0
        ticks = rec.summary["ticks"]
        recorded = bag_messages(rec.run_dir, OUTPUTS[0])
        print(f"recorded run: {run_wall:.2f} s wall, {ticks / run_wall:.0f} ticks/s, "
              f"RTF {args.duration / run_wall:.1f}, {rec.verdict}")
        t0 = time.perf_counter()  # the recorded node as it was: replay speed
        again = api.replay(rec.run_dir, out=Path(tmp) / "same")
        same_wall = time.perf_counter() - t0
        lock = []
        for i in range(args.repeats):
            t0 = time.perf_counter()
            res = api.replay(rec.run_dir, out=Path(tmp) / f"replay{i}",
                             externals=[f"safety={' '.join(heavy)}"])
            wall = time.perf_counter() - t0
            seq = bag_messages(res.run_dir, OUTPUTS[0])
            n_tracks = res.summary["topics"][TRACKS]["count"]
            lock.append({"wall": wall, "missed": n_tracks - len(seq), "seq": seq,
                         "verdict": res.verdict})
        rows.append(("srr replay --ros2 (lockstep)", lock))
        for rate in (1.0, 10.0):
            rows.append((f"wall clock {rate:g}×", [wallclock_playback(rec.run_dir, rate, heavy)
                                                   for _ in range(args.repeats)]))
    print(f"{'playback':<30} {'wall s':>18} {'missed inputs':>16} {'outputs repeat':>15} "
          f"{'= recorded':>11} {'values = recorded':>18}")
    for name, runs in rows:
        walls = "/".join(f"{r['wall']:.1f}" for r in runs)
        missed = "/".join(str(r["missed"]) for r in runs)
        digests = {digest(r["seq"]) for r in runs}
        same = all(r["seq"] == recorded for r in runs)
        values = all([raw for _, raw in r["seq"]] == [raw for _, raw in recorded] for r in runs)
        print(f"{name:<30} {walls:>18} {missed:>16} {'yes' if len(digests) == 1 else 'no':>15} "
              f"{'yes' if same else 'no':>11} {'yes' if values else 'no':>18}")
    lock_wall = sum(r["wall"] for r in lock) / len(lock)
    print(f"lockstep replay, recorded node: {same_wall:.2f} s wall, {ticks / same_wall:.0f} "
          f"ticks/s, RTF {args.duration / same_wall:.1f} (recorded run: RTF "
          f"{args.duration / run_wall:.1f}), {again.verdict}, digest "
          f"{'=' if again.summary['digest'] == rec.summary['digest'] else '≠'} recorded")
    print(f"lockstep replay, +{args.work_ms:g} ms node: {ticks / lock_wall:.0f} ticks/s, RTF "
          f"{args.duration / lock_wall:.1f}; verdicts {', '.join(r['verdict'] for r in lock)}")


if __name__ == "__main__":
    main()
