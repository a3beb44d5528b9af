"""Systems under test that misbehave the ways a nightly suite must survive: a segfault, a
hang before the first tick or in the middle of a run, a worker that is killed, and output that
depends on something outside the simulation.

The hangs block until the process is interrupted or killed (they never end on their own), so
a test that stops them does not depend on how fast the machine is."""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time
from pathlib import Path

from harness.sut.base import SutContext
from harness.sut.errors import PluginError
from harness.sut.route_follower import RouteFollower

#: Environment variable naming a file :class:`Staller` creates once it blocks.
STALLED_FILE = "SRR_TEST_STALLED_FILE"
#: Environment variable holding the id of the process that plans the suite. Planning sets up
#: every entry's plug-ins (as ``srr validate`` does); the set-ups below misbehave only in
#: other processes: the suite's workers.
PLANNER_PID = "SRR_TEST_PLANNER_PID"


def in_a_worker() -> bool:
    planner = os.environ.get(PLANNER_PID)
    if planner is None:
        raise PluginError(f"set ${PLANNER_PID} to the id of the process that plans the suite")
    return int(planner) != os.getpid()


def block_forever() -> None:
    """Block until interrupted (SIGTERM/SIGINT as KeyboardInterrupt, Ray's cancel) or killed.
    Short sleeps, so an interrupt raised between bytecodes (Ray's) is seen too."""
    while True:
        time.sleep(0.05)


class Segfaulter(RouteFollower):
    """Follows the route, then dereferences a null pointer 1 s into the run."""

    def step(self, now_ns: int) -> None:
        if now_ns >= 1_000_000_000:
            ctypes.string_at(0)  # a real SIGSEGV in this process
        super().step(now_ns)


class BlockedAtStart(RouteFollower):
    """Never gets past its set-up in a worker: the run blocks before its first tick, before
    it has written anything."""

    def setup(self, ctx: SutContext) -> None:
        super().setup(ctx)
        if in_a_worker():
            block_forever()


class KilledAtStart(RouteFollower):
    """Its worker process is killed (SIGKILL) during set-up, before the first tick."""

    def setup(self, ctx: SutContext) -> None:
        super().setup(ctx)
        if in_a_worker():
            os.kill(os.getpid(), signal.SIGKILL)


class Staller(RouteFollower):
    """Follows the route for 0.5 s of simulated time, then blocks forever (after creating the
    file named by ``$SRR_TEST_STALLED_FILE``, when set): a run stuck mid-way."""

    def step(self, now_ns: int) -> None:
        if now_ns >= 500_000_000:
            stalled = os.environ.get(STALLED_FILE)
            if stalled:
                Path(stalled).touch()
            block_forever()
        super().step(now_ns)


class StallsOnce(RouteFollower):
    """:class:`Staller` the first time: blocks 0.5 s into the run unless the file named by
    ``$SRR_TEST_STALLED_FILE`` exists already (it creates it as it blocks), so the same run
    started again follows its route to the end (a suite interrupted, then resumed)."""

    def step(self, now_ns: int) -> None:
        stalled = os.environ.get(STALLED_FILE)
        if now_ns >= 500_000_000 and stalled and not Path(stalled).exists():
            Path(stalled).touch()
            block_forever()
        super().step(now_ns)


class PidDependent(RouteFollower):
    """Drives at a speed that depends on its process id and on how many runs that process has
    set up before (counted where a run's plug-in modules do not reach: an attribute of
    ``sys``, as a C library's global would): flaky across processes, and across the runs of
    one suite's host."""

    def setup(self, ctx: SutContext) -> None:
        super().setup(ctx)
        self.seq = getattr(sys, "_srr_test_setups", 0)
        sys._srr_test_setups = self.seq + 1  # type: ignore[attr-defined]

    def step(self, now_ns: int) -> None:
        speed = 1.0 + (os.getpid() % 997) / 1e4 + (self.seq % 10) / 1e1
        self.p = type(self.p)(**{**self.p.__dict__, "speed": speed})
        super().step(now_ns)


