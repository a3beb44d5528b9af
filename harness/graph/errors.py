"""The action graph's error: a graph that cannot be built or evaluated. It derives from
:class:`~harness.errors.SrrError` (one line, exit 2)."""

from __future__ import annotations

from harness.errors import SrrError

__all__ = ["GraphError"]


class GraphError(SrrError):
    """An action graph could not be built: unknown node type, attribute or connection."""
