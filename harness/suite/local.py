"""Runs in parallel worker processes on this machine: one process per run, at most ``jobs`` at
a time.

With ``fork=True`` (what ``srr suite`` asks for) each run's process is forked from the suite's,
which has already imported srr, MuJoCo, NumPy, pandas and SciPy (1.4 s of start-up a run on
the 2-core CI machine, a sixth of the bundled suite's CPU time); the child runs
:func:`harness.suite.worker.main` and exits. That is done only on Linux and only while the
suite's process is as clean as a fresh one — no other Python thread (a live progress display),
no OpenGL context ever made here (its driver's threads and locks would not survive the fork) —
else, and by default, each run is a fresh ``python -m harness.suite.worker``. Either way a run
never sees another run's state. Once the first workers are forked the suite's process also
loads what every later run would load for itself (:func:`preload`), and, on CPUs the workers
leave idle (``ahead``), forks the next runs' workers ahead of a free slot: each gets ready — a
run that renders makes its OpenGL context, the one its renderer then uses — and waits for its
slot; the run, its timings and its timeout begin when the slot frees.

A process per run isolates what one run can break: a segfault, an out-of-memory kill or
a hang costs that run (INVALID, with the signal or the timeout as the reason), never the
suite. A run past its timeout gets SIGTERM (it finalizes its bag and summary), then SIGKILL
after ``grace_s``. Ctrl-C (or SIGTERM to the suite) stops the runs the same way and keeps every
finished one. Worker output goes to ``OUT/logs/<run id>.log``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import faulthandler
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from harness.sim.render import rendered_in_this_process
from harness.suite.events import Event, Listener, log_path, not_started
from harness.suite.plan import RunSpec
from harness.suite.results import RunOutcome, crash_reason, outcome_of
from harness.suite.timeline import clock_path, take_clock
from harness.suite.worker import peak_rss_mb

__all__ = ["LocalExecutor", "fork_safe", "preload"]


def fork_safe() -> bool:
    """Whether a worker may be forked from this process: Linux, no other Python thread, and
    no OpenGL context made here."""
    return (sys.platform == "linux" and threading.active_count() == 1
            and not rendered_in_this_process())


def preload(specs: Sequence[RunSpec]) -> None:
    """Before the later forks: what every forked run would otherwise load for itself, done once
    here — PyOpenGL's ``GL`` module, which a run that renders imports to read the renderer's
    name (a third of a second; loading it makes no OpenGL context), and the compiled page
    templates of the run's ``report.html``. Nothing here changes what a run records."""
    from harness.report.templates import environment

    if any(s.renders for s in specs):
        with contextlib.suppress(Exception):  # a run without it reports this itself
            import OpenGL.GL  # noqa: F401
    env = environment()
    for name in env.list_templates(extensions=["html"]):
        env.get_template(name)


class _StopRequests:
    """Ctrl-C and SIGTERM while the executor starts and watches workers, taken as a request
    the loop acts on between its steps (:meth:`check` raises :class:`KeyboardInterrupt`).

    Why not let the signal raise where it lands: CPython runs ``os.fork``'s at-fork hooks
    (``logging``'s lock release among them) in Python, and drops an exception raised there
    ("Exception ignored in ..."), so a Ctrl-C that arrived while a worker was forked was lost
    and the suite ran on (seen as a hang about one time in four on a loaded machine)."""

    def __init__(self) -> None:
        self.requested = False

    def _request(self, signum: int, frame: Any) -> None:
        self.requested = True

    @contextlib.contextmanager
    def installed(self) -> Iterator[None]:
        """Take SIGINT and SIGTERM as requests within the block (main thread only; elsewhere
        the handlers stay as they are)."""
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


