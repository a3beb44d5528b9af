"""Where a suite's time goes: runs' timings and the suite's timeline (a real suite's are
checked in tests/suite/test_hosts.py)."""

from __future__ import annotations

import threading
import time

from harness.suite.timeline import STEPS, RunClock, run_timings, suite_timeline


def test_run_timings_are_the_steps_between_known_instants() -> None:
    clock = {"submitted": 10.0, "ready": 10.5, "loaded": 11.0, "built": 12.0,
             "first_tick": 12.5, "ticks": 20.0, "done": 21.0, "reaped": 21.25,
             "gl_context_s": 0.25}
    t = run_timings(clock, t0=9.0)
    assert t is not None
    assert t["started_s"] == 1.0 and t["finished_s"] == 12.25
    assert list(t["steps"]) == [name for name, _, _ in STEPS]
    assert t["steps"] == {"start": 0.5, "load": 0.5, "build": 1.0, "first_tick": 0.5,
                          "loop": 7.5, "finish": 1.0, "exit": 0.25}
    assert sum(t["steps"].values()) == t["finished_s"] - t["started_s"]
    # a worker killed before its first tick: only what it reached
    partial = run_timings({"submitted": 10.0, "ready": 10.5, "loaded": 11.0, "reaped": 15.0},
                          t0=10.0)
    assert partial is not None and partial["steps"] == {"start": 0.5, "load": 0.5}
    assert run_timings(None, 0.0) is None and run_timings({"ready": 1.0}, 0.0) is None


def test_suite_timeline_utilization_and_time_outside_the_runs() -> None:
    a = run_timings({"submitted": 1.0, "ready": 1.5, "reaped": 5.0}, t0=0.0)
    b = run_timings({"submitted": 1.0, "ready": 2.0, "reaped": 3.0}, t0=0.0)
    tl = suite_timeline([a, b, None], jobs=2, checked_s=0.5, wall_s=6.0)
    assert tl["first_start_s"] == 1.0 and tl["last_finish_s"] == 5.0
    assert tl["runs_s"] == 6.0 and tl["utilization"] == 0.75  # 6 of 2 x 4 s
    assert tl["steps_s"] == {"start": 1.5}
    assert suite_timeline([None], jobs=1, checked_s=0.1, wall_s=1.0) == {
        "checked_s": 0.1, "wall_s": 1.0, "jobs": 1}


def _burn(cpu_s: float) -> None:
    """Spend ``cpu_s`` of this thread's CPU time (however loaded the machine)."""
    end = time.thread_time() + cpu_s
    while time.thread_time() < end:
        pass


def test_a_runs_cpu_seconds_count_its_threads_and_only_since_it_began() -> None:
    _burn(0.2)  # before the clock: not the run's
    clock = RunClock()
    worker = threading.Thread(target=_burn, args=(0.3,))  # a render or recorder thread
    worker.start()
    worker.join()
    first = clock.to_json(0.0)["cpu_s"]
    assert 0.3 <= first < 0.45
    assert RunClock().to_json(0.0)["cpu_s"] < 0.1  # a host's next run starts from zero


def test_cpus_a_run_kept_busy_and_the_suites_mean() -> None:
    a = run_timings({"submitted": 0.0, "ready": 1.0, "done": 3.0, "reaped": 3.5,
                     "cpu_s": 3.0}, t0=0.0)  # 1.5 CPUs over its 2 s
    b = run_timings({"submitted": 0.0, "ready": 0.5, "done": 2.5, "reaped": 3.0,
                     "cpu_s": 1.0}, t0=0.0)  # 0.5 CPU over 2 s
    old = run_timings({"submitted": 0.0, "ready": 0.5, "reaped": 1.0}, t0=0.0)  # no cpu_s
    assert a is not None and b is not None and old is not None
    assert (a["cpu_s"], a["cpus"]) == (3.0, 1.5) and (b["cpu_s"], b["cpus"]) == (1.0, 0.5)
    assert old["cpu_s"] is None and old["cpus"] is None
    tl = suite_timeline([a, b, old], jobs=2, checked_s=0.0, wall_s=4.0)
    assert tl["cpu_s"] == 4.0 and tl["cpus"] == 1.0  # 4 CPU-seconds over 4 s of runs
    assert "cpus" not in suite_timeline([old], jobs=1, checked_s=0.0, wall_s=1.0)
