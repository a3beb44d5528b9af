"""Runs in parallel worker processes on this machine, at most ``jobs`` at a time.

With ``fork=True`` (what ``srr suite`` asks for) the runs go to *hosts*
(:mod:`harness.suite.host`): one long-lived process per slot, forked from the suite's (which
has imported srr, MuJoCo, NumPy and pandas: nothing to import again), that runs its runs one
after another and keeps its OpenGL context between them — made once per host, while the
suite is still being checked (``srr suite`` forks its hosts early:
:func:`harness.suite.host.start_early`), instead of once per run (0.3 s alone, 1.4 s each when
16 processes make one at once on a GPU host). A host is replaced by a fresh one after
:data:`harness.suite.host.MAX_RUNS` runs, after a run that ended otherwise than 0 or 1 (failed,
interrupted, could not start) or left a thread running, and when it dies; once no run is left
to start, an idle host ends at once, beside the last runs. Forking is done only
on Linux and only while the suite's process is as clean as a fresh one — no other Python
thread (a live progress display), no OpenGL context ever made here (its driver's threads and
locks would not survive the fork); else, and by default, each run is a fresh ``python -m
harness.suite.worker``. Either way a run records the same bytes: a host puts back what a run
could leave to the next (see :mod:`harness.suite.host`), and tests compare a host's
third run with a fresh process's.

What one run breaks costs that run only: a segfault, an out-of-memory kill or ``os._exit`` in
a host (INVALID, with the signal or the exit status as the reason; the slot gets a fresh host),
a hang (its timeout). A run past its timeout gets SIGTERM (it finalizes its bag and summary),
then SIGKILL after ``grace_s``; in a host, the host goes with it. Ctrl-C (or SIGTERM to the
suite) stops the runs the same way and keeps every finished one; if the suite's process is
killed outright, its hosts get SIGTERM (their runs finalize) and end. Each run's output goes to
``OUT/logs/<run id>.log`` (a host points its stdout and stderr at it for the run); each run's
``peak_rss_mb`` is its own (a host resets its peak before each run, see
:mod:`harness.suite.host`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import select
import signal
import subprocess
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from harness.interrupt import StopRequests
from harness.suite.events import Event, Listener, log_path, not_started
from harness.suite.host import (
    MAX_RUNS,
    Host,
    fork_host,
    fork_safe_here,
    take_early,
)
from harness.suite.plan import RunSpec
from harness.suite.results import RunOutcome, crash_reason, outcome_of
from harness.suite.timeline import clock_path, take_clock
from harness.suite.worker import fresh_process, peak_rss_mb

__all__ = ["LocalExecutor", "fork_safe"]


def fork_safe() -> bool:
    """Whether a worker may be forked from this process: Linux, no other Python thread, and
    no OpenGL context made here (:func:`harness.suite.host.fork_safe_here`)."""
    return fork_safe_here()


@dataclass
class _Running:
    spec: RunSpec
    t0: float  # when it was submitted
    host: Host | None = None  # the host running it, else ``proc``, a fresh process
    proc: subprocess.Popen[bytes] | None = None
    kill_at: float | None = None  # set once SIGTERM was sent
    timed_out: bool = False
    returncode: int | None = None
    peak_rss_mb: float | None = None
    peak_rss_note: str | None = None
    reaped: float | None = None  # time.monotonic() when it was found ended
    leaving: bool = True  # its host goes after this run

    @property
    def pid(self) -> int:
        if self.host is not None:
            return self.host.pid
        assert self.proc is not None
        return self.proc.pid


def _last_line(path: Path) -> str | None:
    try:
        lines = [x.strip() for x in path.read_text(encoding="utf-8", errors="replace")
                 .splitlines() if x.strip()]
    except OSError:
        return None
    return lines[-1] if lines else None


class LocalExecutor:
    name = "local"

    def __init__(self, jobs: int, *, baselines: Path | None = None, grace_s: float = 10.0,
                 poll_s: float = 0.05, fork: bool = False, max_host_runs: int = MAX_RUNS) -> None:
        self.jobs = max(1, jobs)
        self.baselines = baselines
        self.grace_s = grace_s
        self.poll_s = poll_s
        #: Run in hosts forked from this process when that is safe (:func:`fork_safe`).
        self.fork = fork
        #: Runs a host does before a fresh one replaces it (:data:`harness.suite.host.MAX_RUNS`).
        self.max_host_runs = max(1, max_host_runs)
        self._idle: list[Host] = []  # hosts waiting for a run
        self._leaving: list[Host] = []  # hosts told to stop, not yet reaped
        self._warm = False  # the runs render: a new host makes its OpenGL context first

    def _hosts(self, running: Sequence[_Running]) -> list[Host]:
        return [*self._idle, *self._leaving, *(r.host for r in running if r.host is not None)]

    def _fork_host(self, running: Sequence[_Running]) -> Host:
        close = [fd for h in self._hosts(running) for fd in h.fds()]
        host = fork_host(max_runs=self.max_host_runs, close=close)
        if self._warm:
            host.warm()
        return host

    def _start_hosts(self, runs: int) -> None:
        """Every slot's host at once, so that they get ready in parallel: those ``srr
        suite`` started early (:func:`harness.suite.host.start_early`), then new ones."""
        want = min(self.jobs, runs) if self.fork else 0
        for host in take_early():
            if len(self._idle) < want:
                self._idle.append(host)
                if self._warm:
                    host.warm()
            else:
                host.stop()
        while len(self._idle) < want and fork_safe():
            self._idle.append(self._fork_host(()))

    def _job(self, spec: RunSpec, out_root: Path) -> dict[str, object]:
        log_file = log_path(out_root, spec)
        log_file.parent.mkdir(parents=True, exist_ok=True)
        log_file.write_bytes(b"")
        return {**spec.job(), "out_root": str(out_root),
                "baselines": None if self.baselines is None else str(self.baselines),
                "clock_file": str(clock_path(log_file)), "log": str(log_file)}

    def _start(self, spec: RunSpec, out_root: Path, running: Sequence[_Running]) -> _Running:
        """Start ``spec`` on an idle host, a new host (fork mode, while :func:`fork_safe`), or
        else in a fresh ``python -m harness.suite.worker``."""
        job = self._job(spec, out_root)
        while self.fork and (self._idle or fork_safe()):
            host = self._idle.pop() if self._idle else self._fork_host(running)
            t0 = time.monotonic()  # before the host reads it: its own instants come after
            if host.send(job):
                return _Running(spec, t0, host=host)
            self._retire(host)  # gone while it waited: a fresh one
        argv, env = fresh_process(job)
        with Path(str(job["log"])).open("wb") as log:
            t0 = time.monotonic()
            proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=log,
                                    stderr=subprocess.STDOUT, env=env, start_new_session=True)
        return _Running(spec, t0, proc=proc)

    def _retire(self, host: Host) -> None:
        """Let ``host`` go (end of file on its jobs); reaped by :meth:`_reap_leaving`."""
        host.close()
        self._leaving.append(host)

    def _retire_idle(self) -> None:
        while self._idle:
            self._retire(self._idle.pop())

    def _reap_leaving(self, *, wait: bool = False) -> None:
        for host in list(self._leaving):
            if wait:
                host.stop()
            if host.ended():
                self._leaving.remove(host)

    @staticmethod
    def _signal(r: _Running, sig: signal.Signals) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(r.pid, sig)

    def _stop(self, r: _Running, now: float) -> None:
        if r.kill_at is None:
            self._signal(r, signal.SIGTERM)
            r.kill_at = now + self.grace_s
        elif now >= r.kill_at:
            self._signal(r, signal.SIGKILL)

    def _outcome(self, r: _Running, out_root: Path) -> RunOutcome:
        code = r.returncode
        assert code is not None  # reaped
        reaped = r.reaped if r.reaped is not None else time.monotonic()
        log = log_path(out_root, r.spec)
        crash = crash_reason(code) if code < 0 and not r.timed_out else None
        error = _last_line(log) if code == 2 else None
        outcome = outcome_of(r.spec, out_root, exit_code=code, error=error,
                             wall_s=reaped - r.t0, timed_out=r.timed_out, crash=crash, log=log,
                             peak_rss_mb=r.peak_rss_mb)
        return dataclasses.replace(outcome, clock=take_clock(clock_path(log), r.t0, reaped),
                                   peak_rss_note=r.peak_rss_note)

    def _poll(self, r: _Running) -> bool:
        """Whether ``r`` ended; if so, how (its exit code, its own peak memory)."""
        if r.returncode is not None:
            return True
        if r.host is not None:
            return self._poll_host(r, r.host)
        assert r.proc is not None
        pid, status, usage = os.wait4(r.proc.pid, os.WNOHANG)
        if pid == 0:
            return False
        r.reaped = time.monotonic()
        r.returncode = r.proc.returncode = os.waitstatus_to_exitcode(status)
        r.peak_rss_mb = peak_rss_mb(usage)
        return True

    def _poll_host(self, r: _Running, host: Host) -> bool:
        answer = host.answer()
        if answer is None:
            if not host.ended():
                return False
            answer = host.answer()  # it may have answered just before it ended
        r.reaped = time.monotonic()
        if answer is None:  # it died in the run: a signal, or the host itself failed
            assert host.returncode is not None
            r.returncode = host.returncode if host.returncode != 0 else 70
            self._retire(host)
            return True
        r.returncode = int(answer["exit_code"])
        rss = answer.get("peak_rss_mb")
        r.peak_rss_mb = float(rss) if isinstance(rss, (int, float)) else None
        note = answer.get("peak_rss_note")
        r.peak_rss_note = str(note) if note else None
        r.leaving = bool(answer.get("leaving", True)) or r.kill_at is not None
        if r.leaving or host.ended():
            self._retire(host)
        else:
            self._idle.append(host)
        return True

    def run(self, specs: Sequence[RunSpec], out_root: Path,
            listen: Listener) -> tuple[list[RunOutcome], bool]:
        pending = deque(specs)
        running: list[_Running] = []
        done: dict[str, RunOutcome] = {}
        interrupted = False
        stop = StopRequests()
        self._warm = any(s.renders for s in specs)
        with stop.installed():
            try:
                self._start_hosts(len(specs))
                stop.check()
                while pending or running:
                    stop.check()  # here, between steps: never inside a fork (see the class)
                    while pending and len(running) < self.jobs:
                        r = self._start(pending.popleft(), out_root, running)
                        running.append(r)
                        listen(Event("start", r.spec, where=f"pid {r.pid}"))
                    now = time.monotonic()
                    for r in list(running):
                        if self._reap(r, running, out_root, done, listen):
                            continue
                        if r.spec.timeout_s is not None and (
                                r.timed_out or now - r.t0 > r.spec.timeout_s):
                            r.timed_out = True
                            self._stop(r, now)
                    if not pending:  # no run left to start: idle hosts end now, so their
                        self._retire_idle()  # processes (and GL contexts) go beside the last runs
                    self._reap_leaving()
                    self._wait(running)
            except KeyboardInterrupt:
                interrupted = True
                self._drain(running, out_root, done, listen)
            finally:
                self._retire_idle()
                self._reap_leaving(wait=True)
        for spec in specs:
            if spec.id not in done:
                done[spec.id] = not_started(spec)
        return [done[s.id] for s in specs], interrupted

    def _wait(self, running: Sequence[_Running]) -> None:
        """Until a host answers, or ``poll_s`` (fresh processes, timeouts, a host's death)."""
        fds = [r.host.results for r in running if r.host is not None and r.host.results >= 0]
        select.select(fds, [], [], self.poll_s)

    def _reap(self, r: _Running, running: list[_Running], out_root: Path,
              done: dict[str, RunOutcome], listen: Listener) -> bool:
        """If ``r`` ended: take it off ``running``, judge it and say so; whether it ended."""
        if not self._poll(r):
            return False
        running.remove(r)
        done[r.spec.id] = self._outcome(r, out_root)
        listen(Event("finish", r.spec, done[r.spec.id]))
        return True

    def _drain(self, running: list[_Running], out_root: Path, done: dict[str, RunOutcome],
               listen: Listener) -> None:
        """Stop what runs (SIGTERM, then SIGKILL after the grace period), keep what they
        leave. A second Ctrl-C here is ignored: the point is to leave valid files."""
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            self._retire_idle()
            while running:
                now = time.monotonic()
                for r in list(running):
                    if not self._reap(r, running, out_root, done, listen):
                        self._stop(r, now)
                time.sleep(self.poll_s)
        finally:
            signal.signal(signal.SIGINT, previous)
