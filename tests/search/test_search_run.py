"""``srr search`` end to end, with real runs: the planted defect found (and its
counterexample added to a suite and blessed), an objective that holds everywhere (exit 0, no
counterexample), a search process killed with SIGKILL and resumed, a metric no run has.

Runs are a few seconds of simulated time; the planted-defect search's space lies inside the
defect's region by construction (every point violates), so what is asserted does not depend
on how lucky the sampler is (benchmarks/bench_search.py measures that)."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from harness.cli import main
from harness.scenario import load_scenario

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
PLANTED = ROOT / "scenarios" / "planted" / "dock_crossing_blind_spot.yaml"
CROSSING = ROOT / "scenarios" / "dock_worker_crossing.yaml"
# inside the blind spot: faster than 2 m/s, in the ROI during [23.5, 24.5) s
NARROW = ["--space", "workers.0.speed=2.2..2.5", "--space", "workers.0.start_delay=20.5..22"]
OBJECTIVE = ["--objective", "safety.over_mute", "--violated-above", "1.5"]


@pytest.fixture(autouse=True)
def _project_root(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)  # the planted plug-in imports from the project root


def _summary(out: Path) -> dict:
    return json.loads((out / "search.json").read_text())


def test_planted_defect_found_and_added_to_a_suite(tmp_path: Path) -> None:
    project = tmp_path / "proj"
    (project / "scenarios").mkdir(parents=True)
    (project / "baselines").mkdir()
    (project / "pyproject.toml").write_text("[project]\nname = 'p'\n")
    scenario = project / "scenarios" / "crossing.yaml"
    scene = ROOT / "scenarios" / "dock" / "scene.yaml"
    text = PLANTED.read_text().replace("[../dock/scene.yaml]", f"[{scene}]").replace(
        "baseline: dock_worker_crossing", "baselines: ../baselines")  # relative to this file
    scenario.write_text(text)
    suite = project / "suite.yaml"
    suite.write_text("# the nightly suite\nsuite: nightly   # its name\nscenarios:\n"
                     "  - path: scenarios/crossing.yaml   # the crossing\n")
    out = tmp_path / "out"
    code = main(["search", str(scenario), *NARROW, *OBJECTIVE, "--set", "duration=26",
                 "--budget", "6", "--stop-at-first", "--jobs", "2", "--seed", "3",
                 "--out", str(out),
                 "--counterexamples", "1", "--add-to-suite", str(suite), "--bless",
                 "--reason", "found by search", "-q"])
    assert code == 1
    s = _summary(out)
    assert s["verdict"] == "VIOLATED" and s["counts"]["violated"] >= 1
    assert s["first_violation"] == 0
    assert s["counts"]["trials"] == 2  # --stop-at-first: after the first batch (--jobs 2)
    [cex] = s["counterexamples"]
    worst = min((t for t in s["trials"] if t["status"] == "violated"), key=lambda t: t["margin"])
    assert cex["trial"] == worst["number"] and cex["value"] > 1.5
    # the parameters are baked in: the file alone reproduces the trial's worker
    sc = load_scenario(out / cex["file"])
    assert sc.workers[0].speed == pytest.approx(cex["params"]["workers.0.speed"])
    assert sc.workers[0].start_delay == pytest.approx(cex["params"]["workers.0.start_delay"])
    assert sc.duration == 26 and sc.name == cex["name"]
    assert sc.baselines == str((project / "baselines").resolve())  # wherever the file goes
    # the suite keeps its comments and gains the entry; the entry has its own baseline
    suite_text = suite.read_text()
    assert "# the nightly suite" in suite_text and "# the crossing" in suite_text
    assert f"name: {cex['name']}" in suite_text
    assert (project / "baselines" / f"{cex['name']}.json").is_file()
    assert json.loads((project / "baselines" / f"{cex['name']}.json").read_text())[
        "reason"] == "found by search"
    # JUnit: the objective case fails, with one case for the counterexample
    cases = ET.parse(out / "junit.xml").getroot().iter("testcase")
    failed = {c.get("name") for c in cases if c.find("failure") is not None}
    assert failed == {"search.safety.over_mute", f"counterexample.{cex['id']}"}
    # the page: the threshold, one dot per trial, the counterexample linked to its report
    page = (out / "index.html").read_text()
    assert 'class="threshold"' in page and 'data-value="1.5"' in page
    assert page.count('class="trial"') == s["counts"]["trials"]
    assert f'href="{cex["report"]}"' in page and (out / cex["report"]).is_file()
    assert "<script" not in page and "http://" not in page and "https://" not in page


def test_an_objective_that_holds_everywhere_exits_0(tmp_path: Path) -> None:
    """The reference monitor over the planted defect's region: no violation, no false alarm."""
    out = tmp_path / "out"
    code = main(["search", str(CROSSING), *NARROW, *OBJECTIVE, "--set", "duration=26",
                 "--budget", "2", "--jobs", "2", "--sampler", "random", "--out", str(out),
                 "--prune", "-q"])
    assert code == 0
    s = _summary(out)
    assert s["verdict"] == "HOLDS" and s["counts"] == {"trials": 2, "violated": 0,
                                                       "valid": 2, "invalid": 0, "no_value": 0,
                                                       "killed": 0}
    assert s["counterexamples"] == [] and not list((out / "counterexamples").glob("*"))
    assert 'id="no-counterexample"' in (out / "index.html").read_text()
    for t in s["trials"]:  # --prune: the recordings of passing trials go, the rest stays
        assert not (out / t["run_dir"] / "bag").exists()
        assert (out / t["run_dir"] / "summary.json").is_file() and (out / t["report"]).is_file()


