"""A plug-in that presses Ctrl-C on its own process from inside a ``ctypes`` call, as a
Ctrl-C lands in a camera's OpenGL call: ``ctypes`` turns the ``KeyboardInterrupt`` raised
while it converts an argument into ``ArgumentError``."""

from __future__ import annotations

import ctypes
import signal
from typing import Any

from harness.sut.route_follower import RouteFollower

#: Simulated time at which the plug-in presses Ctrl-C.
AT_NS = 1_000_000_000


class _Pressing:
    """A ``ctypes`` argument type whose conversion sends SIGINT to this process."""

    @classmethod
    def from_param(cls, obj: Any) -> ctypes.c_int:
        signal.raise_signal(signal.SIGINT)
        return ctypes.c_int(int(obj))  # the handler runs here, at a bytecode boundary


class CtrlCInCtypes(RouteFollower):
    """Follows the route; at :data:`AT_NS` calls C's ``abs`` with an argument whose
    conversion presses Ctrl-C."""

    def step(self, now_ns: int) -> None:
        if now_ns >= AT_NS:
            c_abs = ctypes.CDLL(None).abs
            c_abs.argtypes = [_Pressing]
            c_abs(-1)
        super().step(now_ns)


class CtrlCInCtypesAtSetup(RouteFollower):
    """Presses Ctrl-C the same way in its set-up, before the run's first tick."""

    def setup(self, ctx: Any) -> None:
        c_abs = ctypes.CDLL(None).abs
        c_abs.argtypes = [_Pressing]
        c_abs(-1)
        super().setup(ctx)
