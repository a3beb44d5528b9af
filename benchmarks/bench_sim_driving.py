"""Physics-only real-time factor of the bare forklift world, driven through its joints.

``World.build`` of the forklift alone, a constant drive command through the reference swivel
IK of ``tests/sim/test_sim_driving.py`` (whose tests pin the joint signs), then ``--ticks``
ticks of 4 substeps (60 Hz ticks): no graphs, bus, plug-ins or recording. Best of
``--repeats`` wall times; ``bench_physics.py`` compares a whole srr run against such a loop.

    python benchmarks/bench_sim_driving.py [--ticks 240] [--repeats 3]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from harness.scenario.schema import ForkliftControl  # noqa: E402
from tests.sim.test_sim_driving import FORKLIFT, forklift_world, swivel_ik  # noqa: E402

SUBSTEPS = 4


def drive(ticks: int) -> tuple[float, float]:
    """(simulated seconds, wall seconds) of ``ticks`` ticks of the driven forklift."""
    world = forklift_world()
    names, pos, vel = swivel_ik(1.0, 0.2, ForkliftControl())
    world.apply_joint_commands(FORKLIFT, names, pos, vel)
    start = time.perf_counter()
    for _ in range(ticks):
        world.step(SUBSTEPS)
    wall = time.perf_counter() - start
    return ticks * SUBSTEPS * world.timestep, wall


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--ticks", type=int, default=240, help="ticks of 4 substeps (240: 4 s)")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    runs = [drive(args.ticks) for _ in range(args.repeats)]
    sim, wall = min(runs, key=lambda r: r[1])
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}")
    print(f"forklift scene, physics only: {sim / wall:.0f} sim s per wall s "
          f"({sim:.1f} s in {wall * 1000:.0f} ms, best of {args.repeats})")


if __name__ == "__main__":
    main()
