"""PLANTED DEFECT — not a real safety monitor. The reference safety monitor
(:class:`harness.sut.safety_monitor.SafetyMonitor`) with a bug put there on purpose, so that
``srr search`` has a failure to find (benchmarks/bench_search.py, tests/search):

while the simulation clock is inside ``[blind_from, blind_to)`` seconds, it ignores every
tracked person whose speed — the track's displacement over the last ``window_s`` seconds —
is above ``blind_speed`` m/s. A worker who crosses the loading ROI fast enough, and at the
wrong moment, is not seen: the mute stays on while they are in the ROI. Any other worker is
seen as by the reference monitor, so the defect shows only in a narrow region of the
scenario's parameters (the worker's speed and start delay).

Scenario: ``scenarios/planted/dock_crossing_blind_spot.yaml`` (run from the project root:
the plug-in is ``scenarios.planted.blind_spot_monitor:BlindSpotSafetyMonitor``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from harness.scenario.schema import num
from harness.sut.base import SutContext, sut_params
from harness.sut.safety_monitor import SafetyMonitor, SafetyMonitorParams

__all__ = ["BlindSpotParams", "BlindSpotSafetyMonitor"]


@dataclass(frozen=True)
class BlindSpotParams(SafetyMonitorParams):
    blind_speed: float = num(2.0, 0.0, 100.0)
    blind_from: float = num(23.5, 0.0, 3600.0)
    blind_to: float = num(24.5, 0.0, 3600.0)
    window_s: float = num(0.8, 0.05, 10.0)


class BlindSpotSafetyMonitor(SafetyMonitor):
    def setup(self, ctx: SutContext) -> None:
        self.blind: BlindSpotParams = sut_params(BlindSpotParams, ctx)
        own = {f.name for f in dataclasses.fields(BlindSpotParams)} - {
            f.name for f in dataclasses.fields(SafetyMonitorParams)}
        # the reference monitor reads its own parameters (the same endpoints list: the
        # wiring checks see what it subscribes and publishes)
        super().setup(dataclasses.replace(ctx, params={
            k: v for k, v in ctx.params.items() if k not in own}))
        self.history: dict[int, list[tuple[float, float, float]]] = {}

    def _speed(self, track: int, t: float, x: float, y: float) -> float:
        h = [s for s in self.history.get(track, []) if t - s[0] <= self.blind.window_s]
        h.append((t, x, y))
        self.history[track] = h
        t0, x0, y0 = h[0]
        return math.hypot(x - x0, y - y0) / (t - t0) if t - t0 >= 0.5 * self.blind.window_s \
            else 0.0

    def _on_tracks(self, msg: Any) -> None:
        people: list[tuple[float, float]] = []
        for m in msg.markers:
            if m.action == 3:  # DELETEALL
                people = []
            elif m.action == 0 and m.ns == self.p.person_class:
                t = m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
                x, y = m.pose.position.x, m.pose.position.y
                fast = self._speed(m.id, t, x, y) > self.blind.blind_speed
                if fast and self.blind.blind_from <= t < self.blind.blind_to:
                    continue  # the planted defect: a fast person in the window is not seen
                people.append((x, y))
        self.people = people
