"""A host: a long-lived process, forked from the suite's, that runs the suite's runs one after
another in itself (Linux only; :mod:`harness.suite.local` decides when).

The executor writes a job (one JSON line: :meth:`RunSpec.job` with ``out_root``,
``baselines``, ``clock_file`` and ``log``) to the host's job pipe; the host sends the run's
stdout and stderr to the job's ``log`` (``dup2`` onto fds 1 and 2), runs it
(:func:`harness.suite.worker.serve`: its clock beside the log) and answers one JSON line on its
result pipe: ``{"exit_code", "peak_rss_mb", "peak_rss_note", "leaving"}``. It stops on end of
file, and of
itself (after answering) once it has run ``max_runs`` runs, after a run that did not end with
0 or 1 (interrupted, failed, could not start), or when a run left a thread running: the
executor then forks a fresh one. A host that dies without answering (a segfault, the
out-of-memory killer, SIGKILL after a timeout) costs the run it had.

What a run could leave to the next one in the same process is put back before the next job
(:class:`_Baseline`): signal handlers, MuJoCo's global callbacks (``mjcb_control`` ...),
NumPy's error handling, the umask, the interpreter's switch interval, ``os.environ``,
the working directory, ``sys.path``, the warnings filters, ``sys.stdout``/``sys.stderr``, and
the plug-in modules the run imported (dropped, so the next run imports them afresh, as a fresh
process would). The global ``random`` and NumPy generators are seeded from the operating
system before each run, as a fresh process's are: a plug-in that draws from them unseeded
gets other numbers in every run, so its repeats differ and the suite calls it flaky (put back
to one saved state, every run of a host, and every host forked from the suite, drew the same).
The OpenGL context is kept on purpose (:func:`harness.sim.render.keep_gl_contexts`): made
once per host, when the suite's runs render (:meth:`Host.warm`), while the suite is checked, at
most :data:`WARM_AT_ONCE` hosts at a time (:func:`warm_slot`). A run's recording does not
depend on which of these it got (tests compare the bytes with a fresh process's).

Peak memory per run: before each run the host resets its peak resident set (``5`` to
``/proc/self/clear_refs``) and reads ``VmHWM`` from ``/proc/self/status`` after it. Where the
kernel refuses the reset (some sandboxes) the run's ``peak_rss_mb`` is None with
``peak_rss_note`` saying why, never the host's lifetime peak.
"""

from __future__ import annotations

import contextlib
import gc
import json
import os
import random
import signal
import sys
import sysconfig
import threading
import warnings
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from harness.interrupt import StopRequests

__all__ = ["MAX_RUNS", "WARM_AT_ONCE", "Host", "RunAfterRun", "fork_host",
           "fork_safe_here", "start_early", "stop_early", "stop_with_parent", "take_early",
           "warm_early", "warm_slot"]

#: Runs a host does before it is replaced by a fresh one. What one run can leave behind that
#: :class:`_Baseline` cannot put back (a fragmented heap, caches of compiled expressions,
#: driver memory) is bounded to this many runs, while a slot's runs in a nightly suite
#: (59 runs on 16 workers: about 4 a slot) mostly share one host and one OpenGL context.
MAX_RUNS = 8

#: Hosts that make their OpenGL context at the same time. The driver makes contexts at about
#: the same total rate however many processes ask (on the H100 host, one alone in 0.29 s, four
#: at once in 0.33 s each, sixteen at once in 1.44 s each), so sixteen hosts asking at once all
#: wait for the last one; in groups of four the first hosts start their runs sooner. H100 host,
#: nightly on 16 workers, seven passes beside the unlimited hosts: the first run began 0.5-1.1 s
#: earlier in every pass, the suites took 71.8 s against 75.6 s in all (8 at a time: no gain).
WARM_AT_ONCE = 4
# How long a host waits for its turn before it makes its context anyway (a host killed while
# it held a turn never gives it back).
_WARM_WAIT_S = 5.0
# the semaphore, made by the suite's process before its first fork (False: none can be made)
_warm_gate: Any = None

_HARNESS = str(Path(__file__).resolve().parents[1])
_LIBRARIES = tuple({str(Path(p).resolve()) for p in
                    (sysconfig.get_paths()[k] for k in ("stdlib", "platstdlib", "purelib",
                                                        "platlib"))})


