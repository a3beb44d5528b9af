"""Where a suite's wall time goes: each run's steps, and the time outside the runs.

A worker times its run (:class:`RunClock`: the instants it reached each of :data:`PHASES`,
``time.monotonic``, which on Linux is one clock for every process of the machine); the local
executor adds when it submitted the run and when it found it ended (:func:`take_clock`). The
suite's ``summary.json`` then holds, per run, ``timings`` (:func:`run_timings`: when it
started and finished, seconds from the suite's start, and how long each step took) and, for
the suite, ``timeline`` (:func:`suite_timeline`: checking before the first run, the span of
the runs, the time after the last one, and how busy the workers were). These are wall-clock
figures about the machine, never part of what a run records or how it is judged.
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["PHASES", "STEPS", "RunClock", "clock_path", "run_timings", "suite_timeline",
           "take_clock"]

#: The instants a worker reaches, in order: ``ready`` it began the job (its process started,
#: srr imported), ``loaded`` the scenario loaded, ``built`` the scene, graphs and systems under
#: test built and the run directory owned, ``first_tick`` the first tick done (with cameras:
#: the OpenGL contexts made), ``ticks`` the last tick done, ``done`` scored, judged and its
#: files written (report included). A phase a run never reached is absent.
PHASES = ("ready", "loaded", "built", "first_tick", "ticks", "done")

#: A run's steps in ``timings["steps"]``, each the time between two instants: ``start``
#: submitted → ready (process start or fork, imports), ``load``, ``build``, ``first_tick``,
#: ``loop`` (the other ticks), ``finish`` (scoring, judging, report), ``exit`` done → the
#: executor found the process ended (its teardown, the executor's polling).
STEPS = (("start", "submitted", "ready"), ("load", "ready", "loaded"),
         ("build", "loaded", "built"), ("first_tick", "built", "first_tick"),
         ("loop", "first_tick", "ticks"), ("finish", "ticks", "done"),
         ("exit", "done", "reaped"))


class RunClock:
    """The instants of :data:`PHASES` one run reaches in its worker."""

    def __init__(self) -> None:
        self.at: dict[str, float] = {"ready": time.monotonic()}
        self._cpu0 = time.process_time()  # every thread of the process: render, recorder...

    def mark(self, phase: str) -> None:
        self.at.setdefault(phase, time.monotonic())

    def progress(self, ticks: int, n_ticks: int) -> None:
        """A run's progress callback: ``first_tick`` and ``ticks``."""
        if ticks == 1:
            self.mark("first_tick")
        if ticks == n_ticks:
            self.mark("ticks")

    def to_json(self, gl_context_s: float) -> dict[str, float]:
        """The instants, the OpenGL seconds, and ``cpu_s``: the CPU seconds the process spent
        since ``ready`` (user and system, all its threads; a host runs one run at a time, so
        they are this run's)."""
        return {**{k: round(v, 6) for k, v in self.at.items()},
                "gl_context_s": round(gl_context_s, 6),
                "cpu_s": round(time.process_time() - self._cpu0, 6)}


def clock_path(log_file: Path) -> Path:
    """Where a local worker leaves its clock: beside its log (taken away once read)."""
    return log_file.with_name(log_file.name.removesuffix(".log") + ".clock.json")


def take_clock(path: Path, submitted: float, reaped: float) -> dict[str, float]:
    """The worker's clock at ``path`` (removed; none when the worker left none, e.g. killed)
    with the executor's ``submitted`` and ``reaped`` instants."""
    clock: dict[str, float] = {}
    with contextlib.suppress(OSError, ValueError):
        data = json.loads(path.read_text(encoding="utf-8"))
        if isinstance(data, dict):
            clock = {str(k): float(v) for k, v in data.items()
                     if isinstance(v, (int, float)) and not isinstance(v, bool)}
    with contextlib.suppress(OSError):
        path.unlink()
    return {**clock, "submitted": submitted, "reaped": reaped}


def run_timings(clock: Mapping[str, float] | None, t0: float) -> dict[str, Any] | None:
    """``{"started_s", "finished_s", "steps": {step: seconds}, "gl_context_s", "warm_gl_s",
    "gl_contexts", "pid", "cpu_s", "cpus"}``: seconds from ``t0`` (the suite's start), the
    :data:`STEPS` whose both ends are known, the seconds the run spent making OpenGL contexts,
    those its process spent making one before its first run, how many contexts its process
    had made by its end (a host that reuses its context: 1 over all its runs), its process id
    (the runs of one host share it), the CPU seconds its process spent from ``ready`` to its
    end (all threads) and those over the wall seconds of that span: how many CPUs the run kept
    busy (``None`` when its worker left no clock of them)."""
    if not clock or "submitted" not in clock or "reaped" not in clock:
        return None
    steps = {name: round(clock[b] - clock[a], 3) for name, a, b in STEPS
             if a in clock and b in clock}
    cpu = clock.get("cpu_s")
    ran = clock.get("done", clock["reaped"]) - clock.get("ready", clock["submitted"])
    return {"started_s": round(clock["submitted"] - t0, 3),
            "finished_s": round(clock["reaped"] - t0, 3), "steps": steps,
            "gl_context_s": round(clock.get("gl_context_s", 0.0), 3),
            "warm_gl_s": round(clock.get("warm_gl_s", 0.0), 3),
            "gl_contexts": int(clock.get("gl_contexts", 0)),
            "pid": int(clock["pid"]) if "pid" in clock else None,
            "cpu_s": None if cpu is None else round(cpu, 3),
            "cpus": round(cpu / ran, 3) if cpu is not None and ran > 0 else None}


def suite_timeline(timings: Sequence[Mapping[str, Any] | None], *, jobs: int,
                   checked_s: float, wall_s: float) -> dict[str, Any]:
    """The suite's ``timeline``: ``checked_s`` (planning and checking, before ``t0``),
    ``first_start_s`` / ``last_finish_s`` (from ``t0``), ``runs_s`` (the sum of the runs'
    walls), ``utilization`` (``runs_s`` over ``jobs`` × the span from the first start to the
    last finish) and ``steps_s`` (each step summed over the runs)."""
    known = [t for t in timings if t is not None]
    out: dict[str, Any] = {"checked_s": round(checked_s, 3), "wall_s": round(wall_s, 3),
                           "jobs": jobs}
    if not known:
        return out
    first = min(t["started_s"] for t in known)
    last = max(t["finished_s"] for t in known)
    busy = sum(t["finished_s"] - t["started_s"] for t in known)
    steps: dict[str, float] = {}
    for t in known:
        for k, v in t["steps"].items():
            steps[k] = steps.get(k, 0.0) + v
    out.update(first_start_s=round(first, 3), last_finish_s=round(last, 3),
               runs_s=round(busy, 3),
               utilization=round(busy / (jobs * (last - first)), 3) if last > first else None,
               steps_s={k: round(v, 3) for k, v in steps.items()},
               gl_context_s=round(sum(t["gl_context_s"] for t in known), 3))
    timed = [t for t in known if t.get("cpu_s") is not None and t.get("cpus")]
    if timed:
        cpu = sum(t["cpu_s"] for t in timed)
        ran = sum(t["cpu_s"] / t["cpus"] for t in timed)
        out.update(cpu_s=round(cpu, 3), cpus=round(cpu / ran, 3))
    return out
