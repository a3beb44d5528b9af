"""``srr suite --resume``: a suite interrupted for real (Ctrl-C while a run is stuck), then
resumed in its folder: the run that ended is kept byte for byte, the interrupted one and the
one never started run, and the whole suite is judged as one. Also what a resume refuses
(another suite's folder, a folder of other files, a folder a suite still writes) and what it
runs again (a changed scenario, another srr)."""

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

from harness.errors import RunInUseError, SrrError
from tests.suite.plugins import STALLED_FILE

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
FORKLIFT = ROOT / "scenarios" / "forklift_warehouse.yaml"
PLUGIN = "systems_under_test.route_follower.plugin"

#: "done" (the costliest: it starts first on one slot) ends; "stuck" blocks 0.5 s in on the
#: first pass only; "later" is never started by the first pass.
SUITE = f"""
suite: resumable
scenarios:
  - path: {FORKLIFT}
    name: done
    set: {{duration: 2}}
  - path: {FORKLIFT}
    name: stuck
    set: {{duration: 1.5, {PLUGIN}: "tests.suite.plugins:StallsOnce"}}
  - path: {FORKLIFT}
    name: later
    set: {{duration: 1}}
"""


def _srr(*args: str) -> list[str]:
    return [sys.executable, "-m", "harness.cli", "suite", *args, "--jobs", "1", "-q"]


def _env(stalled: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT), STALLED_FILE: str(stalled)}


def _resume_lines(stderr: str) -> list[str]:
    """What ``srr suite`` said of the runs it runs again (beside its warnings: the entries
    share a baseline under other durations)."""
    return [line for line in stderr.splitlines() if line.startswith("srr suite: resume:")]


def _summary(out: Path) -> dict[str, Any]:
    data: dict[str, Any] = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return data


def test_a_resumed_suite_keeps_what_ended_and_runs_the_rest(tmp_path: Path) -> None:
    suite, out, stalled = tmp_path / "suite.yaml", tmp_path / "out", tmp_path / "stalled"
    suite.write_text(SUITE, encoding="utf-8")
    first = subprocess.Popen(_srr(str(suite), "--out", str(out)), cwd=ROOT,
                             env=_env(stalled), text=True, stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT)
    while not stalled.exists():
        assert first.poll() is None, first.communicate()[0]
        time.sleep(0.05)
    first.send_signal(signal.SIGINT)
    log = first.communicate(timeout=300)[0]
    assert first.returncode == 130, log
    before = {r["id"]: r for r in _summary(out)["runs"]}
    assert [before[k]["verdict"] for k in ("stuck#1", "later#1")] == ["INTERRUPTED"] * 2
    assert before["later#1"]["run_dir"] is None
    done_bag = out / before["done#1"]["run_dir"] / "bag" / "bag.mcap"
    kept = (done_bag.stat().st_ino, done_bag.stat().st_mtime_ns, done_bag.read_bytes())

    # resumed from another folder than the first pass's, as a CI retry may be
    second = subprocess.run(_srr(str(suite), "--out", str(out), "--resume"),
                            cwd=tmp_path, env=_env(stalled), text=True, capture_output=True,
                            timeout=600, check=False)
    assert second.returncode in (0, 1), second.stdout + second.stderr
    assert "resuming" in second.stdout and "1 run(s) kept, 2 to run" in second.stdout
    assert _resume_lines(second.stderr) == [
        "srr suite: resume: stuck#1: it was interrupted; it runs again"], second.stderr
    summary = _summary(out)
    assert summary["resumed"] == {
        "kept": ["done#1"], "ran": ["stuck#1", "later#1"],
        "notes": ["stuck#1: it was interrupted; it runs again"]}
    assert not summary["interrupted"] and summary["verdict"] != "INTERRUPTED"
    runs = {r["id"]: r for r in summary["runs"]}
    assert runs["done#1"] == {**before["done#1"], "timings": None}  # as it was, not run again
    assert (done_bag.stat().st_ino, done_bag.stat().st_mtime_ns, done_bag.read_bytes()) == kept
    for rid in ("stuck#1", "later#1"):
        assert runs[rid]["verdict"] not in ("INTERRUPTED", "INVALID"), runs[rid]
        assert runs[rid]["timings"] is not None and runs[rid]["digest"]
        assert (out / runs[rid]["run_dir"] / "bag" / "bag.mcap").is_file()
    # the interrupted run's folder and log were replaced: its log holds the second pass only
    assert "Traceback" not in (out / runs["stuck#1"]["log"]).read_text(encoding="utf-8")
    assert not (out / "run.lock").exists()  # the suite's lock, released at its end
    junit = (out / "junit.xml").read_text(encoding="utf-8")
    assert junit.count("<testcase ") == 3 and "<skipped" not in junit

    # nothing left to do: everything kept, nothing run
    third = subprocess.run(_srr(str(suite), "--out", str(out), "--resume"),
                           cwd=ROOT, env=_env(stalled), text=True, capture_output=True,
                           timeout=600, check=False)
    assert third.returncode == second.returncode, third.stdout + third.stderr
    assert "3 run(s) kept, 0 to run" in third.stdout and _resume_lines(third.stderr) == []
    assert {r["id"]: r["digest"] for r in _summary(out)["runs"]} == {
        rid: r["digest"] for rid, r in runs.items()}