class _Forked:
    """A forked worker: what the executor reads of a ``Popen`` (``pid``, ``returncode``)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.returncode: int | None = None


def _fork_worker(job: dict[str, object], log: IO[bytes], *, gate: int | None = None,
                 close: Sequence[int] = (), warm: bool = False) -> _Forked:
    """Fork a child that runs ``job`` as ``python -m harness.suite.worker`` would (its own
    session, stdin from /dev/null, stdout and stderr to ``log``) and exits with its code.

    ``gate``: the read end of a pipe; the child is started ahead of its run: it gets ready
    (``warm``: makes and frees one OpenGL context, :func:`harness.sim.render.warm_gl`), then
    waits for a byte on ``gate`` before it begins the run (none: it exits, status 130, having
    run nothing). ``close``: descriptors the child must not keep (other children's gates)."""
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid:
        return _Forked(pid)
    code = 70  # EX_SOFTWARE: the worker itself failed
    try:
        for fd in close:
            with contextlib.suppress(OSError):
                os.close(fd)
        os.setsid()
        null = os.open(os.devnull, os.O_RDONLY)
        os.dup2(null, 0)
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        # the parent's sys.stdout/sys.stderr may be objects of its own (pytest's capture, an
        # IDE's console) that do not write to fds 1 and 2: the child's go to the log
        sys.stdout = open(1, "w", encoding="utf-8", errors="replace", closefd=False)  # noqa: SIM115
        sys.stderr = open(2, "w", encoding="utf-8", errors="replace", closefd=False)  # noqa: SIM115
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if faulthandler.is_enabled():  # its dump goes to this run's log, not the suite's
            faulthandler.enable(file=sys.stderr)
        sys.path.insert(0, os.getcwd())  # plug-ins import from here, like `srr run`
        from harness.suite.worker import main

        if gate is not None and warm:
            from harness.sim.render import warm_gl

            job = {**job, "warm_gl_s": warm_gl()}
        # at a gate, no byte (the suite stopped before this run began): nothing was run
        code = main([json.dumps(job)]) if gate is None or os.read(gate, 1) else 130
    except BaseException:  # reported in the run's log, then the child exits
        import traceback

        traceback.print_exc()
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)


