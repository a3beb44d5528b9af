"""Who owns a run directory: an OS lock on its ``run.lock``.

The process that writes a run directory (``srr run``, ``srr replay``; ``srr recover`` while it
rebuilds one) holds an exclusive ``flock`` on ``RUN_DIR/run.lock`` from the moment it creates
the directory until it has finished with it, then removes the file. The kernel releases the
lock when the process ends, however it ends (``kill -9`` included), so a lock file left by a
dead process is free and blocks nothing. The file names its holder (pid, host and what it is
doing), for the message.

Every command that reads or changes a run directory first calls :func:`refuse_if_live`: while
the lock is held it raises :class:`~harness.errors.RunInUseError` (one line, exit 2) and
nothing is touched. A reader takes the lock shared, non-blocking, and drops it at once.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import os
import socket
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from harness.errors import RunInUseError, SrrError

__all__ = ["LOCK", "Activity", "Owner", "live_owner", "owning", "refuse_if_live"]

LOCK = "run.lock"
Activity = Literal["written", "recovered"]


@dataclass(frozen=True)
class Owner:
    """The live holder of a run directory's lock (``pid`` None: it has not said yet)."""

    pid: int | None
    host: str
    activity: str

    def refusal(self, run_dir: Path) -> str:
        who = (f"pid {self.pid} on {self.host}" if self.pid is not None
               else "another process")
        stop = f" or stop it (kill {self.pid})" if self.pid is not None else ""
        return (f"{run_dir} is being {self.activity} by {who}; wait until it ends{stop}, "
                "then try again")


def _owner_of(fd: int) -> Owner:
    try:
        data = json.loads(os.pread(fd, 4096, 0).decode("utf-8"))
        pid, host, activity = data["pid"], data["host"], data["activity"]
        if isinstance(pid, int) and isinstance(host, str) and isinstance(activity, str):
            return Owner(pid, host, activity)
    except (OSError, ValueError, KeyError, TypeError):
        pass
    return Owner(None, "?", "written")  # between taking the lock and saying who it is


def live_owner(run_dir: str | Path) -> Owner | None:
    """The process that holds ``run_dir``'s lock now; None when none does (no lock file, a
    lock left by a dead process, or a filesystem without locks, where none can be held)."""
    try:
        fd = os.open(Path(run_dir) / LOCK, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return _owner_of(fd)
    except OSError:
        return None
    finally:
        os.close(fd)  # drops the shared lock, if taken
    return None


def refuse_if_live(run_dir: str | Path) -> None:
    """Raise :class:`RunInUseError` when a live process owns ``run_dir``."""
    owner = live_owner(run_dir)
    if owner is not None:
        raise RunInUseError(owner.refusal(Path(run_dir)))


def _lock_exclusive(fd: int, tries: int = 20) -> None:
    """``flock(LOCK_EX)`` without waiting for an owner. A reader's shared lock
    (:func:`live_owner`) lasts microseconds, so a refusal is tried again for a moment
    (0.1 s) before it is taken as an owner's: a reader looking never stops a run."""
    for attempt in range(tries):
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return
        except BlockingIOError:
            if attempt == tries - 1:
                raise
            time.sleep(0.005)


@contextlib.contextmanager
def owning(run_dir: Path, activity: Activity, *, fresh: bool) -> Iterator[Path]:
    """Hold ``run_dir``'s lock for the block, then remove the lock file and release it.

    ``fresh``: the directory is created if need be (a new run: the caller has checked it is
    empty or absent; the ROS 2 bridge's external processes may have logged in it since);
    otherwise it must exist. Raises :class:`RunInUseError` when another process holds the
    lock, :class:`SrrError` when the lock cannot be taken; nothing is changed then (but a
    directory created for a fresh run). An existing directory this process may not write
    (read-only media) is only checked for a live owner: it cannot be changed from here."""
    path = run_dir / LOCK
    if fresh:
        run_dir.mkdir(parents=True, exist_ok=True)
    created = True
    try:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o644)
        except FileExistsError:
            created = False
            fd = os.open(path, os.O_RDWR | os.O_CLOEXEC)
    except OSError as err:
        if not fresh and err.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
            refuse_if_live(run_dir)
            yield run_dir
            return
        raise SrrError(f"{path}: cannot open the run directory's lock: "
                       f"{err.strerror or err}") from err
    try:
        _lock_exclusive(fd)
    except BlockingIOError:
        owner = _owner_of(fd)
        os.close(fd)
        raise RunInUseError(owner.refusal(run_dir)) from None
    except OSError as err:
        os.close(fd)
        if created:
            path.unlink(missing_ok=True)
        raise SrrError(f"{path}: cannot lock the run directory: "
                       f"{err.strerror or err}") from err
    try:
        me = {"pid": os.getpid(), "host": socket.gethostname(), "activity": activity}
        os.ftruncate(fd, 0)
        os.pwrite(fd, json.dumps(me).encode("utf-8"), 0)
        yield run_dir
    finally:
        path.unlink(missing_ok=True)  # while still holding it: whoever opens it finds it free
        os.close(fd)