def test_what_a_resume_runs_again_and_what_it_refuses(tmp_path: Path) -> None:
    from harness import api, runlock
    from harness.suite.local import LocalExecutor
    from harness.suite.runner import plan_suite, run_suite

    suite = tmp_path / "suite.yaml"
    suite.write_text(f"suite: small\nscenarios:\n  - {{path: {FORKLIFT}, repeat: 2, "
                     "set: {duration: 0.5}}\n", encoding="utf-8")
    out = tmp_path / "out"
    plan = plan_suite([suite])
    run_suite(plan, LocalExecutor(1), out=out)
    assert [len(x) for x in (lambda r: (r.kept, r.again, r.notes))(
        api.resume_suite(plan, out))] == [2, 0, 0]

    # another duration: its runs are stale, each said with the first difference
    suite.write_text(suite.read_text(encoding="utf-8").replace("0.5", "0.6"), encoding="utf-8")
    changed = api.resume_suite(plan_suite([suite]), out)
    assert changed.kept == () and [s.id for s in changed.again] == [
        "forklift_warehouse#1", "forklift_warehouse#2"]
    assert changed.notes[0] == ("forklift_warehouse#1: its scenario changed since it ran "
                                "(duration: 0.5 → 0.6); it runs again")

    # recorded by another srr
    run1 = out / "runs" / "forklift_warehouse" / "nominal" / "r1" / "summary.json"
    data = json.loads(run1.read_text(encoding="utf-8"))
    data["versions"]["srr"] = "0.0.1"
    run1.write_text(json.dumps(data), encoding="utf-8")
    older = api.resume_suite(plan, out)
    assert [s.id for s in older.again] == ["forklift_warehouse#1"]
    assert "recorded by srr 0.0.1" in older.notes[0]
    # stopped at its timeout (its own summary says so, whatever the suite's says)
    run2 = out / "runs" / "forklift_warehouse" / "nominal" / "r2" / "summary.json"
    data = json.loads(run2.read_text(encoding="utf-8"))
    data["health"].append({"name": "wall_clock_timeout", "ok": False, "detail": "300 s"})
    run2.write_text(json.dumps(data), encoding="utf-8")
    assert api.resume_suite(plan, out).notes[1] == (
        "forklift_warehouse#2: it was stopped at its timeout; it runs again")

    # a folder a suite still writes: refused, nothing touched
    with runlock.owning(out, "written", fresh=False), pytest.raises(RunInUseError) as live:
        api.resume_suite(plan, out)
    assert f"pid {os.getpid()}" in str(live.value)

    # another suite's folder, a folder of other files
    other = tmp_path / "other"
    other.mkdir()
    (other / "summary.json").write_text(json.dumps(
        {**json.loads((out / "summary.json").read_text(encoding="utf-8")),
         "name": "nightly"}), encoding="utf-8")
    with pytest.raises(SrrError, match="holds the suite 'nightly', not 'small'"):
        api.resume_suite(plan, other)
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "todo.txt").write_text("mine", encoding="utf-8")
    with pytest.raises(SrrError, match="holds no suite output to resume"):
        api.resume_suite(plan, notes)
    assert (notes / "todo.txt").read_text(encoding="utf-8") == "mine"
    # a missing folder: everything runs
    assert len(api.resume_suite(plan, tmp_path / "new").again) == 2


def test_srr_suite_resume_needs_out_and_refuses_a_foreign_folder(tmp_path: Path) -> None:
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "todo.txt").write_text("mine", encoding="utf-8")
    for args, line in (
            ((), "srr suite: --resume: name the folder of the suite to resume with --out"),
            (("--out", str(notes)), f"srr suite: --out {notes}: folder is not empty and "
             "holds no suite output to resume (no summary.json, runs/ or logs/)")):
        proc = subprocess.run([sys.executable, "-m", "harness.cli", "suite", str(FORKLIFT),
                               "--resume", *args], cwd=ROOT, capture_output=True, text=True,
                              env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=300,
                              check=False)
        assert (proc.returncode, proc.stderr.strip(), proc.stdout) == (2, line, "")
    assert sorted(p.name for p in notes.iterdir()) == ["todo.txt"]
