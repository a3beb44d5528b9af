"""The run-participant lifecycle: plug-ins written against the plain contract (no base class)
are wrapped once, at load time, with the hooks they define; subclasses are used as they are."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from harness.bus import Bus
from harness.recording.recorder import Recorder
from harness.run.facts import sut_endpoints
from harness.scenario import SutSpec, load_scenario
from harness.sut import Participant, RunParticipant, SutContext, SystemUnderTest
from harness.sut.base import load_sut
from harness.sut.errors import PluginError
from harness.sut.participant import HOOKS, PlainPlugin, as_participant, plugin_of


class Plain:
    """A plug-in that subclasses nothing, with the optional ``warnings`` hook."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, Any]] = []

    def setup(self, ctx: Any) -> None:
        self.calls.append(("setup", ctx))

    def step(self, now_ns: int) -> None:
        self.calls.append(("step", now_ns))

    def shutdown(self) -> None:
        self.calls.append(("shutdown", None))

    def warnings(self) -> list[str]:
        return ["plain: noticed something"]


class Minimal:
    def setup(self, ctx: Any) -> None:
        pass

    def step(self, now_ns: int) -> None:
        pass

    def shutdown(self) -> None:
        pass


class NoStep:
    def setup(self, ctx: Any) -> None:
        pass

    def shutdown(self) -> None:
        pass


class Sub(SystemUnderTest):
    pass


def test_a_plain_plugin_is_wrapped_with_the_hooks_it_defines() -> None:
    plain = Plain()
    p = as_participant(plain, "s.yaml: systems_under_test[0].plugin")
    assert isinstance(p, PlainPlugin) and isinstance(p, RunParticipant)
    assert plugin_of(p) is plain
    p.setup("ctx")  # type: ignore[arg-type]
    p.attach(object())  # type: ignore[arg-type]  # not defined: a no-op
    p.step(5)
    p.after_tick(5)  # not defined: a no-op
    p.shutdown()
    assert plain.calls == [("setup", "ctx"), ("step", 5), ("shutdown", None)]
    assert p.warnings() == ("plain: noticed something",)
    assert as_participant(Minimal(), "w").warnings() == ()


def test_a_subclass_is_its_own_participant() -> None:
    sub = Sub()
    assert as_participant(sub, "w") is sub and plugin_of(sub) is sub
    assert isinstance(sub, Participant) and isinstance(sub, RunParticipant)
    assert sub.warnings() == ()
    assert {h for h in HOOKS if callable(getattr(Participant, h))} == set(HOOKS)


def test_a_plain_object_without_the_required_hooks_is_refused() -> None:
    with pytest.raises(PluginError, match=r"^s\.yaml: systems_under_test\[0\]\.plugin: "
                       r".*NoStep is not a system under test \(needs setup, step and shutdown\)"):
        as_participant(NoStep(), "s.yaml: systems_under_test[0].plugin")


def test_loaded_plain_plugins_keep_their_own_name_in_the_summary() -> None:
    spec = SutSpec(name="plain", plugin=f"{__name__}:Plain")
    p = load_sut(spec, "s.yaml: systems_under_test[0]")
    assert isinstance(p, PlainPlugin) and isinstance(plugin_of(p), Plain)
    scenario = load_scenario(Path(__file__).parents[2] / "scenarios" / "dock_empty.yaml")
    ctx = SutContext.for_spec(spec, scenario, Bus(lambda: 0), "f")
    assert sut_endpoints([("plain", p, ctx)])["plain"]["plugin"] == f"{__name__}:Plain"


CALLS: list[tuple[str, Any]] = []  # what the Probe below was called with, in order


class Probe:
    """A plain plug-in (no base class) defining every lifecycle hook."""

    def setup(self, ctx: Any) -> None:
        CALLS.clear()
        CALLS.append(("setup", ctx.name))
        ctx.publisher("/cmd_vel", "geometry_msgs/msg/Twist")  # what the scenario scores

    def attach(self, recorder: Any) -> None:
        CALLS.append(("attach", isinstance(recorder, Recorder)))

    def step(self, now_ns: int) -> None:
        CALLS.append(("step", now_ns))

    def after_tick(self, now_ns: int) -> None:
        CALLS.append(("after_tick", now_ns))

    def warnings(self) -> list[str]:
        CALLS.append(("warnings", None))
        return ["probe: saw every tick"]

    def shutdown(self) -> None:
        CALLS.append(("shutdown", None))


@pytest.mark.slow
def test_a_run_calls_every_hook_in_lifecycle_order(tmp_path: Path) -> None:
    from harness import api

    forklift = Path(__file__).parents[2] / "scenarios" / "forklift_warehouse.yaml"
    sc = api.load(forklift, duration=0.05, overrides=[
        f"systems_under_test.route_follower.plugin={__name__}:Probe"])
    res = api.run_scenario(sc, source=str(forklift), out=tmp_path / "run")
    hz = sc.physics.tick_hz
    ticks = [k * 1_000_000_000 // hz for k in range(sc.n_ticks)]
    # attached to the run's recorder, before the first tick
    assert CALLS[:2] == [("setup", "route_follower"), ("attach", True)]
    assert CALLS[2:-2] == [(hook, t) for t in ticks for hook in ("step", "after_tick")]
    assert CALLS[-2:] == [("shutdown", None), ("warnings", None)]
    assert "probe: saw every tick" in res.summary["warnings"]
    assert res.summary["sut_endpoints"]["route_follower"]["plugin"] == f"{__name__}:Probe"