@dataclass
class Host:
    """The executor's side of a host: its process id and the two pipes."""

    pid: int
    jobs: int  # write end
    results: int  # read end
    _buffer: bytes = b""
    returncode: int | None = None
    warmed: bool = False  # told to make its OpenGL context (:meth:`warm`)
    _eof: bool = field(default=False, repr=False)

    def send(self, job: Mapping[str, Any]) -> bool:
        """Give the host its next run; False when it is gone (the run is then not started)."""
        line = json.dumps(dict(job)).encode() + b"\n"
        try:
            os.write(self.jobs, line)  # far below the pipe's buffer: never blocks
        except OSError:
            return False
        return True

    def warm(self) -> None:
        """Have it make its OpenGL context now, before its first run (the runs render); once
        per host."""
        if self.warmed:
            return
        self.warmed = True
        with contextlib.suppress(OSError):  # gone: found when it is given a run
            os.write(self.jobs, b'{"warm": true}\n')

    def answer(self) -> dict[str, Any] | None:
        """The answer to its run, once it has come (never blocks)."""
        while b"\n" not in self._buffer and not self._eof:
            try:
                chunk = os.read(self.results, 65536)
            except BlockingIOError:
                break
            if not chunk:
                self._eof = True
                break
            self._buffer += chunk
        if b"\n" not in self._buffer:
            return None
        line, self._buffer = self._buffer.split(b"\n", 1)
        try:
            answer = json.loads(line)
        except ValueError:
            return None
        return answer if isinstance(answer, dict) else None

    def ended(self) -> bool:
        """Whether the process has ended (reaped here; :attr:`returncode` then set)."""
        if self.returncode is None:
            try:
                pid, status = os.waitpid(self.pid, os.WNOHANG)
            except ChildProcessError:
                self.returncode = -signal.SIGKILL
                return True
            if pid == 0:
                return False
            self.returncode = os.waitstatus_to_exitcode(status)
        return True

    def signal(self, sig: signal.Signals) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pid, sig)

    def close(self) -> None:
        """Tell it to stop (end of file on its job pipe) and let go of the pipes."""
        for fd in (self.jobs, self.results):
            with contextlib.suppress(OSError):
                os.close(fd)
        self.jobs = self.results = -1

    def stop(self) -> None:
        """Stop it now (it has no run, or its run is given up) and reap it."""
        self.close()
        self.signal(signal.SIGKILL)
        if self.returncode is None:
            with contextlib.suppress(ChildProcessError):
                _, status = os.waitpid(self.pid, 0)
                self.returncode = os.waitstatus_to_exitcode(status)

    def fds(self) -> tuple[int, ...]:
        return tuple(fd for fd in (self.jobs, self.results) if fd >= 0)


_EARLY: list[Host] = []  # started by start_early, not yet taken


def fork_safe_here() -> bool:
    """Whether a host may be forked from this process now: Linux, no other Python thread, no
    OpenGL context made here (its driver's threads and locks would not survive the fork).
    Imports nothing heavy (MuJoCo is not loaded for it)."""
    render = sys.modules.get("harness.sim.render")
    return (sys.platform == "linux" and threading.active_count() == 1
            and not (render is not None and render.rendered_in_this_process()))


def start_early(n: int, *, max_runs: int = MAX_RUNS) -> None:
    """Fork ``n`` hosts now, where that is safe, for the suite this process is about to check
    and run; the local executor then takes them (:func:`take_early`). ``srr suite`` calls it
    once it has imported srr (with MuJoCo, NumPy, pandas, SciPy): the hosts share those
    imports copy-on-write. Forking them before the imports, each importing for itself,
    measured slower on a 16-CPU GPU host: 16 processes importing at once slowed the suite's
    own imports, and the first run began 1.8 s later.

    They make no OpenGL context until :func:`warm_early` (called by the suite's planning at
    the first run that renders): then they make it while the rest of the suite is checked
    (16 contexts made at once take 1.5 s on a GPU host). Hosts that made one for a suite
    that does not render measured slower there: 30 runs without cameras on 16 workers took
    5.0 s against 4.1 s, their summed walls 36.9 s against 18.2 s."""
    stop = StopRequests()  # a Ctrl-C during a fork would be lost (see StopRequests)
    with stop.installed():
        while len(_EARLY) < n and fork_safe_here() and not stop.requested:
            _EARLY.append(fork_host(max_runs=max_runs,
                                    close=[fd for h in _EARLY for fd in h.fds()]))
    if stop.requested:
        stop_early()
        raise KeyboardInterrupt


def warm_early() -> None:
    """Have the hosts :func:`start_early` made make their OpenGL contexts now (the suite's
    runs render)."""
    for host in _EARLY:
        host.warm()


