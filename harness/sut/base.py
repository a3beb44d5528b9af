"""The plug-in contract for systems under test.

A system under test is a class named in the scenario as ``"module:Class"``. The engine owns
the loop; a plug-in gets narrow hooks and never reads clocks or globals:

* ``setup(ctx)`` once, before the first tick: advertise and subscribe through ``ctx``;
* ``step(now_ns)`` once per tick after the graphs ran and messages were delivered;
* ``shutdown()`` once at the end.

Messages arrive through subscription callbacks (delivered between graph evaluation and
``step``); time is only what the engine passes in. These are three of the hooks of
:class:`~harness.sut.participant.RunParticipant`, the lifecycle of everything that takes part
in a run; a plug-in class that does not subclass :class:`SystemUnderTest` is wrapped once, as
it is loaded (:func:`~harness.sut.participant.as_participant`).
"""

from __future__ import annotations

import dataclasses
import importlib
import os
import sys
import traceback
import zlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any, Literal

import numpy as np

from harness.bus import Bus, Envelope, Publisher, Qos, TopicNameError, remap_topic
from harness.bus.endpoints import Endpoint
from harness.errors import ScenarioError, SrrError, reason
from harness.scenario import RobotSpec, Scenario, SutSpec, validate_dataclass
from harness.serde.messages import UnknownMessageType, require_msgtype
from harness.sut.errors import PluginError, SutRaised
from harness.sut.participant import Participant, as_participant, is_plugin

__all__ = ["SutContext", "SystemUnderTest", "import_project_module", "load_sut", "load_suts",
           "setup_suts", "step_suts", "sut_params"]


@dataclass(frozen=True)
class SutContext:
    """What a plug-in may touch: its name and parameters, the scenario, a seeded RNG source
    and the bus (through :meth:`publisher` and :meth:`subscribe` only).

    Relative topics resolve in ``namespace``, then ``remap`` rules apply (ROS 2 style: both
    sides resolve in the namespace). ``robot`` is the robot the plug-in is bound to (None:
    none); :meth:`frame` gives that robot's frame ids. ``endpoints`` records every topic the
    plug-in advertised or subscribed, for the wiring checks. ``field`` prefixes the plug-in's
    errors (``scenario.yaml: systems_under_test[0]``); ``path`` is its entry's field path in
    ``scenario`` and ``source`` the scenario file, so that an error in a parameter names the
    file or the ``--set`` flag that gave it (empty for a participant no entry declares)."""

    name: str
    params: Mapping[str, Any]
    scenario: Scenario
    seed: int
    field: str
    bus: Bus
    namespace: str = ""
    remap: Mapping[str, str] = dataclasses.field(default_factory=dict)
    robot: RobotSpec | None = None
    endpoints: list[Endpoint] = dataclasses.field(default_factory=list)
    path: str = ""
    source: str = "<scenario>"

    @classmethod
    def for_spec(cls, spec: SutSpec, scenario: Scenario, bus: Bus, field: str, *,
                 path: str = "", source: str = "<scenario>") -> SutContext:
        """The context of ``spec``: its parameters, namespace, remapping and bound robot."""
        robot = next((r for r in scenario.robots if r.name == spec.robot), None) \
            if spec.robot else None
        return cls(name=spec.name, params=spec.params, scenario=scenario, seed=scenario.seed,
                   field=field, bus=bus, namespace=spec.namespace or "", remap=spec.remap,
                   robot=robot, path=path, source=source)

    def rng(self) -> np.random.Generator:
        """A generator seeded from the scenario seed and the plug-in's name."""
        return np.random.default_rng([self.seed, zlib.crc32(self.name.encode())])

    def frame(self, name: str) -> str:
        """Frame id ``name`` of the bound robot (its frame prefix in front), or ``name``."""
        return self.robot.frame(name) if self.robot is not None else name

    def topic(self, name: str) -> str:
        """The fully qualified topic a relative or absolute ``name`` resolves to here."""
        try:
            return remap_topic(name, self.namespace, dict(self.remap))
        except TopicNameError as err:
            raise PluginError(f"{self.field}: {err}") from err

    def _declare(self, kind: Literal["pub", "sub"], name: str, msgtype: str) -> str:
        topic = self.topic(name)
        try:
            require_msgtype(msgtype)
        except UnknownMessageType as err:
            call = "publisher" if kind == "pub" else "subscribe"
            raise PluginError(f"{self.field}: {call}({name!r}, {msgtype!r}): {err}") from err
        self.endpoints.append(Endpoint(kind, name, msgtype, self.namespace, input=name,
                                       rules=tuple(self.remap.items())))
        return topic

    def publisher(self, topic: str, msgtype: str, qos: Qos | None = None) -> Publisher:
        return self.bus.advertise(self._declare("pub", topic, msgtype), msgtype, qos)

    def subscribe(self, topic: str, msgtype: str, callback: Callable[[Any], None]) -> None:
        self.bus.subscribe(self._declare("sub", topic, msgtype), msgtype,
                           self._guarded(topic, callback))

    def subscribe_envelopes(self, topic: str, msgtype: str,
                            callback: Callable[[Envelope], None]) -> None:
        """:meth:`subscribe`, handing ``callback`` each message's envelope (its ``msg`` built
        when read: see :meth:`harness.bus.Bus.subscribe_envelopes`)."""
        self.bus.subscribe_envelopes(self._declare("sub", topic, msgtype), msgtype,
                                     self._guarded(topic, callback))

    def _guarded(self, topic: str, callback: Callable[[Any], None]) -> Callable[[Any], None]:
        """``callback``, an error it raises (the plug-in's own) turned into :class:`SutRaised`."""
        name = self.name

        def deliver(message: Any) -> None:
            try:
                callback(message)
            except SrrError:
                raise
            except Exception as err:
                raise SutRaised(name, f"in its callback on {topic}", err) from err

        return deliver


