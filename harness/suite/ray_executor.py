"""Runs as Ray tasks on a real Ray cluster: an existing one (``address``: ``auto``,
``ray://host:10001`` or ``host:6379``; else ``RAY_ADDRESS``), else a local cluster started here
and stopped at the end (never a ``ray start`` cluster that happens to run on this machine).

Each run is one task (``num_cpus=1``; runs that render also ask for ``gpu_share`` of a GPU
when the cluster has GPUs) with no retries, so a segfault or an out-of-memory kill shows up as
that run's ``WorkerCrashedError`` / ``OutOfMemoryError`` (INVALID with the reason), never the
suite's. A run past its timeout is cancelled (``ray.cancel``: first as an interrupt, so it
finalizes, then forced after ``grace_s``).

A Ray worker process runs up to :data:`~harness.suite.host.MAX_RUNS` runs one after another
(``max_calls``), as a local host does (:class:`~harness.suite.host.RunAfterRun`: what a run
could leave behind is put back, each run's own peak memory, the OpenGL context kept), so a run
does not pay for a fresh interpreter and its imports. A worker whose run left a thread running
or was interrupted runs its later runs each in a fresh process (``python -m
harness.suite.worker``) instead, and so does a run given a GPU other than the one the worker's
OpenGL context was made on.

With an existing cluster the project folder (the current directory: scenarios, baselines,
plug-ins; not ``reports/``, ``.venv/``, ``.git/``) travels as the job's ``working_dir``, and a
run executed on another node sends its run directory back as a tar archive; srr must be
installed on every node. Runs on the driver's node write to the output folder directly.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import logging
import os
import tarfile
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.errors import SrrError
from harness.interrupt import INTERRUPTED_EXIT
from harness.suite.events import Event, Listener, not_started
from harness.suite.host import MAX_RUNS
from harness.suite.plan import RunSpec
from harness.suite.results import RunOutcome, outcome_of

__all__ = ["RayExecutor"]

_EXCLUDES = ["reports/", ".venv/", ".git/", "**/__pycache__/"]


@dataclass
class _Worker:
    """This Ray worker process's state across its runs (see the module doc)."""

    between: Any = None  # harness.suite.host.RunAfterRun, made by its first run here
    device: str | None = None  # the EGL device its OpenGL context is on
    fresh: bool = False  # every later run in a fresh process


_WORKER = _Worker()


def _run_fresh(job: dict[str, Any], out_root: str, baselines: str | None) -> dict[str, Any]:
    """Run ``job`` in a fresh ``python -m harness.suite.worker``: :func:`run_job`'s answer
    (its clock left out: the child's instants are not measured here), with ``crash`` when the
    child was killed. An interrupt here (Ray's cancel) is passed on to the child as SIGTERM,
    so the run finalizes as it would in this process."""
    import signal
    import subprocess

    from harness.suite.results import crash_reason
    from harness.suite.worker import STOP_WITH_PARENT, fresh_process, peak_rss_mb

    # plug-ins import from the current directory: the project folder (a remote worker's
    # working_dir), as in this process
    argv, env = fresh_process({**job, "out_root": out_root, "baselines": baselines},
                              {STOP_WITH_PARENT: str(os.getpid())})
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, env=env)
    assert proc.stderr is not None
    try:
        err = proc.stderr.read()
    except KeyboardInterrupt:
        proc.send_signal(signal.SIGTERM)
        err = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    code = proc.returncode = os.waitstatus_to_exitcode(status)
    lines = err.decode(errors="replace").strip().splitlines()
    return {"exit_code": code, "error": lines[-1] if code == 2 and lines else None,
            "peak_rss_mb": peak_rss_mb(usage), "clock": {}, "pid": proc.pid,
            "crash": crash_reason(code) if code < 0 else None}


def _run_here(job: dict[str, Any], out_root: str, baselines: str | None) -> dict[str, Any]:
    """Run ``job`` in this worker process, after the runs it has run (see the module doc)."""
    from harness.sim.render import gl_contexts_made
    from harness.suite.worker import run_job

    device = os.environ.get("MUJOCO_EGL_DEVICE_ID")
    w = _WORKER
    if w.between is not None and device != w.device:
        if gl_contexts_made():  # its kept context is on the other GPU
            return _run_fresh(job, out_root, baselines)
        w.device = device  # none made yet: its first will be on this one
    if w.fresh:
        return _run_fresh(job, out_root, baselines)
    if w.between is None:
        from harness.suite.host import RunAfterRun

        w.between, w.device = RunAfterRun(), device
    w.fresh = True  # until this run has ended and the process is put back
    note = w.between.before()
    res = run_job(job, out_root, baselines)
    peak, left = w.between.after(note)
    # an interrupt may come again mid-restore
    w.fresh = bool(left) or res["exit_code"] == INTERRUPTED_EXIT
    return {**res, "peak_rss_mb": peak, "peak_rss_note": note, "pid": os.getpid(),
            "gl_contexts": gl_contexts_made()}


