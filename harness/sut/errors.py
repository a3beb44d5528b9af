"""The systems under test's errors. They derive from :class:`~harness.errors.SrrError` (one
line, exit 2; a plug-in that raised during the run: INVALID, exit 3)."""

from __future__ import annotations

import traceback

from harness.errors import RunStopped, SrrError, reason

__all__ = ["PluginError", "SutRaised"]


class PluginError(SrrError):
    """A system-under-test plug-in could not be loaded or broke its contract."""


class SutRaised(RunStopped):
    """A system under test raised ``err`` in one of its hooks during the run: the run stops
    there, INVALID (health gate ``sut_raised:<name>``), what was recorded kept, and the
    traceback goes beside the recording. The code under test broke, not the harness."""

    def __init__(self, name: str, where: str, err: Exception) -> None:
        super().__init__(
            f"sut_raised:{name}",
            f"system under test {name} raised {type(err).__name__} {where}: {reason(err)}",
            "".join(traceback.format_exception(err)))
