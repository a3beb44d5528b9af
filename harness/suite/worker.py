"""One run of a suite, in whatever process an executor gives it.

:func:`run_job` runs a job (:meth:`RunSpec.job`) in the calling process and says how it ended;
the local executor runs it with :func:`serve` in a host process it forked
(:mod:`harness.suite.host`) or starts ``python -m harness.suite.worker JOB_JSON`` per run (a
fresh process), so a crash, a leak or a hung renderer costs that run only; Ray calls
:func:`run_job` in a task. The run directory is the only output that matters: the suite reads its
``summary.json`` afterwards (:mod:`harness.suite.results`).

Exit status of the module: the run's exit code (0, 1, 3), 2 when the run could not start (the
reason is the last line on stderr), 130 when interrupted (SIGTERM or SIGINT).
"""

from __future__ import annotations

import json
import os
import resource
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from harness.atomic import write_json_atomic
from harness.errors import SrrError
from harness.interrupt import INTERRUPTED_EXIT, StopRequests
from harness.run.loading import load
from harness.run.simulate import run_scenario
from harness.sim.render import gl_context_seconds, gl_contexts_made
from harness.suite.timeline import RunClock

__all__ = ["STOP_WITH_PARENT", "fresh_process", "peak_rss_mb", "run_job", "serve"]

#: An environment variable naming the process id whose end should stop the run (SIGTERM: it
#: finalizes), for :func:`main`.
STOP_WITH_PARENT = "SRR_STOP_WITH_PARENT"


def run_job(job: Mapping[str, Any], out_root: str | Path,
            baselines: str | None = None) -> dict[str, Any]:
    """Run ``job`` here, writing ``out_root / job["run_dir"]``.

    Returns ``{"exit_code": int, "error": str | None, "peak_rss_mb": float, "clock":
    {phase: instant, "gl_context_s": seconds}}``; ``error`` is the one-line reason when the
    run could not be started or finished (an :class:`~harness.errors.SrrError`);
    ``peak_rss_mb`` this process's peak resident memory; ``clock`` when the run reached each
    of :data:`harness.suite.timeline.PHASES` and the seconds this run spent making OpenGL
    contexts."""
    clock = RunClock()
    gl_before = gl_context_seconds()  # a host's earlier runs made theirs
    run_dir = Path(out_root) / str(job["run_dir"])

    def ended(code: int, error: str | None) -> dict[str, Any]:
        return {"exit_code": code, "error": error, "peak_rss_mb": peak_rss_mb(),
                "clock": clock.to_json(gl_context_seconds() - gl_before)}

    stop = StopRequests(at_once=True)
    try:
        with stop.installed():
            scenario = load(job["scenario_file"], overrides=list(job["overrides"]))
            clock.mark("loaded")
            res = run_scenario(scenario, source=str(job["scenario_file"]), out=run_dir,
                               baselines=Path(baselines) if baselines else None,
                               progress=clock.progress,
                               started=lambda _dir: clock.mark("built"))
            clock.mark("done")
    except (KeyboardInterrupt, Exception) as err:
        # stop.requested: an interrupt that became this error where it landed
        if isinstance(err, KeyboardInterrupt) or stop.requested:
            # stopped after its loop, the run's directory holds its recording (the suite
            # recovers it); before its first tick, there is none
            return ended(INTERRUPTED_EXIT, "interrupted before the run's summary was written"
                         if run_dir.is_dir() else
                         "interrupted before the run directory was written")
        if isinstance(err, SrrError):
            return ended(err.exit_code, str(err))
        raise
    return ended(res.exit_code, None)


def fresh_process(job: Mapping[str, Any], extra_env: Mapping[str, str] | None = None,
                  ) -> tuple[list[str], dict[str, str]]:
    """The command that runs ``job`` (with ``out_root``, as :func:`serve` takes it) in a fresh
    ``python -m harness.suite.worker``, and its environment: this process's, with the current
    directory first on ``PYTHONPATH`` (plug-ins, ``module:Class``, import from there, as with
    ``srr run``), and ``extra_env`` added."""
    path = os.pathsep.join(p for p in (os.getcwd(), os.environ.get("PYTHONPATH")) if p)
    return ([sys.executable, "-m", "harness.suite.worker", json.dumps(dict(job))],
            {**os.environ, "PYTHONPATH": path, **(extra_env or {})})


def peak_rss_mb(usage: resource.struct_rusage | None = None) -> float:
    """Peak resident memory in MiB of this process (or of ``usage``, a child's rusage)."""
    ru = usage or resource.getrusage(resource.RUSAGE_SELF)
    return round(ru.ru_maxrss / 1024.0, 1)  # Linux reports KiB


def serve(job: Mapping[str, Any]) -> int:
    """Run ``job`` (:meth:`RunSpec.job` with ``out_root``, ``baselines``, ``clock_file`` and
    ``warm_gl_s``) here, leave its clock in ``clock_file`` (with ``gl_contexts``: the OpenGL
    contexts this process has made so far, and ``pid``) and its error, if any, as the last line on
    stderr; its exit code."""
    result = run_job(job, job["out_root"], job.get("baselines"))
    if job.get("clock_file"):  # for the suite's timeline
        write_json_atomic(Path(job["clock_file"]),
                          {**result["clock"], "warm_gl_s": float(job.get("warm_gl_s", 0.0)),
                           "gl_contexts": gl_contexts_made(), "pid": os.getpid()})
    if result["error"]:
        sys.stderr.write(result["error"] + "\n")
    sys.stderr.flush()
    return int(result["exit_code"])


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        sys.stderr.write("usage: python -m harness.suite.worker JOB_JSON\n")
        return 2
    os.environ.setdefault("MUJOCO_GL", "egl")
    parent = os.environ.pop(STOP_WITH_PARENT, None)
    if parent:  # started by a Ray worker that may be killed (a forced cancel)
        from harness.suite.host import stop_with_parent

        stop_with_parent(int(parent))
    return serve(json.loads(argv[0]))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
