"""The lifecycle of everything that takes part in a run: one :class:`RunParticipant` protocol
with named hooks, called by the engine and the run pipeline, never probed for.

The engine owns the loop; a participant gets narrow hooks, in this order, and never reads
clocks or globals to find out where the run is:

1. ``setup(ctx)`` — once, before the first tick: advertise and subscribe through ``ctx``;
2. ``attach(recorder)`` — once the recorder is open on the bus, before the first tick
   (the ROS 2 bridge publishes the recorder's bytes; the live view serves them);
3. ``step(now_ns)`` — every tick, after the graphs ran and messages were delivered
   (systems under test and the ROS 2 bridge);
4. ``after_tick(now_ns)`` — after each whole tick (the live view broadcasts the time and
   paces the run);
5. ``shutdown()`` — once, however the run ends: a system under test when the loop closes
   after the last tick, the run's own participants (:mod:`harness.run.participants`) once
   the run's outputs are written;
6. ``warnings()`` — once the ticks are over: what it noticed, for the run's summary (a
   system under test is asked after its ``shutdown``).

:class:`Participant` has a no-op default for each hook: subclass it (or
:class:`~harness.sut.base.SystemUnderTest`) and override what you need. A plug-in that
subclasses neither is wrapped once, when it is loaded, by :func:`as_participant`: that is
the one place where a plain object's hooks are looked up; ``setup``, ``step`` and
``shutdown`` are required, the others are used when it defines them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from harness.sut.errors import PluginError

if TYPE_CHECKING:
    from harness.recording.recorder import Recorder
    from harness.sut.base import SutContext

__all__ = ["HOOKS", "Participant", "PlainPlugin", "RunParticipant", "as_participant",
           "is_plugin", "plugin_of"]

HOOKS = ("setup", "attach", "step", "after_tick", "warnings", "shutdown")
_REQUIRED = ("setup", "step", "shutdown")


@runtime_checkable
class RunParticipant(Protocol):
    """What the engine and the run pipeline call, in lifecycle order (module docstring)."""

    def setup(self, ctx: SutContext) -> None: ...

    def attach(self, recorder: Recorder) -> None: ...

    def step(self, now_ns: int) -> None: ...

    def after_tick(self, now_ns: int) -> None: ...

    def warnings(self) -> Sequence[str]: ...

    def shutdown(self) -> None: ...


class Participant:
    """A :class:`RunParticipant` whose hooks do nothing; override what you need."""

    def setup(self, ctx: SutContext) -> None:
        """Advertise, subscribe and read parameters (before the first tick)."""

    def attach(self, recorder: Recorder) -> None:
        """The recorder is open on the bus (before the first tick)."""

    def step(self, now_ns: int) -> None:
        """Called once per tick with the simulation time in nanoseconds."""

    def after_tick(self, now_ns: int) -> None:
        """Called after each whole tick with that tick's simulation time."""

    def warnings(self) -> Sequence[str]:
        """What it noticed during the run (the run's summary lists them)."""
        return ()

    def shutdown(self) -> None:
        """Called once at the end."""


class PlainPlugin(Participant):
    """A plug-in class that does not subclass :class:`Participant`, wrapped: each hook it
    defines is called, the others are :class:`Participant`'s no-ops. ``plugin`` is the
    wrapped object."""

    def __init__(self, plugin: Any, hooks: dict[str, Callable[..., Any]]) -> None:
        self.plugin = plugin
        self._hooks = hooks

    def setup(self, ctx: SutContext) -> None:
        self._hooks["setup"](ctx)

    def attach(self, recorder: Recorder) -> None:
        if "attach" in self._hooks:
            self._hooks["attach"](recorder)

    def step(self, now_ns: int) -> None:
        self._hooks["step"](now_ns)

    def after_tick(self, now_ns: int) -> None:
        if "after_tick" in self._hooks:
            self._hooks["after_tick"](now_ns)

    def warnings(self) -> Sequence[str]:
        if "warnings" in self._hooks:
            return tuple(self._hooks["warnings"]())
        return ()

    def shutdown(self) -> None:
        self._hooks["shutdown"]()


def as_participant(plugin: Any, where: str) -> Participant:
    """``plugin`` as a :class:`Participant`: itself when it subclasses one, else wrapped
    (:class:`PlainPlugin`) with the hooks it defines, looked up here once. A plain object
    without ``setup``, ``step`` and ``shutdown`` is a :class:`PluginError` naming ``where``."""
    if isinstance(plugin, Participant):
        return plugin
    hooks = _hooks(plugin)
    if not is_plugin(plugin):
        raise PluginError(f"{where}: {type(plugin).__module__}:{type(plugin).__qualname__} "
                          f"is not a system under test (needs setup, step and shutdown)")
    return PlainPlugin(plugin, hooks)


def is_plugin(plugin: Any) -> bool:
    """Whether ``plugin`` (a class or an instance) defines the required hooks, ``setup``,
    ``step`` and ``shutdown``."""
    hooks = _hooks(plugin)
    return all(name in hooks for name in _REQUIRED)


def _hooks(plugin: Any) -> dict[str, Callable[..., Any]]:
    """The lifecycle hooks ``plugin`` defines: the one place they are looked up by name."""
    return {name: hook for name in HOOKS if callable(hook := getattr(plugin, name, None))}


def plugin_of(participant: Participant) -> Any:
    """The plug-in object itself (unwrapped from :class:`PlainPlugin`)."""
    return participant.plugin if isinstance(participant, PlainPlugin) else participant
