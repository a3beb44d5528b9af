"""Where a suite's time goes: runs' timings and the suite's timeline (a real suite's are
checked in tests/suite/test_hosts.py)."""

from __future__ import annotations

from harness.suite.timeline import STEPS, run_timings, suite_timeline


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
