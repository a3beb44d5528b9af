"""Real-time factor of a scene with and without the live ROS 2 bridge, measured side by side.

Configurations, one after the other in one process on the same scenario:

* plain:     ``srr run`` as usual;
* --ros2:    every topic also published on a live ROS 2 graph (rclpy, Fast DDS), no outputs
             taken back (nothing waits);
* lockstep:  --ros2 with the route follower replaced by an external rclpy node in its own
             process (tests/ros2/ext_cmd_node.py) publishing cmd_vel for every odometry
             message, the run waiting for it at every tick (60 Hz).

Prints wall time and real-time factor (simulated s / wall s) of each, and their ratios.

    python benchmarks/bench_ros2.py [--scenario scenarios/forklift_warehouse.yaml] [--duration 35]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MUJOCO_GL", "egl")

from harness import api  # noqa: E402

NODE = ROOT / "tests" / "ros2" / "ext_cmd_node.py"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenario", type=Path, default=ROOT / "scenarios" /
                    "forklift_warehouse.yaml")
    ap.add_argument("--duration", type=float, default=None)
    args = ap.parse_args()
    cmd = json.dumps([sys.executable, str(NODE)])
    configs = {
        "plain": [],
        "--ros2": ["ros2.enabled=true"],
        "lockstep": ["ros2.enabled=true", "systems_under_test.route_follower.enabled=false",
                     "ros2.outputs=[{topic: /cmd_vel, type: geometry_msgs/msg/Twist, "
                     "rate_hz: 60}]", f"ros2.external=[{{name: commander, cmd: {cmd}}}]"],
    }
    print(f"machine: {platform.machine()}, {os.cpu_count()} CPUs, Python "
          f"{platform.python_version()}; scenario {args.scenario.name}")
    walls: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, overrides in configs.items():
            sc = api.load(args.scenario, duration=args.duration, overrides=overrides)
            t0 = time.perf_counter()
            res = api.run_scenario(sc, source=str(args.scenario),
                                   out=Path(tmp) / name.strip("-"))
            walls[name] = time.perf_counter() - t0
            sim = res.summary["simulated_s"]
            n = sum(t["count"] for t in res.summary["topics"].values())
            print(f"{name:>9}: {walls[name]:6.2f} s wall, {sim:g} s simulated, "
                  f"RTF {sim / walls[name]:6.1f}, {n} messages, {res.verdict}")
    for name in ("--ros2", "lockstep"):
        print(f"{name} / plain wall time: {walls[name] / walls['plain']:.2f}×")


if __name__ == "__main__":
    main()