def _task(job: dict[str, Any], out_root: str, baselines: str | None,
          driver_node: str) -> dict[str, Any]:
    """The Ray task: run one job in this worker process (:func:`_run_here`)."""
    import ray

    gpu_ids = ray.get_gpu_ids()
    if gpu_ids:  # render on the GPU Ray assigned (EGL device index)
        os.environ["MUJOCO_EGL_DEVICE_ID"] = str(int(float(gpu_ids[0])))
    os.environ.setdefault("MUJOCO_GL", "egl")
    node = ray.get_runtime_context().get_node_id()
    if node == driver_node:
        return {**_run_here(job, out_root, baselines), "archive": None, "node": node}
    with tempfile.TemporaryDirectory(prefix="srr-ray-") as tmp:
        res = _run_here(job, tmp, baselines)
        buf = io.BytesIO()
        run_dir = Path(tmp) / job["run_dir"]
        if run_dir.is_dir():
            with tarfile.open(fileobj=buf, mode="w") as tar:
                tar.add(run_dir, arcname=".")
        return {**res, "archive": buf.getvalue() or None, "node": node}


@dataclass
class _InFlight:
    spec: RunSpec
    ref: Any
    t0: float
    cancelled_at: float | None = None
    forced: bool = False
    timed_out: bool = False


