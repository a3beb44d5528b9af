"""Systems under test that misbehave the ways a nightly suite must survive: a segfault, a
hang past the timeout, and output that depends on something outside the simulation."""

from __future__ import annotations

import ctypes
import os
import time

from harness.sut.route_follower import RouteFollower


class Segfaulter(RouteFollower):
    """Follows the route, then dereferences a null pointer 1 s into the run."""

    def step(self, now_ns: int) -> None:
        if now_ns >= 1_000_000_000:
            ctypes.string_at(0)  # a real SIGSEGV in this process
        super().step(now_ns)


class Sleeper(RouteFollower):
    """Spends 50 ms of wall-clock time per tick: a 3 s scenario takes ~9 s."""

    def step(self, now_ns: int) -> None:
        time.sleep(0.05)
        super().step(now_ns)


class PidDependent(RouteFollower):
    """Drives at a speed that depends on its process id: flaky across processes."""

    def step(self, now_ns: int) -> None:
        self.p = type(self.p)(**{**self.p.__dict__, "speed": 1.0 + (os.getpid() % 9973) / 1e4})
        super().step(now_ns)