@dataclass
class _Running:
    spec: RunSpec
    proc: subprocess.Popen[bytes] | _Forked
    log: IO[bytes]
    t0: float
    kill_at: float | None = None  # set once SIGTERM was sent
    timed_out: bool = False
    peak_rss_mb: float | None = None
    reaped: float | None = None  # time.monotonic() when it was found ended
    gate: int | None = None  # started ahead: the write end of its gate, until it may run


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
                 poll_s: float = 0.05, fork: bool = False, ahead: int | None = None) -> None:
        self.jobs = max(1, jobs)
        self.baselines = baselines
        self.grace_s = grace_s
        self.poll_s = poll_s
        #: Fork each worker from this process when that is safe (:func:`fork_safe`).
        self.fork = fork
        #: Forked workers started ahead of a free slot, each ready (imports done, its first
        #: OpenGL context made if its run renders) and waiting for the slot. Default: on the
        #: CPUs the workers leave idle, at most 2 (none with a worker per CPU).
        self.ahead = (ahead if ahead is not None else
                      max(0, min(2, (os.cpu_count() or 1) - self.jobs)))
        self._gates: set[int] = set()

    def _start(self, spec: RunSpec, out_root: Path, *, ahead: bool = False) -> _Running:
        """Start ``spec``'s worker; ``ahead``: forked, made ready, held at its gate until
        :meth:`_go` (fork mode only)."""
        log_file = log_path(out_root, spec)
        job = {**spec.job(), "out_root": str(out_root),
               "baselines": None if self.baselines is None else str(self.baselines),
               "clock_file": str(clock_path(log_file))}
        log_file.parent.mkdir(parents=True, exist_ok=True)
        log = log_file.open("wb")
        t0 = time.monotonic()  # before the worker exists: its own instants come after it
        if ahead:
            read, write = os.pipe()
            self._gates.add(write)
            try:
                proc: subprocess.Popen[bytes] | _Forked = _fork_worker(
                    job, log, gate=read, close=sorted(self._gates), warm=spec.renders)
            finally:
                os.close(read)
            return _Running(spec, proc, log, t0, gate=write)
        if self.fork and fork_safe():
            return _Running(spec, _fork_worker(job, log, close=sorted(self._gates)), log, t0)
        env = dict(os.environ)
        # the worker imports plug-ins ("module:Class") from here, like `srr run` does
        env["PYTHONPATH"] = os.pathsep.join(p for p in (os.getcwd(), env.get("PYTHONPATH"))
                                            if p)
        proc = subprocess.Popen([sys.executable, "-m", "harness.suite.worker", json.dumps(job)],
                                stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                env=env, start_new_session=True)
        return _Running(spec, proc, log, t0)

    def _go(self, r: _Running) -> _Running:
        """Let a worker started ahead begin its run: its timings and timeout count from here."""
        assert r.gate is not None
        r.t0 = time.monotonic()  # before the go: the worker's own instants come after it
        with contextlib.suppress(OSError):  # it ended while it waited: reaped as it is
            os.write(r.gate, b"g")
        self._close_gate(r)
        return r

    def _close_gate(self, r: _Running) -> None:
        if r.gate is not None:
            self._gates.discard(r.gate)
            os.close(r.gate)
            r.gate = None

    def _ahead(self, pending: Sequence[RunSpec]) -> int:
        """How many workers to start ahead of a free slot."""
        if not (self.fork and pending and fork_safe()):
            return 0
        return self.ahead

    def _unstart(self, r: _Running, out_root: Path) -> None:
        """A worker started ahead that never ran: stop it, leave nothing of it."""
        with contextlib.suppress(ProcessLookupError):
            os.kill(r.proc.pid, signal.SIGKILL)
        self._close_gate(r)
        with contextlib.suppress(ChildProcessError):
            os.waitpid(r.proc.pid, 0)
        r.log.close()
        log = log_path(out_root, r.spec)
        for path in (log, clock_path(log)):
            with contextlib.suppress(OSError):
                path.unlink()

    @staticmethod
    def _signal(r: _Running, sig: signal.Signals) -> None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(r.proc.pid, sig)

    def _stop(self, r: _Running, now: float) -> None:
        if r.kill_at is None:
            self._signal(r, signal.SIGTERM)
            r.kill_at = now + self.grace_s
        elif now >= r.kill_at:
            self._signal(r, signal.SIGKILL)

    def _outcome(self, r: _Running, out_root: Path) -> RunOutcome:
        r.log.close()
        code = r.proc.returncode
        assert code is not None  # reaped
        reaped = r.reaped if r.reaped is not None else time.monotonic()
        log = log_path(out_root, r.spec)
        crash = crash_reason(code) if code < 0 and not r.timed_out else None
        error = _last_line(log) if code == 2 else None
        outcome = outcome_of(r.spec, out_root, exit_code=code, error=error,
                             wall_s=reaped - r.t0, timed_out=r.timed_out, crash=crash, log=log,
                             peak_rss_mb=r.peak_rss_mb)
        return dataclasses.replace(outcome, clock=take_clock(clock_path(log), r.t0, reaped))

    @staticmethod
    def _poll(r: _Running) -> bool:
        """Reap ``r`` if it ended (``os.wait4``: its exit status and its own peak memory)."""
        if r.proc.returncode is None:
            pid, status, usage = os.wait4(r.proc.pid, os.WNOHANG)
            if pid == 0:
                return False
            r.reaped = time.monotonic()
            r.proc.returncode = os.waitstatus_to_exitcode(status)
            r.peak_rss_mb = peak_rss_mb(usage)
        return True

    def run(self, specs: Sequence[RunSpec], out_root: Path,
            listen: Listener) -> tuple[list[RunOutcome], bool]:
        pending = deque(specs)
        preloaded = False  # after the first workers are forked: they need not wait for it
        running: list[_Running] = []
        waiting: deque[_Running] = deque()  # started ahead, at their gates
        done: dict[str, RunOutcome] = {}
        interrupted = False
        stop = _StopRequests()
        with stop.installed():
            try:
                while pending or waiting or running:
                    stop.check()  # here, between steps: never inside a fork (see the class)
                    while (pending or waiting) and len(running) < self.jobs:
                        r = (self._go(waiting.popleft()) if waiting else
                             self._start(pending.popleft(), out_root))
                        running.append(r)
                        listen(Event("start", r.spec, where=f"pid {r.proc.pid}"))
                    if pending and not preloaded and self.fork and fork_safe():
                        preload(pending)
                        preloaded = True
                    while pending and len(waiting) < self._ahead(pending):
                        waiting.append(self._start(pending.popleft(), out_root, ahead=True))
                    now = time.monotonic()
                    for r in list(running):
                        if self._reap(r, running, out_root, done, listen):
                            continue
                        if r.spec.timeout_s is not None and (
                                r.timed_out or now - r.t0 > r.spec.timeout_s):
                            r.timed_out = True
                            self._stop(r, now)
                    time.sleep(self.poll_s)
            except KeyboardInterrupt:
                interrupted = True
                while waiting:
                    self._unstart(waiting.popleft(), out_root)
                self._drain(running, out_root, done, listen)
        for spec in specs:
            if spec.id not in done:
                done[spec.id] = not_started(spec)
        return [done[s.id] for s in specs], interrupted

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
            while running:
                now = time.monotonic()
                for r in list(running):
                    if not self._reap(r, running, out_root, done, listen):
                        self._stop(r, now)
                time.sleep(self.poll_s)
        finally:
            signal.signal(signal.SIGINT, previous)
