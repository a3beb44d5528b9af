"""What executors tell the suite while they work, and what they all share."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, Protocol

from harness.interrupt import INTERRUPTED_EXIT
from harness.suite.plan import RunSpec, safe_file_name
from harness.suite.results import RunOutcome

__all__ = ["Event", "Executor", "Listener", "log_path", "not_started"]


@dataclass(frozen=True)
class Event:
    """``start``: a run began (``where`` says which process or node); ``finish``: it ended."""

    kind: Literal["start", "finish"]
    spec: RunSpec
    outcome: RunOutcome | None = None
    where: str = ""


Listener = Callable[[Event], None]


class Executor(Protocol):
    """Runs specs and returns their outcomes in plan order, plus whether it was interrupted
    (Ctrl-C or SIGTERM: running runs are stopped and finalized, unstarted ones are reported
    as not started, finished ones are kept)."""

    name: str
    jobs: int

    def run(self, specs: Sequence[RunSpec], out_root: Path,
            listen: Listener) -> tuple[list[RunOutcome], bool]: ...


def log_path(out_root: Path, spec: RunSpec) -> Path:
    return out_root / "logs" / f"{safe_file_name(spec.id)}.log"


def not_started(spec: RunSpec) -> RunOutcome:
    return RunOutcome(spec=spec, verdict="INTERRUPTED", exit_code=INTERRUPTED_EXIT,
                      reasons=("not started: the suite was interrupted",), wall_s=0.0,
                      run_dir=None, report=None, log=None, digest=None, started=False)
