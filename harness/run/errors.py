"""The run pipeline's error. It derives from :class:`~harness.errors.SrrError` (one line);
a run that cannot be trusted exits 3."""

from __future__ import annotations

from harness.errors import SrrError

__all__ = ["InvalidRunError"]


class InvalidRunError(SrrError):
    """A health gate tripped, so the run's scores cannot be trusted."""

    exit_code = 3
