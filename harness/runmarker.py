"""The in-progress marker of a run directory: ``incomplete.json``.

A run writes it before anything else and removes it right after ``summary.json`` is in place,
so a directory that holds it is a run that did not finish (it is still going, or it was
killed). It says how far the run got (``phase``: ``recording`` during the tick loop and
until the bag is closed, ``finalizing`` from the closed bag, every message written, until
the summary is written), which process writes the run (``pid`` and ``host``; whether it is
alive is its lock's to say, :mod:`harness.runlock`), the scenario file and the command that
reproduces the run; ``srr recover`` reads it. It holds no wall-clock time.
"""

from __future__ import annotations

import json
import os
import socket
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

from harness.atomic import write_json_atomic

__all__ = ["MARKER", "Phase", "clear", "killed_while", "mark", "read"]

MARKER = "incomplete.json"
Phase = Literal["recording", "finalizing"]


def mark(run_dir: Path, phase: Phase, **info: Any) -> None:
    """Write (atomically) or update the marker, naming this process as the writer."""
    write_json_atomic(Path(run_dir) / MARKER, {"phase": phase, "pid": os.getpid(),
                                               "host": socket.gethostname(), **info})


def read(run_dir: Path) -> dict[str, Any] | None:
    """The marker's content; None when there is none. It is renamed into place, so a crash
    never leaves half of one; one that is not a JSON object reads as ``{"phase": "unknown"}``."""
    path = Path(run_dir) / MARKER
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return {"phase": "unknown"}
    return data if isinstance(data, dict) else {"phase": "unknown"}


def killed_while(marker: Mapping[str, Any]) -> str:
    """What a killed run was doing, for messages: its marker's phase (``recording``,
    ``finalizing``), or ``running`` for a marker that does not say (one that does not read)."""
    phase = marker.get("phase")
    return phase if phase in ("recording", "finalizing") else "running"


def clear(run_dir: Path) -> None:
    (Path(run_dir) / MARKER).unlink(missing_ok=True)