class RayExecutor:
    name = "ray"

    def __init__(self, *, address: str | None = None, jobs: int | None = None,
                 baselines: Path | None = None, gpu_share: float = 0.5,
                 grace_s: float = 10.0, poll_s: float = 0.1) -> None:
        if not 0 < gpu_share <= 1:
            raise SrrError(f"--gpu-share: expected a fraction in (0, 1], got {gpu_share!r}")
        try:  # said before anything runs or is written
            import ray  # noqa: F401
        except ImportError as err:
            raise SrrError("--executor ray: Ray is not installed (pip install 'srr[ray]')") \
                from err
        self.address = address
        self.jobs = jobs or 0  # 0: as many as the cluster has CPUs
        self.baselines = baselines
        self.gpu_share = gpu_share
        self.grace_s = grace_s
        self.poll_s = poll_s
        self.cluster: dict[str, float] = {}

    def _connect(self) -> bool:
        """Start or join the cluster; True when srr connected (and must disconnect: that stops
        a cluster it started, and only leaves one it joined)."""
        import ray  # installed: checked when this executor was made

        if ray.is_initialized():
            return False
        cwd = os.getcwd()
        # RAY_ADDRESS (set by `ray job submit`, or by hand) names a cluster to join, as
        # --address does; without either, start a cluster of our own even when a `ray start`
        # cluster runs on this machine (ray.init would otherwise join that one)
        self.address = self.address or os.environ.get("RAY_ADDRESS") or None
        if self.address:
            try:
                ray.init(address=self.address, log_to_driver=False, logging_level=logging.ERROR,
                         runtime_env={"working_dir": cwd, "excludes": _EXCLUDES})
            except (ConnectionError, RuntimeError, ValueError) as err:
                raise SrrError(f"--address {self.address}: cannot join the Ray cluster "
                               f"({type(err).__name__}: {str(err).splitlines()[0]})") from err
            return True
        path = os.pathsep.join(p for p in (cwd, os.environ.get("PYTHONPATH")) if p)
        ray.init(address="local", num_cpus=self.jobs or os.cpu_count() or 1,
                 include_dashboard=False, log_to_driver=False, logging_level=logging.ERROR,
                 runtime_env={"env_vars": {"PYTHONPATH": path}})
        return True

    @contextlib.contextmanager
    def session(self) -> Iterator[None]:
        """One cluster connection over several :meth:`run` calls (a search's batches): a
        local cluster is started once, not per call."""
        connected_here = self._connect()
        if not self.jobs:  # as many as the cluster has CPUs, known before the first batch
            import ray

            cpus = ray.cluster_resources().get("CPU", 1)  # type: ignore[no-untyped-call]
            self.jobs = max(1, int(cpus))
        try:
            yield
        finally:
            if connected_here:
                import ray

                ray.shutdown()

    def run(self, specs: Sequence[RunSpec], out_root: Path,
            listen: Listener) -> tuple[list[RunOutcome], bool]:
        import ray

        connected_here = self._connect()
        try:
            self.cluster = {k: float(v) for k, v in ray.cluster_resources().items()}  # type: ignore[no-untyped-call]
            if not self.jobs:
                self.jobs = max(1, int(self.cluster.get("CPU", 1)))
            return self._run(ray, specs, out_root.resolve(), listen)
        finally:
            if connected_here:
                ray.shutdown()

    def _submit(self, ray: Any, spec: RunSpec, out_root: Path, driver: str) -> _InFlight:
        gpus = self.gpu_share if spec.renders and self.cluster.get("GPU", 0) > 0 else 0
        remote = ray.remote(max_calls=MAX_RUNS)(_task).options(
            num_cpus=1, num_gpus=gpus, max_retries=0, name=f"srr:{spec.id}")
        job = {**spec.job()}
        here = Path.cwd().resolve()
        path = Path(job["scenario_file"]).resolve()
        if self.address and path.is_relative_to(here):  # as found in the uploaded working_dir
            job["scenario_file"] = path.relative_to(here).as_posix()
        ref = remote.remote(job, str(out_root),
                            None if self.baselines is None else str(self.baselines.resolve()),
                            driver)
        return _InFlight(spec, ref, time.monotonic())

    def _finish(self, ray: Any, f: _InFlight, out_root: Path) -> RunOutcome:
        reaped = time.monotonic()
        wall = reaped - f.t0
        crash = error = note = None
        code = 3
        rss = None
        process: dict[str, float] = {}  # which process ran it, how many contexts it had made
        try:
            res = ray.get(f.ref)
            code, error, rss = int(res["exit_code"]), res["error"], res.get("peak_rss_mb")
            note, crash = res.get("peak_rss_note"), res.get("crash")
            process = {k: float(res[k]) for k in ("pid", "gl_contexts") if res.get(k)}
            if res.get("archive"):
                dest = out_root / f.spec.run_dir
                dest.mkdir(parents=True, exist_ok=True)
                with tarfile.open(fileobj=io.BytesIO(res["archive"])) as tar:
                    tar.extractall(dest, filter="data")
        except Exception as err:  # Ray reports the task's fate as exceptions
            kind = type(err).__name__
            first = (str(err).strip().splitlines() or [""])[0][:300]
            if f.timed_out:
                pass
            elif kind == "OutOfMemoryError":
                crash = f"out of memory (Ray OutOfMemoryError: {first})"
            elif kind in ("WorkerCrashedError", "TaskCancelledError", "NodeDiedError",
                          "ActorDiedError", "LocalRayletDiedError"):
                crash = f"the Ray worker died ({kind}: {first})"
            else:
                cause = getattr(err, "cause", None)
                error = f"{kind}: {cause if cause is not None else first}"
                code = 2
        outcome = outcome_of(f.spec, out_root, exit_code=code, error=error, wall_s=wall,
                             timed_out=f.timed_out, crash=crash, peak_rss_mb=rss)
        # the task's own instants are another process's (maybe another machine's) clock
        return dataclasses.replace(outcome, clock={**process, "submitted": f.t0,
                                                   "reaped": reaped}, peak_rss_note=note)

    def _cancel(self, ray: Any, f: _InFlight, now: float) -> None:
        if f.cancelled_at is None:
            f.cancelled_at = now
            with contextlib.suppress(Exception):
                ray.cancel(f.ref, force=False)
        elif not f.forced and now - f.cancelled_at >= self.grace_s:
            f.forced = True
            with contextlib.suppress(Exception):
                ray.cancel(f.ref, force=True)

    def _run(self, ray: Any, specs: Sequence[RunSpec], out_root: Path,
             listen: Listener) -> tuple[list[RunOutcome], bool]:
        driver = ray.get_runtime_context().get_node_id()
        pending = list(specs)
        flying: list[_InFlight] = []
        done: dict[str, RunOutcome] = {}
        interrupted = False
        try:
            while pending or flying:
                while pending and len(flying) < self.jobs:
                    f = self._submit(ray, pending.pop(0), out_root, driver)
                    flying.append(f)
                    listen(Event("start", f.spec, where="ray task"))
                ready, _ = ray.wait([f.ref for f in flying], num_returns=1,
                                    timeout=self.poll_s)
                now = time.monotonic()
                for f in list(flying):
                    if f.ref in ready:
                        flying.remove(f)
                        done[f.spec.id] = self._finish(ray, f, out_root)
                        listen(Event("finish", f.spec, done[f.spec.id]))
                    elif f.spec.timeout_s is not None and (
                            f.timed_out or now - f.t0 > f.spec.timeout_s):
                        f.timed_out = True
                        self._cancel(ray, f, now)
        except KeyboardInterrupt:
            interrupted = True
            while flying:
                now = time.monotonic()
                for f in list(flying):
                    self._cancel(ray, f, now)
                ready, _ = ray.wait([f.ref for f in flying], num_returns=len(flying),
                                    timeout=self.poll_s)
                for f in list(flying):
                    if f.ref in ready:
                        flying.remove(f)
                        done[f.spec.id] = self._finish(ray, f, out_root)
                        listen(Event("finish", f.spec, done[f.spec.id]))
        for spec in specs:
            if spec.id not in done:
                done[spec.id] = not_started(spec)
        return [done[s.id] for s in specs], interrupted
