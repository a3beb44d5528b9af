"""Systems under test: the plug-in contract and the bundled reference systems.

A plug-in subclasses :class:`SystemUnderTest` and is named in a scenario as ``"module:Class"``;
see :mod:`harness.sut.base` for the hooks and :class:`SutContext` for what it may touch, and
:mod:`harness.sut.participant` for the lifecycle of everything that takes part in a run.
Names are imported from their submodules on first use (:mod:`harness._lazy`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.sut.base import SutContext, SystemUnderTest, load_sut, load_suts, sut_params
    from harness.sut.participant import Participant, RunParticipant, as_participant

__all__ = [
    "Participant",
    "RunParticipant",
    "SutContext",
    "SystemUnderTest",
    "as_participant",
    "load_sut",
    "load_suts",
    "sut_params",
]

_WHERE = {
    "Participant": "participant",
    "RunParticipant": "participant",
    "as_participant": "participant",
    "SutContext": "base",
    "SystemUnderTest": "base",
    "load_sut": "base",
    "load_suts": "base",
    "sut_params": "base",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
