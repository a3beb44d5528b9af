"""The systems under test's error. It derives from :class:`~harness.errors.SrrError` (one
line, exit 2)."""

from __future__ import annotations

from harness.errors import SrrError

__all__ = ["PluginError"]


class PluginError(SrrError):
    """A system-under-test plug-in could not be loaded or broke its contract."""