def take_early() -> list[Host]:
    """The hosts :func:`start_early` made (they are the caller's from now on)."""
    hosts = list(_EARLY)
    _EARLY.clear()
    return hosts


def stop_early() -> None:
    """Stop the hosts :func:`start_early` made that no executor took (a suite that did not
    run: bad input, another executor)."""
    for host in take_early():
        host.stop()


@contextlib.contextmanager
def warm_slot() -> Iterator[None]:
    """Hold one of the :data:`WARM_AT_ONCE` turns to make an OpenGL context, shared by every
    host this process forks (after :func:`fork_host`'s first call; before it, or where the
    platform has no shared semaphores, no limit), for at most ``_WARM_WAIT_S`` of waiting."""
    gate = _warm_gate
    held = gate is not None and gate is not False and gate.acquire(timeout=_WARM_WAIT_S)
    try:
        yield
    finally:
        if held:
            gate.release()


def fork_host(*, max_runs: int = MAX_RUNS, close: Sequence[int] = ()) -> Host:
    """Fork a host; ``close``: descriptors it must not keep (the other hosts' pipes, else
    they would not see end of file). It imports what runs need, then waits for its jobs
    (:meth:`Host.warm` first, if the runs render)."""
    # What every run imports at its end (scoring, report): imported here, before the fork,
    # the hosts share it (copy-on-write) instead of each importing it at its first run's end
    # (and a run's peak memory stays measured as in a host that has it).
    from harness.run.record import import_after_the_loop

    import_after_the_loop()
    global _warm_gate
    if _warm_gate is None:  # a POSIX semaphore: the forked hosts share it
        import multiprocessing

        try:
            _warm_gate = multiprocessing.get_context("fork").Semaphore(WARM_AT_ONCE)
        except (ImportError, OSError):  # no working sem_open here (no /dev/shm): no limit
            _warm_gate = False
    jobs_r, jobs_w = os.pipe()
    results_r, results_w = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    suite = os.getpid()
    # Everything this process holds now (srr, NumPy, pandas, SciPy: some 130,000 objects the
    # collector tracks) lives as long as the host: frozen in the host, its collections (its
    # runs', and the full one after each run) skip it instead of walking it again and again,
    # which cost ~8 % of a run's CPU and wrote to the pages it shares with this process. This
    # process thaws at once: a program that runs suite after suite collects as before.
    gc.freeze()
    try:
        pid = os.fork()
    finally:
        if os.getpid() == suite:
            gc.unfreeze()
    if pid == 0:  # the host
        code = 70  # EX_SOFTWARE: the host itself failed
        try:
            for fd in (*close, jobs_w, results_r):
                with contextlib.suppress(OSError):
                    os.close(fd)
            code = _serve(jobs_r, results_w, max_runs=max_runs, suite=suite)
        except BaseException:
            import traceback

            with contextlib.suppress(Exception):
                traceback.print_exc()
        finally:
            with contextlib.suppress(Exception):
                sys.stdout.flush()
                sys.stderr.flush()
            os._exit(code)
    os.close(jobs_r)
    os.close(results_w)
    os.set_blocking(results_r, False)
    return Host(pid, jobs_w, results_r)


