"""Physics-only benchmark: the forklift scenario without cameras, srr against a bare loop.

Measured side by side in one process, alternating, best of ``--repeats``:

* bare:  ``World.build`` + the same number of ``mj_step`` calls (4 substeps × 60 Hz ticks),
         with the drive commands set directly (no graphs, bus, plug-ins or recording);
* srr:   ``api.run_scenario`` on the same scenario: graphs, bus, route follower, CDR
         serialization and MCAP writes, summary.

Prints real-time factors, the harness's own time per tick, and their ratio.

    python benchmarks/bench_physics.py [--repeats 3] [--duration 35]
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
from pathlib import Path

import mujoco

from harness import api

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "forklift_warehouse.yaml"


def bare(duration: float) -> float:
    sc = api.load(SCENARIO, duration=duration)
    from harness.sim import World

    world = World.build(sc)
    m, d = world.model, world.data
    prim = sc.robots[0].prim
    world.apply_joint_commands(prim, ["back_wheel_drive", "back_wheel_swivel"],
                               [0.0, 0.1], [-1.5 / 0.15, 0.0])
    steps = sc.n_ticks * sc.physics.substeps
    t0 = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d)
    return time.perf_counter() - t0


def harness(duration: float) -> float:
    sc = api.load(SCENARIO, duration=duration)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        api.run_scenario(sc, source=str(SCENARIO), out=Path(tmp) / "run")
        return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--duration", type=float, default=35.0)
    args = ap.parse_args()
    b, h = [], []
    for _ in range(args.repeats):
        b.append(bare(args.duration))
        h.append(harness(args.duration))
    tb, th = min(b), min(h)
    ticks = round(args.duration * 60)
    print(f"machine: {platform.processor() or platform.machine()}, python "
          f"{platform.python_version()}, mujoco {mujoco.__version__}")
    print(f"simulated {args.duration:.1f} s = {ticks} ticks x 4 substeps, best of {args.repeats}")
    print(f"bare MuJoCo loop : {tb:7.3f} s  RTF {args.duration / tb:8.1f}")
    print(f"srr run          : {th:7.3f} s  RTF {args.duration / th:8.1f}")
    print(f"harness time per tick: {(th - tb) / ticks * 1e3:.3f} ms "
          f"(bare physics {tb / ticks * 1e3:.3f} ms per tick)")
    print(f"ratio srr / bare : {th / tb:.2f}")


if __name__ == "__main__":
    main()
