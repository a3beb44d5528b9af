"""The tick loop: the engine owns time, the graphs, the bus and the systems under test.

Per tick ``k`` (simulation time ``k * 1e9 // tick_hz`` ns, integer so it never drifts):

1. workers on foot move to their pose at this time (a pure function of time); every action
   graph evaluates (sensors and state publish, control graphs apply the latest
   commands to the articulations);
2. the bus delivers queued messages; each system under test steps; the bus delivers again
   (so a ``cmd_vel`` published at tick ``k`` reaches the control graph at tick ``k + 1``);
3. physics advances ``substeps`` fixed steps to the next tick.

Single-threaded and free of wall-clock reads, so a scenario and a seed give the same bytes.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from harness.builders import BuildContext, build_all
from harness.bus import Bus, Envelope
from harness.graph import GraphStage
from harness.scenario import Scenario
from harness.sim import World
from harness.sut.base import SutContext, load_suts, setup_suts, step_suts
from harness.sut.participant import Participant
from harness.wiring import Plan, plan_wiring

__all__ = ["Closeable", "EvalContext", "Joined", "Simulation", "join"]


class Closeable(Protocol):
    """A resource a run holds until it ends: :meth:`Simulation.close` closes it."""

    def close(self) -> None: ...


@dataclass
class EvalContext:
    """What graph nodes see while they compute: the tick, its time, the world and the bus.
    ``extras``: the run's shared resources by name (the render products, the RTSP servers),
    created by the nodes on first use and closed when the run ends."""

    tick: int
    time_ns: int
    world: World
    bus: Bus
    seed: int = 0
    extras: dict[str, Closeable] = field(default_factory=dict)


@dataclass(frozen=True)
class Joined:
    """A participant that is not one of the scenario's plug-ins but steps with them, after
    them (the ROS 2 bridge, which stands for the external nodes): its name, the participant
    (:class:`~harness.sut.participant.RunParticipant`), ``where`` its errors and the wiring
    checks name and its parameters."""

    name: str
    participant: Participant
    where: str
    params: Mapping[str, Any] = field(default_factory=dict)


def join(joined: Sequence[Joined], scenario: Scenario, bus: Bus
         ) -> list[tuple[str, Participant, SutContext]]:
    """``joined`` as systems under test on ``bus``: (name, participant, context), in order
    (a simulation's and an open-loop replay's)."""
    return [(j.name, j.participant,
             SutContext(name=j.name, params=j.params, scenario=scenario, seed=scenario.seed,
                        field=j.where, bus=bus))
            for j in joined]


class Simulation:
    """A built scenario, ready to tick. Build it, :meth:`start`, :meth:`run`, :meth:`close`.
    ``joined`` take part as systems under test after the scenario's own, in order."""

    def __init__(self, scenario: Scenario, *, srr_gt: bool | None = None,
                 source: str = "<scenario>", joined: Sequence[Joined] = ()) -> None:
        self.scenario = scenario
        self.source = source
        self.srr_gt = scenario.srr_gt if srr_gt is None else srr_gt
        self.world = World.build(scenario, source)
        self.tick_index = 0
        self.time_ns = 0
        self.bus = Bus(lambda: self.time_ns)
        self.ctx = EvalContext(0, 0, self.world, self.bus, seed=scenario.seed)
        self.stage = GraphStage()
        build = BuildContext(scenario, self.world, self.srr_gt, source)
        with self.stage:
            self.graph_paths = build_all(build)
        self.origins = build.origins  # node path → scenario field, for the wiring checks
        self.custom_graphs = build.custom_graphs  # graph path → graphs[i] (harness.output)
        self.suts: list[tuple[str, Participant, SutContext]] = load_suts(
            scenario, self.bus, source)
        self.suts += join(joined, scenario, self.bus)
        self._started = False

    def plan(self) -> Plan:
        """The wiring plan: what every graph node and (set-up) system under test publishes
        and subscribes, and the TF edges the graphs publish. Starts the systems under test."""
        if not self._started:
            self.start()
        return plan_wiring(self.stage, self.origins, self.suts, self.scenario, self.source,
                           self.world)

    def add_tap(self, tap: Callable[[Envelope], None]) -> None:
        self.bus.add_tap(tap)

    def start(self) -> None:
        setup_suts(self.suts)
        self._started = True

    def step_tick(self) -> None:
        """Run one whole tick (graphs, delivery, systems under test, physics)."""
        if not self._started:
            self.start()
        k = self.tick_index
        self.time_ns = k * 1_000_000_000 // self.scenario.physics.tick_hz
        self.ctx.tick, self.ctx.time_ns = k, self.time_ns
        self.world.update_workers(self.time_ns)
        with self.stage:
            self.stage.evaluate(self.ctx)
        self.bus.spin()
        step_suts(self.suts, self.time_ns)
        self.bus.spin()
        self.world.step(self.scenario.physics.substeps)
        self.tick_index += 1

    def run(self, n_ticks: int, progress: Callable[[int, int], None] | None = None) -> None:
        for _ in range(n_ticks):
            self.step_tick()
            if progress is not None:
                progress(self.tick_index, n_ticks)

    def close(self) -> None:
        for _, sut, _ in self.suts:
            sut.shutdown()
        for extra in self.ctx.extras.values():  # e.g. the render products' GL contexts
            extra.close()