class SystemUnderTest(Participant):
    """Base class for plug-ins: every hook of :class:`~harness.sut.participant.Participant`
    does nothing; override what you need (``setup``, ``step`` and ``shutdown``, mostly)."""


def sut_params(cls: type[Any], ctx: SutContext) -> Any:
    """Validate ``ctx.params`` into the plug-in's frozen parameter dataclass. An error names
    the file or the ``--set`` flag that gave the parameter (``--set:
    systems_under_test[0].params.bogus: unknown field``)."""
    if not ctx.path:  # no entry of the scenario: named by ctx.field alone
        try:
            return validate_dataclass(cls, dict(ctx.params), "<scenario>", f"{ctx.field}.params")
        except ScenarioError as err:
            raise PluginError(f"{err.field}: {err.message}") from err
    try:
        return validate_dataclass(cls, dict(ctx.params),
                                  lambda path: ctx.scenario.file_for(path, ctx.source),
                                  f"{ctx.path}.params")
    except ScenarioError as err:
        raise PluginError(str(err)) from err


def import_project_module(name: str) -> ModuleType:
    """Import ``name`` from the Python path or, after it, the current directory (as ``python
    -m`` would), so a project's own plug-ins and graph builders work from its root without
    being installed. Errors are the import's own; callers name the field."""
    here = os.getcwd()
    if here not in sys.path:
        sys.path.append(here)
    return importlib.import_module(name)


def load_sut(spec: SutSpec, field: str) -> Participant:
    """Import ``spec.plugin`` (``"module:Class"``) and instantiate it, as a
    :class:`~harness.sut.participant.Participant` (a class that does not subclass one is
    wrapped, :func:`~harness.sut.participant.as_participant`). Modules are found on
    the Python path and, after it, in the current directory (as ``python -m`` would), so a
    project's own plug-ins work from its root without being installed."""
    module_name, _, attr = spec.plugin.partition(":")
    try:
        module = import_project_module(module_name)
    except Exception as err:  # ImportError, a syntax error, the module raising as it imports
        raise PluginError(f"{field}.plugin: cannot import module {module_name!r}: "
                          f"{type(err).__name__}: {reason(err)}") from err
    cls = getattr(module, attr, None)
    if cls is None:
        raise PluginError(f"{field}.plugin: module {module_name!r} has no {attr!r}")
    if not isinstance(cls, type) or not is_plugin(cls):
        raise PluginError(f"{field}.plugin: {spec.plugin} is not a system under test "
                          "(needs setup, step and shutdown)")
    try:
        made = cls()
    except Exception as err:  # its parameters come in setup(ctx), not to its constructor
        raise PluginError(f"{field}.plugin: {spec.plugin}() failed ({type(err).__name__}: "
                          f"{reason(err)}); a plug-in is made with no arguments and gets its "
                          "parameters in setup(ctx)") from err
    return as_participant(made, f"{field}.plugin")


def load_suts(scenario: Scenario, bus: Bus, source: str = "<scenario>"
              ) -> list[tuple[str, Participant, SutContext]]:
    """Every enabled system under test of ``scenario``, loaded (not yet set up), with its
    context on ``bus``: (name, plug-in, context) in scenario order."""
    out = []
    for i, spec in enumerate(scenario.systems_under_test):
        if not spec.enabled:
            continue
        path = f"systems_under_test[{i}]"
        where = f"{source}: {path}"
        # the plug-in's file or the --set that gave it answers for an import error
        plugin_from = f"{scenario.file_for(f'{path}.plugin', source)}: {path}"
        out.append((spec.name, load_sut(spec, plugin_from),
                    SutContext.for_spec(spec, scenario, bus, where, path=path, source=source)))
    return out


def setup_suts(suts: Sequence[tuple[str, Participant, SutContext]]) -> None:
    """``setup`` every system under test, in order (before the run: its wiring is planned
    from what they advertise). An error a plug-in raises there (not an
    :class:`~harness.errors.SrrError`: one that breaks the contract says so itself) is a
    :class:`PluginError` naming its field and where in the plug-in it was raised."""
    for name, sut, ctx in suts:
        try:
            sut.setup(ctx)
        except SrrError:
            raise
        except Exception as err:
            frame = traceback.extract_tb(err.__traceback__)[-1]
            raise PluginError(f"{ctx.field}: {name} raised {type(err).__name__} in setup: "
                              f"{reason(err)} ({frame.filename}:{frame.lineno})") from err


def step_suts(suts: Sequence[tuple[str, Participant, SutContext]], now_ns: int) -> None:
    """``step(now_ns)`` every system under test, in order; an error a plug-in raises (not an
    :class:`~harness.errors.SrrError`) stops the run: :class:`SutRaised`."""
    for name, sut, _ in suts:
        try:
            sut.step(now_ns)
        except SrrError:
            raise
        except Exception as err:
            raise SutRaised(name, f"in step at {now_ns / 1e9:g} s of simulated time",
                            err) from err