def _serve(jobs_r: int, results_w: int, *, max_runs: int, suite: int) -> int:
    """The host's life: set up, then one run per job line until end of file or a reason to
    be replaced. Its exit status: 0."""
    os.setsid()  # the suite signals it (and what it started) as a group; no terminal's Ctrl-C
    stop_with_parent(suite)
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):  # between runs, nothing is written anywhere
        os.dup2(null, fd)
    # the parent's sys.stdout/sys.stderr may be objects of its own (pytest's capture, an
    # IDE's console) that do not write to fds 1 and 2: the host's follow each run's log
    sys.stdout = open(1, "w", encoding="utf-8", errors="replace", closefd=False)  # noqa: SIM115
    sys.stderr = open(2, "w", encoding="utf-8", errors="replace", closefd=False)  # noqa: SIM115
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # between runs: stop; in a run: finalize
    import faulthandler

    if faulthandler.is_enabled():  # its dump goes to the current run's log (fd 2)
        faulthandler.enable(file=sys.stderr)
    sys.path.insert(0, os.getcwd())  # plug-ins import from here, like `srr run`
    from harness.sim.render import warm_gl

    warm_s = 0.0  # seconds making its OpenGL context, counted in its first run's clock
    from harness.report.templates import environment
    from harness.suite.worker import serve

    env = environment()  # every run writes a report.html
    for name in env.list_templates(extensions=["html"]):
        env.get_template(name)
    between = RunAfterRun()  # from here on, OpenGL contexts are kept
    runs = 0
    with os.fdopen(jobs_r, "rb") as jobs:
        for line in jobs:
            job = json.loads(line)
            if job.get("warm"):  # what rendering runs need, before the first
                with warm_slot():
                    warm_s += warm_gl()  # none made if it has one
                with contextlib.suppress(Exception):  # a run without it reports this itself
                    import OpenGL.GL  # noqa: F401 - the renderer's name; no context made
                continue
            log = os.open(job["log"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
            os.dup2(log, 1)
            os.dup2(log, 2)
            os.close(log)
            note = between.before()
            code = serve({**job, "warm_gl_s": warm_s})
            warm_s = 0.0
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(null, 1)
            os.dup2(null, 2)
            runs += 1
            peak, left = between.after(note)
            leaving = code not in (0, 1) or bool(left) or runs >= max_runs
            answer = {"exit_code": code, "peak_rss_mb": peak, "peak_rss_note": note,
                      "leaving": leaving}
            os.write(results_w, json.dumps(answer).encode() + b"\n")
            if leaving:
                break
            gc.collect()  # what the run left, freed while the suite judges it
    return 0


def stop_with_parent(suite: int) -> None:
    """SIGTERM to this process (a host; a run's own process under a Ray worker), once, when
    its parent ``suite`` ends, however (``kill -9`` included): a run in progress finalizes its
    bag and summary, as at its timeout, instead of running on alone. Linux
    ``PR_SET_PDEATHSIG``, with SIGHUP relayed as one SIGTERM: the kernel sends the
    parent-death signal again each time the process passes to another dying thread of its
    parent (its native thread pools), and a second SIGTERM would cut the run's finalizing
    short. Nothing where ``prctl`` is missing."""
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        prctl = libc.prctl
    except (OSError, AttributeError):
        return
    relayed: list[bool] = []

    def orphaned(signum: int, frame: Any) -> None:
        if not relayed:
            relayed.append(True)
            prctl(1, 0, 0, 0, 0)  # no more parent-death signals
            os.kill(os.getpid(), signal.SIGTERM)

    signal.signal(signal.SIGHUP, orphaned)
    prctl(1, int(signal.SIGHUP), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
    if os.getppid() != suite:  # the suite ended before the request took effect
        orphaned(signal.SIGHUP, None)


_CLEAR_REFS = Path("/proc/self/clear_refs")
_STATUS = Path("/proc/self/status")


class RunAfterRun:
    """What a process that runs one run after another (a host; a Ray worker) does around each
    run, so that each records what a fresh process would and reports its own peak memory.

    Made before the first run (keeping OpenGL contexts from then on, and taking the
    process's :class:`_Baseline`): :meth:`before` each run resets the peak resident set,
    :meth:`after` it reads that peak and puts the baseline back."""

    def __init__(self) -> None:
        from harness.sim.render import keep_gl_contexts

        keep_gl_contexts()
        self._baseline = _Baseline.take()

    def before(self) -> str | None:
        """Seed the global generators from the operating system, as a fresh process does (see
        the module doc), and reset the peak memory; None, or why that could not be (then the
        run has no peak)."""
        import numpy as np

        random.seed()
        np.random.seed()
        return _reset_peak()

    def after(self, note: str | None) -> tuple[float | None, list[str]]:
        """The run's peak memory (MiB; None where :meth:`before` said why not) and the names
        of the threads it left running, once the rest of the process is put back (the
        process must then run no other run: they may still touch what the next would use)."""
        peak = _peak_mb() if note is None else None
        return peak, self._baseline.restore()


def _reset_peak() -> str | None:
    """Reset this process's peak resident set to its current one; why not, if it failed."""
    try:
        _CLEAR_REFS.write_text("5")
    except OSError as err:
        return (f"not measured: resetting the host's peak memory before the run failed "
                f"({_CLEAR_REFS}: {err.strerror or err})")
    return None


def _peak_mb() -> float | None:
    """``VmHWM`` of this process, MiB."""
    with contextlib.suppress(OSError, ValueError):
        for line in _STATUS.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return round(int(line.split()[1]) / 1024.0, 1)
    return None


@dataclass
class _Baseline:
    """What a fresh process would start a run with, put back after each run."""

    handlers: dict[int, Any]
    switch: float
    environ: dict[str, str]
    cwd: str
    path: list[str]
    filters: list[Any]
    streams: tuple[Any, Any]
    modules: frozenset[str]
    registry: Any
    mujoco_callbacks: dict[str, Any]
    numpy_errors: Any  # np.geterr()
    umask: int
    threads: frozenset[int]  # idents of the threads running then (a Ray worker has its own)

    @classmethod
    def take(cls) -> _Baseline:
        """The process as it is now, less the plug-in modules it has imported (the suite's
        checks set every entry's plug-ins up) and the graph node types they registered: each
        run imports its own, as in a fresh process."""
        import numpy as np

        from harness.graph.registry import DEFAULT_REGISTRY

        dropped = {n for n, m in list(sys.modules.items()) if _is_plugin(m)}
        for name in dropped:
            del sys.modules[name]
        types, names = DEFAULT_REGISTRY.snapshot()
        types = {k: v for k, v in types.items() if v.__module__ not in dropped}
        DEFAULT_REGISTRY.restore((types, {k: v for k, v in names.items() if v in types}))

        handlers = {}
        for sig in signal.valid_signals():
            with contextlib.suppress(OSError, ValueError):
                handlers[int(sig)] = signal.getsignal(sig)
        umask = os.umask(0o022)
        os.umask(umask)
        return cls(handlers, sys.getswitchinterval(), dict(os.environ), os.getcwd(),
                   list(sys.path), list(warnings.filters), (sys.stdout, sys.stderr),
                   frozenset(sys.modules),
                   DEFAULT_REGISTRY.snapshot(), _mujoco_callbacks(), np.geterr(), umask,
                   frozenset(t.ident for t in threading.enumerate() if t.ident is not None))

    def restore(self) -> list[str]:
        """Put it all back; the names of threads the run left running (the host must then
        go: they may still touch what the next run uses)."""
        import numpy as np

        from harness.graph.registry import DEFAULT_REGISTRY

        for sig, handler in self.handlers.items():
            if handler is not None and signal.getsignal(sig) is not handler:
                with contextlib.suppress(OSError, ValueError, TypeError):
                    signal.signal(sig, handler)
        sys.setswitchinterval(self.switch)
        if dict(os.environ) != self.environ:
            os.environ.clear()
            os.environ.update(self.environ)
        with contextlib.suppress(OSError):
            os.chdir(self.cwd)
        sys.path[:] = self.path
        warnings.filters[:] = self.filters  # type: ignore[index]
        sys.stdout, sys.stderr = self.streams
        for name in [n for n in sys.modules if n not in self.modules]:
            if _is_plugin(sys.modules.get(name)):
                del sys.modules[name]
        DEFAULT_REGISTRY.restore(self.registry)
        import mujoco

        for name, callback in self.mujoco_callbacks.items():  # MuJoCo's are process-wide
            if getattr(mujoco, f"get_{name}")() is not callback:
                getattr(mujoco, f"set_{name}")(callback)
        np.seterr(**self.numpy_errors)
        os.umask(self.umask)
        return [t.name for t in threading.enumerate() if t.ident not in self.threads]


def _mujoco_callbacks() -> dict[str, Any]:
    """MuJoCo's global callbacks (``mjcb_control`` and the others), which a plug-in may set:
    they act on every model of the process."""
    import mujoco

    return {name[4:]: getattr(mujoco, name)() for name in dir(mujoco)
            if name.startswith("get_mjcb_")}


def _is_plugin(module: Any, here: str | None = None) -> bool:
    """A module of the project's own Python source, where plug-ins import from (the current
    directory ``here``): not srr's, not an installed package's (a virtual environment or a
    ``site-packages`` in the project included), not compiled (which cannot be imported twice).
    Packages installed elsewhere (``PYTHONPATH``, a ``--target`` folder) are never dropped:
    MuJoCo, PyOpenGL and their kin keep process-wide state that a second import breaks."""
    origin = getattr(module, "__file__", None)
    if not isinstance(origin, str) or not origin.endswith(".py"):
        return False
    path = str(Path(origin).resolve())
    project = str(Path(here if here is not None else os.getcwd()).resolve())
    return (path.startswith(project + os.sep) and not path.startswith(_HARNESS + os.sep)
            and not any(path.startswith(lib + os.sep) for lib in _LIBRARIES)
            and not any(part in ("site-packages", "dist-packages")
                        for part in Path(path).parts))
