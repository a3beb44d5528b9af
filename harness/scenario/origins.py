"""Where a scenario's value came from, for error messages: the one lookup of an origins table
(field path → the file, or the command-line flag, that gave the value there)."""

from __future__ import annotations

from collections.abc import Mapping

__all__ = ["origin_of"]


def origin_of(origins: Mapping[str, str], path: str) -> str | None:
    """The origin of the value at field ``path`` (``robots[1].odometry.rate``): that of the
    most specific entry of ``origins`` that is ``path`` or holds it (``robots[1]``, then
    ``robots``; an entry ``--set`` gave, ``robots[1].odometry``, before both), or None."""
    best = ""
    for key in origins:
        if len(key) > len(best) and (path == key or path.startswith((f"{key}.", f"{key}["))):
            best = key
    return origins[best] if best else None
