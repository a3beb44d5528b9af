"""The live view's error. It derives from :class:`~harness.errors.SrrError` (one line,
exit 2)."""

from __future__ import annotations

from harness.errors import SrrError

__all__ = ["LiveViewError"]


class LiveViewError(SrrError):
    """The live view (``--foxglove``) cannot start: a bad address, a port in use, or the
    foxglove-sdk package missing."""
