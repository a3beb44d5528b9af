"""Where a scenario's value came from: the one lookup of an origins table (field path → the
file, or the ``--set`` flag, that gave the value there), for error messages and for the
folder a relative path in the value is relative to."""

from __future__ import annotations

from collections.abc import Mapping

__all__ = ["SET_FLAG", "origin_of"]

#: The origin of a value a ``--set`` gave (errors about it name the flag).
SET_FLAG = "--set"


def origin_of(origins: Mapping[str, str], path: str, *, files_only: bool = False) -> str | None:
    """The origin of the value at field ``path`` (``robots[1].odometry.rate``): that of the
    most specific entry of ``origins`` that is ``path`` or holds it (``robots[1]``, then
    ``robots``; an entry a ``--set`` gave, ``robots[1].odometry``, before both), or None.
    ``files_only``: the file, passing over what ``--set`` gave (a relative path set on the
    command line is relative to the scenario file it was set on, as one written there)."""
    best = ""
    for key, origin in origins.items():
        if (len(key) > len(best) and not (files_only and origin == SET_FLAG)
                and (path == key or path.startswith((f"{key}.", f"{key}[")))):
            best = key
    return origins[best] if best else None
