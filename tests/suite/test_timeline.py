"""Where a suite's time goes (runs' timings, the suite's timeline) and workers started ahead
of a free slot: same bytes, their OpenGL context made before the run, nothing left behind
when the suite is interrupted before they run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from harness.suite.timeline import STEPS, run_timings, suite_timeline
from tests.suite.plugins import PLANNER_PID, STALLED_FILE

ROOT = Path(__file__).resolve().parents[2]
FORKLIFT = ROOT / "scenarios" / "forklift_warehouse.yaml"
CROSSING = ROOT / "scenarios" / "dock_worker_crossing.yaml"
PLUGIN = "systems_under_test.route_follower.plugin"

#: Runs a suite file on a forked local executor with ``ahead`` workers started ahead, in a
#: process of its own (this one may have rendered or have threads: it would not fork).
SCRIPT = f"""
import os, sys
from pathlib import Path
os.environ["{PLANNER_PID}"] = str(os.getpid())
from harness.suite.local import LocalExecutor
from harness.suite.runner import plan_suite, run_suite
plan = plan_suite([sys.argv[1]])
run_suite(plan, LocalExecutor(int(sys.argv[3]), fork=True, ahead=int(sys.argv[4])),
          out=Path(sys.argv[2]))
"""


def _suite(tmp_path: Path, text: str, jobs: int, ahead: int,
           env: dict[str, str] | None = None) -> subprocess.Popen[str]:
    suite = tmp_path / "suite.yaml"
    suite.write_text(text, encoding="utf-8")
    return subprocess.Popen([sys.executable, "-c", SCRIPT, str(suite), str(tmp_path / "out"),
                             str(jobs), str(ahead)], cwd=ROOT, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT), **(env or {})},
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)


def _runs(out: Path) -> dict[str, dict[str, Any]]:
    s = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return {r["id"]: r for r in s["runs"]}


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


@pytest.mark.slow
def test_a_worker_started_ahead_renders_the_same_bytes_with_its_context_made_before(
        tmp_path: Path) -> None:
    """Two repeats of a rendering scene on one worker, one more started ahead: the second
    run's worker made its OpenGL context while the first ran and its renderer used it (no
    context made during the run); both record what a fresh interpreter records; every run
    has its timings, the second starting once the first had finished."""
    from harness.suite.local import LocalExecutor
    from harness.suite.runner import plan_suite, run_suite

    text = f"scenarios:\n  - {{path: {CROSSING}, repeat: 2, set: {{duration: 1.5}}}}\n"
    proc = _suite(tmp_path, text, jobs=1, ahead=1)
    log = proc.communicate(timeout=600)[0]
    assert proc.returncode == 0, log
    runs = _runs(tmp_path / "out")
    first, second = runs["dock_worker_crossing#1"], runs["dock_worker_crossing#2"]
    assert first["timings"]["warm_gl_s"] == 0 and first["timings"]["gl_context_s"] > 0
    assert second["timings"]["warm_gl_s"] > 0 and second["timings"]["gl_context_s"] == 0
    assert second["timings"]["started_s"] >= first["timings"]["finished_s"]
    for run in (first, second):
        t = run["timings"]
        assert set(t["steps"]) == {name for name, _, _ in STEPS}
        assert min(t["steps"].values()) >= 0 and t["finished_s"] > t["started_s"]
    assert not list((tmp_path / "out" / "logs").glob("*.clock.json"))  # taken once read
    (tmp_path / "suite.yaml").write_text(text.replace("repeat: 2", "repeat: 1"))
    fresh = tmp_path / "fresh"
    run_suite(plan_suite([tmp_path / "suite.yaml"]), LocalExecutor(1, fork=False), out=fresh)
    (plain,) = _runs(fresh).values()
    assert first["digest"] == second["digest"] == plain["digest"] is not None


@pytest.mark.slow
def test_an_interrupted_suite_leaves_nothing_of_a_worker_that_waited(tmp_path: Path) -> None:
    """Ctrl-C while the only slot's run is stuck and the next run's worker waits for the
    slot: the waiting one is stopped without running — no run directory, no log — and
    reported as not started; the stuck run is stopped and finalized as before."""
    stalled = tmp_path / "stalled"
    text = f"""
scenarios:
  - path: {FORKLIFT}
    name: slow
    set: {{duration: 3, {PLUGIN}: "tests.suite.plugins:Staller"}}
  - path: {FORKLIFT}
    name: quick
    set: {{duration: 1}}
"""
    proc = _suite(tmp_path, text, jobs=1, ahead=1, env={STALLED_FILE: str(stalled)})
    out = tmp_path / "out"
    while not stalled.exists():  # the slow run (the costlier: first) is stuck mid-way
        assert proc.poll() is None, proc.communicate()[0]
        time.sleep(0.05)
    while not (out / "logs" / "quick_1.log").exists():  # its worker is started ahead
        assert proc.poll() is None, proc.communicate()[0]
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    log = proc.communicate(timeout=300)[0]
    assert proc.returncode == 0, log
    runs = _runs(out)
    assert runs["slow#1"]["verdict"] == "INTERRUPTED" and runs["slow#1"]["run_dir"]
    quick = runs["quick#1"]
    assert quick["verdict"] == "INTERRUPTED" and quick["reasons"] == [
        "not started: the suite was interrupted"]
    assert quick["run_dir"] is None and not (out / "runs" / "quick").exists()
    assert sorted(p.name for p in (out / "logs").iterdir()) == ["slow_1.log"]
