"""Physics-only benchmark: the forklift scenario without cameras, srr against a bare loop.

Measured side by side in one process, alternating, best of ``--repeats``:

* bare:  ``World.build`` + the same number of ``mj_step`` calls (4 substeps × 60 Hz ticks),
         with the drive commands set directly (no graphs, bus, plug-ins or recording);
* srr:   ``api.run_scenario`` on the same scenario: graphs, bus, route follower, CDR
         serialization and MCAP writes, then scoring, summary and report. Its tick loop is
         timed on its own too (from the end of the first tick to the end of the last, through
         the run's progress callback, scaled to all ticks), so the harness's cost per tick is
         seen apart from the fixed costs of building the scene and scoring the run.

Prints real-time factors, the harness's own time per tick, and the ratios, from wall time and
from the process's CPU time (both threads; what the run costs a core, and far less disturbed
than wall time when other jobs share the machine). ``--profile N`` then runs srr once more
under cProfile, profiling only the tick loop, and prints its top N entries by own time (the
recorder's writer thread is not seen by cProfile).

    python benchmarks/bench_physics.py [--repeats 3] [--duration 35] [--profile 25]
"""

from __future__ import annotations

import argparse
import cProfile
import io
import platform
import pstats
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import mujoco

from harness import api

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "forklift_warehouse.yaml"


def bare(duration: float) -> Times:
    sc = api.load(SCENARIO, duration=duration)
    from harness.sim import World

    world = World.build(sc)
    m, d = world.model, world.data
    prim = sc.robots[0].prim
    world.apply_joint_commands(prim, ["back_wheel_drive", "back_wheel_swivel"],
                               [0.0, 0.1], [-1.5 / 0.15, 0.0])
    steps = sc.n_ticks * sc.physics.substeps
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        mujoco.mj_step(m, d)
    return Times(time.perf_counter() - t0, time.process_time() - c0)


@dataclass(frozen=True)
class Times:
    """Wall and process CPU seconds."""

    wall: float
    cpu: float


class _LoopClock:
    """A progress callback that times the tick loop (and may profile it)."""

    def __init__(self, profiler: cProfile.Profile | None = None) -> None:
        self.first = self.last = Times(0.0, 0.0)
        self.ticks = 0
        self.profiler = profiler

    def __call__(self, done: int, total: int) -> None:
        # The clocks are read on the first and the last tick only: a clock read costs about
        # a microsecond, which on every tick would count against srr.
        if done == 1:
            self.first = Times(time.perf_counter(), time.process_time())
            if self.profiler is not None:
                self.profiler.enable()
        if done == total:
            if self.profiler is not None:
                self.profiler.disable()
            self.last, self.ticks = Times(time.perf_counter(), time.process_time()), total

    def loop(self) -> Times:
        """Tick-loop times scaled from ticks 2..n to all n ticks."""
        scale = self.ticks / max(self.ticks - 1, 1)
        return Times((self.last.wall - self.first.wall) * scale,
                     (self.last.cpu - self.first.cpu) * scale)


def harness(duration: float, profiler: cProfile.Profile | None = None) -> tuple[Times, Times]:
    """Times of the whole run and of its tick loop."""
    sc = api.load(SCENARIO, duration=duration)
    clock = _LoopClock(profiler)
    with tempfile.TemporaryDirectory() as tmp:
        t0, c0 = time.perf_counter(), time.process_time()
        api.run_scenario(sc, source=str(SCENARIO), out=Path(tmp) / "run", progress=clock)
        return Times(time.perf_counter() - t0, time.process_time() - c0), clock.loop()


def profile(duration: float, top: int) -> str:
    prof = cProfile.Profile()
    harness(duration, prof)
    out = io.StringIO()
    pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(top)
    return out.getvalue()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--duration", type=float, default=35.0)
    ap.add_argument("--profile", type=int, default=0, metavar="N",
                    help="also profile one run's tick loop and print its top N entries")
    args = ap.parse_args()
    b: list[Times] = []
    h: list[Times] = []
    loop: list[Times] = []
    for _ in range(args.repeats):
        b.append(bare(args.duration))
        run, in_loop = harness(args.duration)
        h.append(run)
        loop.append(in_loop)
    ticks = round(args.duration * 60)
    print(f"machine: {platform.processor() or platform.machine()}, python "
          f"{platform.python_version()}, mujoco {mujoco.__version__}")
    print(f"simulated {args.duration:.1f} s = {ticks} ticks x 4 substeps, best of {args.repeats}")
    for clock in ("wall", "cpu"):
        tb, th, tl = (min(getattr(t, clock) for t in ts) for ts in (b, h, loop))
        print(f"-- {clock} time")
        print(f"bare MuJoCo loop : {tb:7.3f} s  RTF {args.duration / tb:8.1f}")
        print(f"srr tick loop    : {tl:7.3f} s  RTF {args.duration / tl:8.1f}  "
              f"ratio {tl / tb:.2f}")
        print(f"srr run (whole)  : {th:7.3f} s  RTF {args.duration / th:8.1f}  "
              f"ratio {th / tb:.2f}")
        print(f"harness per tick : {(tl - tb) / ticks * 1e3:.3f} ms in the loop, "
              f"{(th - tb) / ticks * 1e3:.3f} ms with the fixed costs of {th - tl:.3f} s "
              f"(build, scoring, report; bare physics {tb / ticks * 1e3:.3f} ms per tick)")
    if args.profile:
        print(profile(args.duration, args.profile))


if __name__ == "__main__":
    main()