def _trials(db: Path) -> list[tuple[int, str]]:
    with sqlite3.connect(db) as con:
        return con.execute("select number, state from trials order by number").fetchall()


def test_killed_search_resumes_where_it_stopped(tmp_path: Path) -> None:
    out = tmp_path / "out"
    argv = [str(CROSSING), "--space", "workers.0.speed=0.5..2.5", "--objective",
            "safety.over_mute", "--violated-above", "50", "--set", "duration=3",
            "--budget", "3", "--jobs", "1", "--sampler", "random", "--seed", "5",
            "--out", str(out), "-q"]
    proc = subprocess.Popen([sys.executable, "-m", "harness.cli", "search", *argv],
                            cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    db = out / "study.db"
    # wait until one trial finished and the next one runs (its worker has started)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline:
        try:
            states = [s for _, s in _trials(db)] if db.is_file() else []
        except sqlite3.OperationalError:  # the study's tables are being created
            states = []
        if states.count("COMPLETE") >= 1 and "RUNNING" in states:
            break
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
        time.sleep(0.05)
    else:
        pytest.fail("the search did not get to its second trial")
    import psutil

    workers = psutil.Process(proc.pid).children(recursive=True)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    for w in workers:  # the worker runs in its own session: kill -9 does not reach it
        w.kill()
    before = _trials(db)
    assert ("RUNNING" in {s for _, s in before}) and proc.returncode == -signal.SIGKILL
    assert main(["search", *argv]) == 0  # resume: the same command
    after = _trials(db)
    numbers = [n for n, _ in after]
    assert numbers == list(range(len(numbers)))  # no number used twice
    assert after[: len(before)] != before  # the killed trial is now marked failed
    s = _summary(out)
    killed = [t for t in s["trials"] if t["status"] == "killed"]
    done = [t for t in s["trials"] if t["status"] in ("holds", "violated")]
    assert len(killed) == 1 and len(done) == 3  # the budget counts finished trials only
    first = next(t for t in s["trials"] if t["number"] == 0)
    assert first["status"] == "holds"  # kept from before the kill, not run again
    assert s["ran_now"] == 3 - sum(1 for _, st in before if st == "COMPLETE")


def test_an_interrupted_search_does_not_pass_its_objective_in_junit(tmp_path: Path) -> None:
    """Ctrl-C before any violation: exit 130, and junit.xml's objective case is skipped (the
    search did not show that the objective holds), not passed."""
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "search", str(ROOT / "scenarios/two_forklifts.yaml"),
         "--space", "systems_under_test.follower_a.params.speed=1..3", "--objective",
         "control.forklift.cross_track_error.max", "--violated-above", "50", "--set",
         "duration=600", "--budget", "2", "--jobs", "1", "--out", str(out), "-q"],
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 300
    while not list(out.glob("runs/t00000/bag/*.mcap")):  # the first trial is recording
        assert proc.poll() is None and time.monotonic() < deadline, (
            proc.stderr.read() if proc.stderr else "")
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    assert proc.wait(timeout=120) == 130
    s = _summary(out)
    assert s["verdict"] == "INTERRUPTED" and s["counts"]["violated"] == 0
    suite = ET.parse(out / "junit.xml").getroot().find("testsuite")
    assert suite is not None and suite.get("skipped") == "1" and suite.get("failures") == "0"
    (case,) = suite.iter("testcase")
    skipped = case.find("skipped")
    assert skipped is not None and case.find("system-out") is None
    assert skipped.get("message", "").startswith("interrupted with 0 of 2 trials done: ")


def test_a_metric_no_run_has_stops_the_search(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    code = main(["search", str(CROSSING), "--space", "workers.0.speed=0.5..2.5",
                 "--objective", "safety.over_mutes", "--violated-above", "1",
                 "--set", "duration=2", "--budget", "4", "--jobs", "1", "--out", str(out),
                 "-q"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("srr search: --objective safety.over_mutes: the runs' summary.json "
                          "has no such metric; did you mean safety.over_mute")
    assert not out.exists()  # stopped after the first run; exit 2 leaves nothing behind


@pytest.mark.ray
def test_search_on_a_local_ray_cluster(tmp_path: Path) -> None:
    """Two batches on one cluster (started once for the search, stopped at its end)."""
    pytest.importorskip("ray")
    out = tmp_path / "out"
    code = main(["search", str(ROOT / "scenarios" / "forklift_warehouse.yaml"), "--space",
                 "systems_under_test.route_follower.params.speed=0.5..2.5", "--objective",
                 "control.cross_track_error.max", "--violated-above", "50", "--set",
                 "duration=2", "--budget", "3", "--jobs", "2", "--executor", "ray",
                 "--out", str(out), "-q"])
    assert code == 0
    s = _summary(out)
    assert s["executor"] == "ray" and s["counts"]["valid"] == 3
    assert all((out / t["report"]).is_file() for t in s["trials"])
