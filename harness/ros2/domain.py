"""A ROS_DOMAIN_ID of the run's own, so parallel runs and suite workers do not hear each other.

A domain is taken by holding an exclusive ``flock`` on ``<lock dir>/domain-<id>.lock`` for the
run's lifetime; the kernel releases it when the process ends, however it ends, so a crashed run
never leaks its domain. Ids 1-101 are used (0 is everyone's default; above 101 the RTPS port
arithmetic collides with the ephemeral port range on Linux)."""

from __future__ import annotations

import contextlib
import fcntl
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from harness.errors import SrrError

__all__ = ["DomainLease", "lease_domain"]

FIRST, LAST = 1, 101


@dataclass
class DomainLease:
    domain_id: int
    _file: IO[bytes] | None = None

    def release(self) -> None:
        if self._file is not None:
            with contextlib.suppress(OSError):
                fcntl.flock(self._file, fcntl.LOCK_UN)
            self._file.close()
            self._file = None


def _lock_dir() -> Path:
    d = Path(os.environ.get("SRR_ROS2_LOCK_DIR") or Path(tempfile.gettempdir()) / "srr-ros2")
    d.mkdir(parents=True, exist_ok=True)
    return d


def lease_domain(requested: int | None) -> DomainLease:
    """``requested`` as given (no lock: the user chose it), else the first free id, locked."""
    if requested is not None:
        return DomainLease(requested)
    d = _lock_dir()
    start = FIRST + os.getpid() % (LAST - FIRST + 1)  # spread concurrent starts
    for k in range(LAST - FIRST + 1):
        domain = FIRST + (start - FIRST + k) % (LAST - FIRST + 1)
        f = (d / f"domain-{domain}.lock").open("ab")
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            continue
        return DomainLease(domain, f)
    raise SrrError(f"ros2: every ROS_DOMAIN_ID {FIRST}-{LAST} is taken by another srr run "
                   f"(locks in {d}); set ros2.domain_id")
