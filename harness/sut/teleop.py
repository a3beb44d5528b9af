"""Scripted teleop: a system under test that plays a fixed list of velocity segments.

Plug-in ``harness.sut.teleop:ScriptedTeleop``. Parameters::

    segments:                 # played back to back from t = 0
      - {duration: 3.0, linear: 0.2}
      - {duration: 3.14, angular: 0.5}
    rate_hz: 10               # geometry_msgs/Twist on cmd_vel_topic at this rate
    cmd_vel_topic: cmd_vel

It publishes on a fixed grid of simulation times (``k * 1e9 / rate_hz`` ns, rounded, so it
never drifts), the command of the segment that holds at that time, and zero velocity once
the script has ended, so its output stays alive.
"""

from __future__ import annotations

from dataclasses import dataclass

from harness.bus import Publisher
from harness.scenario.schema import num
from harness.serde.messages import twist
from harness.sut.base import SutContext, SystemUnderTest, sut_params
from harness.sut.errors import PluginError

__all__ = ["ScriptedTeleop", "Segment", "TeleopParams", "command_at"]


@dataclass(frozen=True)
class Segment:
    """Hold ``linear`` m/s forward and ``angular`` rad/s (counter-clockwise) for ``duration`` s."""

    duration: float = num(1.0, 0.0, 3600.0, lo_open=True)
    linear: float = num(0.0, -10.0, 10.0)
    angular: float = num(0.0, -20.0, 20.0)


@dataclass(frozen=True)
class TeleopParams:
    segments: tuple[Segment, ...]
    rate_hz: float = num(10.0, 0.0, 1000.0, lo_open=True)
    cmd_vel_topic: str = "cmd_vel"


def command_at(segments: tuple[Segment, ...], t_ns: int) -> tuple[float, float]:
    """(linear, angular) the script commands at ``t_ns``; (0, 0) before 0 and after the end.

    Segment boundaries are integer nanoseconds (each duration rounded), so a segment starts
    exactly when the previous one ends.
    """
    if t_ns < 0:
        return 0.0, 0.0
    end = 0
    for seg in segments:
        end += round(seg.duration * 1e9)
        if t_ns < end:
            return seg.linear, seg.angular
    return 0.0, 0.0


class ScriptedTeleop(SystemUnderTest):
    """Publishes the scripted ``cmd_vel`` (see the module docstring)."""

    def setup(self, ctx: SutContext) -> None:
        self.params: TeleopParams = sut_params(TeleopParams, ctx)
        if not self.params.segments:
            raise PluginError(f"{ctx.field}.params.segments: give at least one segment")
        self._rate_hz: float = float(self.params.rate_hz)
        self._k = 0
        self._pub: Publisher = ctx.publisher(self.params.cmd_vel_topic,
                                             "geometry_msgs/msg/Twist")

    def _due_ns(self, k: int) -> int:
        return round(k * 1e9 / self._rate_hz)

    def step(self, now_ns: int) -> None:
        if now_ns < self._due_ns(self._k):
            return
        while self._due_ns(self._k + 1) <= now_ns:  # ticks slower than rate_hz: skip ahead
            self._k += 1
        self._k += 1
        v, w = command_at(self.params.segments, now_ns)
        self._pub.publish(twist((v, 0.0, 0.0), (0.0, 0.0, w)))
