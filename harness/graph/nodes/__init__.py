"""Built-in node types; importing :mod:`harness.graph` registers them."""

from __future__ import annotations

__all__: list[str] = []