class PidDependentStaller(PidDependent, Staller):
    """Drives as :class:`PidDependent` (each process records other bytes), then blocks at
    0.5 s as :class:`Staller`: repeats that record different things before their timeouts."""


class RaisesInColour(RouteFollower):
    """Raises 0.5 s into the run with a message in ANSI colours (as a coloured logger or
    traceback writes one): escape characters that XML 1.0 cannot hold, even escaped."""

    def step(self, now_ns: int) -> None:
        if now_ns >= 500_000_000:
            raise RuntimeError("\x1b[31mmotor fault\x1b[0m <&> \x00")
        super().step(now_ns)


#: Set up in this module (a fresh process: 0 before the first run's set-up).
SETUPS = 0


class ModuleCounter(RouteFollower):
    """Drives at a speed that depends on how many times this module has seen a set-up: the
    same in every run only if each run imports its plug-ins afresh (as a process per run
    does), whatever ran before it in the same process."""

    def setup(self, ctx: SutContext) -> None:
        global SETUPS
        super().setup(ctx)
        SETUPS += 1
        self.seen = SETUPS

    def step(self, now_ns: int) -> None:
        self.p = type(self.p)(**{**self.p.__dict__, "speed": 1.0 + self.seen / 10})
        super().step(now_ns)


class LeavesAThread(RouteFollower):
    """Starts a thread that outlives the run (it waits for ever): the process it ran in must
    not run another run."""

    def setup(self, ctx: SutContext) -> None:
        super().setup(ctx)
        threading.Thread(target=threading.Event().wait, name="left-behind", daemon=True).start()


class Exits(RouteFollower):
    """Says so on stdout, then ends its process with ``os._exit(3)`` 1 s into the run (no
    clean-up, no answer to anyone)."""

    def step(self, now_ns: int) -> None:
        if now_ns >= 1_000_000_000:
            print(f"exits: leaving the process {os.getpid()}", flush=True)
            os._exit(3)
        super().step(now_ns)


#: Resident memory :class:`Hog` holds through its run.
HOG_MB = 300


class Hog(RouteFollower):
    """Holds :data:`HOG_MB` MiB of resident memory (every page written) from its set-up to its
    shutdown, and says so on stdout and stderr."""

    def setup(self, ctx: SutContext) -> None:
        super().setup(ctx)
        if in_a_worker():
            self.block = bytearray(HOG_MB << 20)
            self.block[::4096] = b"\x01" * len(range(0, HOG_MB << 20, 4096))
            print("hog: holding memory", flush=True)
            print("hog: on stderr too", file=sys.stderr, flush=True)

    def shutdown(self) -> None:
        self.block = bytearray()
        super().shutdown()


class SetsMujocoCallback(RouteFollower):
    """Sets MuJoCo's process-wide control callback (every actuator pushed by 0.5) in a worker
    and never clears it: what a later run in the same process must not inherit."""

    def setup(self, ctx: SutContext) -> None:
        super().setup(ctx)
        if in_a_worker():
            import mujoco

            def push(model: object, data: object) -> None:
                data.ctrl[:] += 0.5  # type: ignore[attr-defined]

            mujoco.set_mjcb_control(push)


class Unseeded(RouteFollower):
    """Follows the route at a speed drawn from the global generators, unseeded (a leak a
    nightly's repeats must catch): every run of a fresh process drives differently."""

    def setup(self, ctx: SutContext) -> None:
        import random

        import numpy as np

        super().setup(ctx)
        self.p = type(self.p)(**{**self.p.__dict__, "speed": 0.5 + random.random() * 0.1
                                 + float(np.random.random()) * 0.1})


#: Environment variable naming a file :class:`CountsFrozen` writes, in a worker, how many
#: objects the collector holds frozen (skips in its collections) as its run starts.
FROZEN_FILE = "SRR_TEST_FROZEN_FILE"


class CountsFrozen(RouteFollower):
    """Follows the route; in a worker, notes ``gc.get_freeze_count()`` at its set-up."""

    def setup(self, ctx: SutContext) -> None:
        super().setup(ctx)
        if in_a_worker():
            import gc

            Path(os.environ[FROZEN_FILE]).write_text(str(gc.get_freeze_count()))
