"""Ctrl-C and SIGTERM: how srr stops.

SIGTERM is handled like Ctrl-C, so a run stopped by a job scheduler, a suite's timeout or a
``kill`` finalizes its bag and summary (INTERRUPTED) the way an interactive Ctrl-C does. Within
:meth:`StopRequests.installed` both set a flag that the code acts on between its steps,
whatever became of the signal where it landed; with ``at_once`` they also raise
:class:`KeyboardInterrupt` there (the ``srr`` command, a run's tick loop).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any

__all__ = ["INTERRUPTED_EXIT", "StopRequests"]

#: The exit status of a command or run stopped by Ctrl-C or SIGTERM (128 + SIGINT, as a shell
#: reports a process that SIGINT ended).
INTERRUPTED_EXIT = 130


class StopRequests:
    """Ctrl-C and SIGTERM taken as a request: :attr:`requested` is set, and the caller acts on
    it between its steps (:meth:`check` raises :class:`KeyboardInterrupt` there).

    With ``at_once`` the signal also raises :class:`KeyboardInterrupt` where it lands, as Ctrl-C
    does by default (a run's tick loop: a plug-in stuck in a tick must still stop), and
    :attr:`requested` tells the caller afterwards that whatever error came of it was the user
    stopping the run. Python raises it at whatever bytecode runs, and code there may turn it
    into another error: ``ctypes`` turns one raised while it converts an argument into
    ``ArgumentError``, so a Ctrl-C landing in a camera's OpenGL call failed the run's graph
    ("compute failed: ArgumentError: argument 1: KeyboardInterrupt") instead of interrupting
    it; code that catches every exception may drop it.

    Without ``at_once`` nothing is raised where the signal lands. CPython runs ``os.fork``'s
    at-fork hooks in Python and drops an exception raised there ("Exception ignored in
    ..."), so a Ctrl-C that arrived while a suite's worker was forked was lost and the suite
    ran on (a hang about one time in four on a loaded machine)."""

    def __init__(self, *, at_once: bool = False) -> None:
        self.requested = False
        self._at_once = at_once

    def _request(self, signum: int, frame: Any) -> None:
        self.requested = True
        if self._at_once:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def installed(self) -> Iterator[None]:
        """Take SIGINT and SIGTERM as requests within the block (main thread only; elsewhere
        the handlers stay as they are), also where the process inherited them ignored (a
        process started in the background by a shell without job control: CI jobs, scripts),
        so that ``kill -INT`` stops srr the same way wherever it was started."""
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        previous = {sig: signal.signal(sig, self._request)
                    for sig in (signal.SIGINT, signal.SIGTERM)}
        try:
            yield
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    def check(self) -> None:
        if self.requested:
            raise KeyboardInterrupt
