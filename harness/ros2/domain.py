"""A ROS_DOMAIN_ID of the run's own, so parallel runs and suite workers do not hear each other.

A domain is taken by holding an exclusive ``flock`` on ``<lock dir>/domain-<id>.lock`` for the
run's lifetime; the kernel releases it when the process ends, however it ends, so a crashed run
never leaks its domain. Ids 1-101 are used (0 is everyone's default; above 101 the RTPS port
arithmetic collides with the ephemeral port range on Linux). A domain the scenario names
(``ros2.domain_id``) is locked too: two runs on one domain would hear each other's clock,
sensors and outputs, so the second is refused, and a run that picks a free id skips it.

The lock folder is shared by every user of the machine (sticky and writable by all, as
``/tmp`` is), and a lock file is opened read-only (``flock`` needs no more), so one user's
runs see another's locks instead of failing on their files."""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import stat
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from harness.errors import SrrError

__all__ = ["DomainInUse", "DomainLease", "lease_domain"]

FIRST, LAST = 1, 101


class DomainInUse(SrrError):
    """The ``ros2.domain_id`` a scenario names is held by another srr run on this machine."""


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
    """The lock folder, made if missing (a folder that cannot be made shows as lock files
    that cannot be opened: see :func:`_take`)."""
    chosen = os.environ.get("SRR_ROS2_LOCK_DIR")
    d = Path(chosen or Path(tempfile.gettempdir()) / "srr-ros2")
    try:
        d.mkdir(parents=True)
    except OSError:  # there already, or not ours to make
        return d
    if not chosen:  # made here: every user's runs lock in it (sticky, as /tmp is)
        with contextlib.suppress(OSError):
            os.chmod(d, stat.S_ISVTX | 0o777)
    return d


def _take(d: Path, domain: int) -> IO[bytes] | OSError | None:
    """The lock file of ``domain``, opened read-only (made if missing) and locked; None when
    another run holds the lock; the error when it cannot be opened or locked at all (a folder
    not writable by this user, a filesystem without ``flock``)."""
    try:
        f = os.fdopen(os.open(d / f"domain-{domain}.lock", os.O_RDONLY | os.O_CREAT, 0o644),
                      "rb")
    except OSError as err:
        return err
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as err:
        f.close()
        return None if err.errno in (errno.EWOULDBLOCK, errno.EAGAIN) else err
    return f


def lease_domain(requested: int | None) -> DomainLease:
    """``requested``, locked (:class:`DomainInUse` if another srr run holds it; not locked if
    its lock file cannot be opened), else the first free id, locked."""
    d = _lock_dir()
    if requested is not None:
        f = _take(d, requested)
        if f is None:
            raise DomainInUse(f"ROS_DOMAIN_ID {requested} is in use by another srr run on this "
                              f"machine (lock {d / f'domain-{requested}.lock'}): this run would "
                              "hear its messages; leave it unset for a free one")
        return DomainLease(requested, None if isinstance(f, OSError) else f)
    start = FIRST + os.getpid() % (LAST - FIRST + 1)  # spread concurrent starts
    unusable: OSError | None = None
    for k in range(LAST - FIRST + 1):
        domain = FIRST + (start - FIRST + k) % (LAST - FIRST + 1)
        f = _take(d, domain)
        if isinstance(f, OSError):
            unusable = f
        elif f is not None:
            return DomainLease(domain, f)
    if unusable is not None:
        raise SrrError(f"ros2: no free ROS_DOMAIN_ID {FIRST}-{LAST}: cannot lock in {d} "
                       f"({unusable.strerror or unusable}); make that folder writable by "
                       "every user of srr (on a filesystem with flock), or set ros2.domain_id")
    raise SrrError(f"ros2: every ROS_DOMAIN_ID {FIRST}-{LAST} is taken by another srr run "
                   f"(locks in {d}); set ros2.domain_id")
