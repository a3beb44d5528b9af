"""Real suites end to end: worker processes (local) and a real local Ray cluster, with a
worker that segfaults, one stuck mid-way and one stuck before its first tick (both past their
timeouts), one whose output depends on its process id (flaky), and a sweep of three values;
Ctrl-C; the bundled scenarios over repeats.

The stuck plug-ins block until they are stopped (tests/suite/plugins.py), so what these tests
assert holds however slow the machine is: no run can finish before the suite stops it."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

from harness import api
from harness.summary import read_summary
from tests.suite.plugins import PLANNER_PID, STALLED_FILE

ROOT = Path(__file__).resolve().parents[2]
FORKLIFT = ROOT / "scenarios" / "forklift_warehouse.yaml"
CROSSING = ROOT / "scenarios" / "dock_worker_crossing.yaml"
SPEED = "systems_under_test.route_follower.params.speed"
PLUGIN = "systems_under_test.route_follower.plugin"

MISBEHAVING = f"""
suite: misbehaving
scenarios:
  - path: {FORKLIFT}
    name: segfault
    set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:Segfaulter"}}
  - path: {FORKLIFT}
    name: hang
    timeout: 6
    set: {{duration: 3, {PLUGIN}: "tests.suite.plugins:Staller"}}
  - path: {FORKLIFT}
    name: stuck
    timeout: 2
    set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:BlockedAtStart"}}
  - path: {FORKLIFT}
    name: pid
    repeat: 2
    set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:PidDependent"}}
  - path: {FORKLIFT}
    name: speeds
    set: {{duration: 2}}
    sweep: {{{SPEED}: [1.0, 1.5, 2.0]}}
"""

pytestmark = pytest.mark.slow


@pytest.fixture()
def suite_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(ROOT)  # plug-ins import from the project root, like `srr run`
    monkeypatch.setenv(PLANNER_PID, str(os.getpid()))
    p = tmp_path / "suite.yaml"
    p.write_text(MISBEHAVING, encoding="utf-8")
    return p


def _by_id(summary: dict[str, Any], key: str) -> dict[str, Any]:
    return {g["id"]: g for g in summary[key]}


def _check_misbehaving(res: Any, out: Path) -> None:
    s = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert s == json.loads(json.dumps(res.summary))
    assert res.exit_code == 3 and s["verdict"] == "INVALID" and not s["interrupted"]
    groups = _by_id(s, "groups")
    runs = _by_id(s, "runs")
    # the segfault: INVALID with its reason, the rest of the suite finished
    seg = groups["segfault"]
    assert seg["verdict"] == "INVALID"
    assert "crashed" in seg["reasons"][0]
    assert runs["segfault#1"]["crash"] is not None
    # the hangs (they never end on their own): stopped at their timeouts, INVALID, each with
    # its run directory and a summary, whether it was stopped mid-way (finalized, or
    # recovered) or before its first tick (written by the suite)
    for rid, timeout in (("hang#1", 6), ("stuck#1", 2)):
        hang = runs[rid]
        assert hang["verdict"] == "INVALID" and hang["timed_out"]
        assert hang["reasons"][0] == (f"timed out after {timeout} s of wall-clock time and was "
                                      "stopped")
        assert hang["wall_s"] >= timeout
        assert hang["run_dir"] == f"runs/{rid[:-2]}/nominal/r1"
        own = read_summary(out / hang["run_dir"])  # the run's own summary says the same
        assert own["verdict"] == "INVALID" and hang["reasons"][0] in own["reasons"][0]
    assert "before its first tick" in runs["stuck#1"]["reasons"][1]
    stuck = read_summary(out / runs["stuck#1"]["run_dir"])
    assert stuck["verdict"] == "INVALID" and stuck["topics"] == {}
    assert "timed out after 2 s" in stuck["reasons"][0]
    # output depending on the process id: flaky, with the topics and the first divergence
    pid = groups["pid"]
    assert pid["verdict"] == "FLAKY" and pid["flaky"]
    detail = pid["flaky_detail"]
    assert "/cmd_vel" in detail["differing_topics"]
    assert detail["first_divergence"].startswith("/cmd_vel message #0")
    assert detail["digests"][0] != detail["digests"][1]
    # the sweep: three points, named by their values, in order, each its own configuration
    sweep = s["sweeps"][0]
    assert sweep["params"] == [SPEED]
    assert sweep["groups"] == [f"speeds[speed={v}]" for v in ("1", "1.5", "2")]
    dist = [groups[g]["stats"]["control.distance_travelled"]["mean"] for g in sweep["groups"]]
    assert dist[0] < dist[1] < dist[2]  # faster drives further in the same 2 s
    for g in sweep["groups"]:
        assert groups[g]["params"] == {SPEED: float(g.split("=")[1].rstrip("]"))}
        r = runs[g + "#1"]
        assert (out / r["report"]).is_file()
        # no baseline was blessed for a sweep point: said plainly, never a PASS
        assert r["verdict"] == "FAIL" and any("@" in x for x in r["reasons"])
        # a MuJoCo run's worker: its own peak memory, measured (not the suite's)
        assert 80 < r["peak_rss_mb"] < 4000
    # CI outputs
    junit = ET.parse(out / "junit.xml").getroot()
    cases = junit.findall(".//testcase")
    assert len(cases) == len(s["runs"]) == 1 + 1 + 1 + 2 + 3
    by_name = {c.get("name"): c for c in cases}
    assert by_name["segfault#1"].find("error").get("type") == "crash"
    assert by_name["hang#1"].find("error").get("type") == "timeout"
    assert by_name["stuck#1"].find("error").get("type") == "timeout"
    assert all(by_name[f"pid#{k}"].find("failure").get("type") == "flaky" for k in (1, 2))
    assert junit.get("errors") == "3"
    assert (out / "index.html").is_file()
    # the pull-request summary: from the same result, the same exit code and rows
    md = api.write_summary_md(res, out / "pr.md").read_text(encoding="utf-8")
    assert md.startswith("## 💥 srr suite `misbehaving`: **INVALID** (exit code 3)\n")
    broken = md.split("### Crashed, timed-out and invalid runs\n\n", 1)[1].split("\n\n")[0]
    assert [line.split(" | ")[:2] for line in broken.splitlines()[2:]] == [
        ["| `segfault#1`", "crashed"], ["| `hang#1`", "timed out"], ["| `stuck#1`", "timed out"]]
    flaky = md.split("### Flaky groups\n\n", 1)[1].split("\n\n")[0].splitlines()[2:]
    assert len(flaky) == 1 and flaky[0].startswith("| `pid` | ") and "`/cmd_vel`" in flaky[0]
    assert "[#1](runs/pid/nominal/r1/report.html)" in flaky[0]


def test_local_suite_survives_crash_timeout_and_catches_flaky(suite_file: Path,
                                                             tmp_path: Path) -> None:
    out = tmp_path / "out"
    # in hosts (what `srr suite` does) when this process may fork, else fresh processes
    res = api.suite([suite_file], executor="local", jobs=2, out=out, fork=True)
    _check_misbehaving(res, out)
    assert res.summary["executor"] == "local" and res.summary["jobs"] == 2
    logs = {r["id"]: r["log"] for r in res.summary["runs"]}
    assert all(logs.values()) and all((out / v).is_file() for v in logs.values())


@pytest.mark.ray
def test_ray_suite_on_a_real_local_cluster(suite_file: Path, tmp_path: Path) -> None:
    pytest.importorskip("ray")
    out = tmp_path / "out"
    res = api.suite([suite_file], executor="ray", jobs=2, out=out)
    _check_misbehaving(res, out)
    assert res.summary["executor"] == "ray"
    assert "Ray worker died" in _by_id(res.summary, "runs")["segfault#1"]["crash"]


@pytest.mark.ray
def test_a_ray_worker_runs_run_after_run_as_fresh_processes_would(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """One Ray worker slot: three repeats of a rendering scene run in one worker process, with
    the one OpenGL context it made in the first, and record the bag a fresh process records;
    a plug-in whose behaviour depends on its module's state drives the same in each run. A run
    that leaves a thread running is the worker's last: the run after it (the cheapest, so it
    starts last) gets a fresh process."""
    pytest.importorskip("ray")
    monkeypatch.chdir(ROOT)
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"""
scenarios:
  - {{path: {CROSSING}, name: crossing, repeat: 3, set: {{duration: 1.0}}}}
  - {{path: {FORKLIFT}, name: counter, repeat: 3,
     set: {{duration: 1, {PLUGIN}: "tests.suite.plugins:ModuleCounter"}}}}
  - {{path: {FORKLIFT}, name: leaves, set: {{duration: 0.5,
     {PLUGIN}: "tests.suite.plugins:LeavesAThread"}}}}
  - {{path: {FORKLIFT}, name: after, set: {{duration: 0.3}}}}
""", encoding="utf-8")
    res = api.suite([suite], executor="ray", jobs=1, out=tmp_path / "ray")
    assert res.summary["verdict"] != "INVALID", res.summary
    runs = {r["id"]: r for r in res.summary["runs"]}
    after = runs.pop("after#1")
    assert len({r["timings"]["pid"] for r in runs.values()}) == 1  # one worker, seven runs
    assert after["timings"]["pid"] != runs["leaves#1"]["timings"]["pid"]  # a fresh process
    assert after["verdict"] != "INVALID" and after["digest"] is not None
    crossing = [runs[f"crossing#{k}"] for k in (1, 2, 3)]
    assert [r["timings"]["gl_contexts"] for r in crossing] == [1, 1, 1]
    assert all(80 < r["peak_rss_mb"] < 4000 for r in runs.values())
    assert len({runs[f"counter#{k}"]["digest"] for k in (1, 2, 3)}) == 1
    alone = tmp_path / "alone.yaml"  # the crossing's run in a fresh process, nothing else
    alone.write_text(f"scenarios:\n  - {{path: {CROSSING}, name: crossing, set: "
                     "{duration: 1.0}}\n", encoding="utf-8")
    (fresh,) = api.suite([alone], executor="local", jobs=1, out=tmp_path / "fresh",
                         fork=False).summary["runs"]
    assert fresh["id"] == "crossing#1" and fresh["digest"] is not None
    sha = {r["id"]: hashlib.sha256((tmp_path / "ray" / r["run_dir"] / "bag" / "bag.mcap")
                                   .read_bytes()).hexdigest() for r in crossing}
    reference = hashlib.sha256((tmp_path / "fresh" / fresh["run_dir"] / "bag" / "bag.mcap")
                               .read_bytes()).hexdigest()
    assert set(sha.values()) == {reference}


#: A Ray worker's runs, called as its task calls them (no cluster needed for this part): the
#: GPU Ray names for each run (MUJOCO_EGL_DEVICE_ID), then whether the run stayed in this
#: process. An OpenGL context made here is stood in for by the renderer's count.
GPUS = """
import json, os, sys
from harness.suite.runner import plan_suite
from harness.suite import ray_executor
import harness.sim.render as render
(spec,) = plan_suite([sys.argv[1]]).runs
here = []
for k, (device, contexts) in enumerate([(None, 0), ("3", 0), ("4", 1)]):
    os.environ.pop("MUJOCO_EGL_DEVICE_ID", None)
    if device is not None:
        os.environ["MUJOCO_EGL_DEVICE_ID"] = device
    render._CONTEXTS_MADE = contexts
    res = ray_executor._run_here(spec.job(), os.path.join(sys.argv[2], str(k)), None)
    here.append((res["pid"] == os.getpid(), res["exit_code"]))
print(json.dumps(here))
"""


def test_a_ray_worker_runs_elsewhere_a_run_given_another_gpu_than_its_context(
        tmp_path: Path) -> None:
    """A worker that has made no OpenGL context takes whatever GPU Ray names next; once it has
    one, a run on another GPU gets a fresh process (its context would be on the wrong GPU)."""
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"scenarios: [{{path: {FORKLIFT}, set: {{duration: 0.5}}}}]\n",
                     encoding="utf-8")
    out = subprocess.run([sys.executable, "-c", GPUS, str(suite), str(tmp_path / "out")],
                         cwd=ROOT, capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0, out.stderr
    here = json.loads(out.stdout.strip().splitlines()[-1])
    assert [h for h, _ in here] == [True, True, False]
    assert all(code in (0, 1) for _, code in here), here  # each ran to its verdict


def test_runs_stopped_before_their_first_tick_get_an_invalid_run_directory(
        suite_file: Path, tmp_path: Path) -> None:
    """A run that times out before it has written anything, and one whose worker is killed
    then, still get their run directories: the resolved scenario, an INVALID summary saying
    what happened, junit.xml. Both plug-ins block or die in their set-up, whatever the load."""
    suite_file.write_text(f"""
scenarios:
  - path: {FORKLIFT}
    name: stuck
    timeout: 1
    set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:BlockedAtStart"}}
  - path: {FORKLIFT}
    name: killed
    set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:KilledAtStart"}}
""", encoding="utf-8")
    out = tmp_path / "out"
    res = api.suite([suite_file], executor="local", jobs=2, out=out, fork=True)
    runs = _by_id(res.summary, "runs")
    stuck, killed = runs["stuck#1"], runs["killed#1"]
    assert stuck["timed_out"] and stuck["reasons"][0].startswith("timed out after 1 s")
    assert killed["crash"] == "killed by signal SIGKILL (the out-of-memory killer, or kill -9)"
    for run, what in ((stuck, "timed out after 1 s"), (killed, "killed by signal SIGKILL")):
        assert run["verdict"] == "INVALID" and run["digest"] is None
        assert "before its first tick" in run["reasons"][1]
        assert run["run_dir"] == f"runs/{run['group']}/nominal/r1"
        summary = json.loads((out / run["run_dir"] / "summary.json").read_text())
        assert summary["verdict"] == "INVALID" and summary["exit_code"] == 3
        assert what in summary["reasons"][0] and "before its first tick" in summary["reasons"][0]
        assert summary["topics"] == {} and summary["ticks"] == 0
        assert not summary["health"][0]["ok"]
        assert api.load(out / run["run_dir"] / "scenario.yaml").duration == 2
        assert (out / run["run_dir"] / "junit.xml").is_file()
        assert not (out / run["run_dir"] / "incomplete.json").exists()
        from harness.summary import read_summary

        assert read_summary(out / run["run_dir"]) == summary  # every reader takes it


def test_repeats_that_timed_out_are_invalid_not_flaky(suite_file: Path,
                                                      tmp_path: Path) -> None:
    """Two repeats stopped at their timeouts recorded different things (each drove at its own
    speed until it stalled): where a run is stopped says nothing of whether the simulation
    repeats, so the group is INVALID for the timeouts, not called flaky."""
    suite_file.write_text(f"""
scenarios:
  - path: {FORKLIFT}
    name: stalls
    repeat: 2
    timeout: 5
    set: {{duration: 3, {PLUGIN}: "tests.suite.plugins:PidDependentStaller"}}
""", encoding="utf-8")
    out = tmp_path / "out"
    res = api.suite([suite_file], executor="local", jobs=2, out=out, fork=True)
    runs = res.summary["runs"]
    assert [r["timed_out"] for r in runs] == [True, True]
    digests = [r["digest"] for r in runs]
    assert None not in digests and digests[0] != digests[1]  # they did record other bytes
    (group,) = res.summary["groups"]
    assert group["verdict"] == "INVALID" and not group["flaky"]
    assert group["flaky_detail"] is None
    assert group["reasons"] == ["#1: timed out after 5 s of wall-clock time and was stopped",
                                "#2: timed out after 5 s of wall-clock time and was stopped"]
    junit = ET.parse(out / "junit.xml").getroot()
    assert [c.find("error").get("type") for c in junit.iter("testcase")] == ["timeout"] * 2
    md = api.write_summary_md(res, tmp_path / "pr.md").read_text(encoding="utf-8")
    assert "### Flaky groups" not in md and "flaky" not in md


def test_a_reason_with_characters_that_are_not_printable_is_escaped_everywhere(
        suite_file: Path, tmp_path: Path) -> None:
    """A plug-in's exception message in ANSI colours, with a NUL, becomes the run's reason
    with those characters written as escapes (``\\x1b``, ``\\x00``), the rest as it was:
    the run's summary.json reads back, the suite's and the run's junit.xml are XML that a
    CI's reader parses, and the suite page and the PR summary carry no escape character."""
    suite_file.write_text(f"""
scenarios:
  - path: {FORKLIFT}
    name: colour
    set: {{duration: 1, {PLUGIN}: "tests.suite.plugins:RaisesInColour"}}
""", encoding="utf-8")
    out = tmp_path / "out"
    res = api.suite([suite_file], executor="local", jobs=1, out=out, fork=True)
    (run,) = res.summary["runs"]
    said = "\\x1b[31mmotor fault\\x1b[0m <&> \\x00"
    assert run["verdict"] == "INVALID" and said in run["reasons"][0], run["reasons"]
    own = json.loads((out / run["run_dir"] / "summary.json").read_text(encoding="utf-8"))
    assert any(said in r for r in own["reasons"]), own["reasons"]
    for junit in (out / "junit.xml", out / run["run_dir"] / "junit.xml"):
        root = ET.parse(junit).getroot()
        messages = [e.get("message", "") for e in root.iter() if e.tag in ("failure", "error")]
        assert any(said in m for m in messages), messages
    md = api.write_summary_md(res, tmp_path / "pr.md").read_text(encoding="utf-8")
    page = (out / "index.html").read_text(encoding="utf-8")
    assert "motor fault" in md and "motor fault" in page
    assert not any(c in text for c in "\x1b\x00" for text in (md, page))


def test_cli_ctrl_c_keeps_finished_runs(tmp_path: Path) -> None:
    """Ctrl-C once the quick run has finished and while the slow one is stuck mid-way (it
    cannot finish on its own): the quick run is kept as it was, the slow one is stopped and
    finalized, the suite writes its outputs and exits 130."""
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"""
scenarios:
  - path: {FORKLIFT}
    name: quick
    set: {{duration: 1}}
  - path: {FORKLIFT}
    name: slow
    set: {{duration: 3, {PLUGIN}: "tests.suite.plugins:Staller"}}
""", encoding="utf-8")
    out = tmp_path / "out"
    stalled = tmp_path / "stalled"  # the slow run creates it when it gets stuck
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1",
           STALLED_FILE: str(stalled)}
    proc = subprocess.Popen([sys.executable, "-m", "harness.cli", "suite", str(suite), "-j",
                             "2", "--out", str(out)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.stdout is not None
    seen = []
    for line in proc.stdout:  # not a terminal: one line per run as the suite judges it
        seen.append(line)
        if " quick#1: " in line:
            break
    assert " quick#1: MISMATCH" in seen[-1], "".join(seen)
    while not stalled.exists():  # the slow run is mid-way, and stays there
        assert proc.poll() is None, "".join(seen) + proc.communicate()[0]
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    text = "".join(seen) + proc.communicate(timeout=300)[0]
    assert proc.returncode == 130, text
    s = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert s["interrupted"] and s["verdict"] == "INTERRUPTED" and s["exit_code"] == 130
    runs = _by_id(s, "runs")
    assert runs["quick#1"]["verdict"] == "MISMATCH"  # finished before Ctrl-C: kept as it was
    assert runs["slow#1"]["verdict"] == "INTERRUPTED"  # stopped cleanly: bag and summary valid
    slow = json.loads((out / runs["slow#1"]["run_dir"] / "summary.json").read_text())
    assert slow["interrupted"] and slow["topics"]["/clock"]["count"] > 0
    assert slow["simulated_s"] >= 0.5  # where it got stuck
    assert "Traceback" not in text


def test_cli_bad_suite_is_one_line_exit_2(tmp_path: Path) -> None:
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"scenarios: [{{path: {FORKLIFT}, sweep: {{seed: []}}}}]\n",
                     encoding="utf-8")
    from harness.cli import main

    out = tmp_path / "out"
    assert main(["suite", str(suite), "--out", str(out)]) == 2
    assert not out.exists()  # nothing half-written


def test_cli_ray_executor_without_ray_is_one_line_exit_2(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
        ) -> None:
    """``--executor ray`` where Ray is not installed: the install hint on one line, exit 2,
    before anything runs or is written (it was a traceback once the suite had been checked)."""
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` fails as if not installed
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"scenarios: [{{path: {FORKLIFT}, set: {{duration: 0.5}}}}]\n",
                     encoding="utf-8")
    from harness.cli import main

    out = tmp_path / "out"
    assert main(["suite", str(suite), "--executor", "ray", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("srr suite: --executor ray: Ray is not installed "
                       "(pip install 'srr[ray]')"), err
    assert "Traceback" not in "\n".join(err)
    assert not out.exists()  # nothing half-written


def test_bundled_scenarios_are_not_flaky(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Each repeat in its own process: digests must agree across processes."""
    monkeypatch.chdir(ROOT)
    names = ["forklift_warehouse", "two_forklifts", "dock_worker_crossing", "turtlebot3_room"]
    suite = tmp_path / "suite.yaml"
    suite.write_text("scenarios:\n" + "".join(
        f"  - {{path: {ROOT / 'scenarios' / n}.yaml, repeat: 2, set: {{duration: 1.5}}}}\n"
        for n in names), encoding="utf-8")
    res = api.suite([suite], executor="local", jobs=2, out=tmp_path / "out")
    groups = _by_id(res.summary, "groups")
    assert sorted(groups) == sorted(names)
    for g in groups.values():
        assert not g["flaky"], g["flaky_detail"]
        # 1.5 s is not the baselines' configuration; turtlebot3_room has no scoring block
        assert g["verdict"] == ("UNSCORED" if g["id"] == "turtlebot3_room" else "MISMATCH")
        assert all(st["n"] in (0, 2) for st in g["stats"].values())
        assert all(st["std"] in (None, 0.0) for st in g["stats"].values())


def _in_use(port: int) -> bool:
    """Whether another socket holds ``port`` on the loopback interface now."""
    import errno
    import socket

    with socket.socket() as sock:
        try:
            sock.bind(("127.0.0.1", port))
        except OSError as err:
            return err.errno == errno.EADDRINUSE
    return False


@pytest.mark.ray
def test_ray_suite_joins_an_existing_cluster(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """``--address``: a cluster started beforehand with ``ray start``; the project folder
    travels as the job's working_dir and the cluster keeps running afterwards. `srr suite`
    runs as a command of its own: Ray keeps the authentication mode a process first saw, so a
    driver in this process would leave later tests' local clusters unreachable."""
    pytest.importorskip("ray")
    import socket

    monkeypatch.chdir(ROOT)
    ray_bin = str(Path(sys.executable).parent / "ray")
    # one machine, loopback only: no token to share between `ray start` and the driver
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0", "RAY_AUTH_MODE": "disabled",
           "PYTHONPATH": str(ROOT)}
    for _ in range(5):
        # `ray start` takes a port number, not 0: one that was free a moment ago may be taken
        # by another process before Ray binds it; then `ray start` fails, and another is tried
        with socket.socket() as sock:
            sock.bind(("127.0.0.1", 0))
            port = sock.getsockname()[1]
        started = subprocess.run([ray_bin, "start", "--head", f"--port={port}", "--num-cpus=1",
                                  "--include-dashboard=false", "--node-ip-address=127.0.0.1"],
                                 capture_output=True, text=True, env=env, timeout=120)
        if started.returncode == 0 or not _in_use(port):
            break
    assert started.returncode == 0, started.stdout + started.stderr
    try:
        suite = tmp_path / "suite.yaml"
        suite.write_text(f"scenarios: [{{path: {FORKLIFT}, "
                         f"set: {{duration: 1}}}}]\n", encoding="utf-8")
        done = subprocess.run([sys.executable, "-m", "harness.cli", "suite", str(suite),
                               "--executor", "ray", "--address", f"127.0.0.1:{port}",
                               "--out", str(tmp_path / "out"), "-q"],
                              capture_output=True, text=True, env=env, timeout=300)
        summary = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
        run = summary["runs"][0]
        assert summary["address"] == f"127.0.0.1:{port}", done.stderr
        assert run["verdict"] == "MISMATCH", run["reasons"]
        assert (tmp_path / "out" / run["report"]).is_file()
        status = subprocess.run([ray_bin, "status", "--address", f"127.0.0.1:{port}"],
                                capture_output=True, text=True, env=env, timeout=120)
        assert status.returncode == 0, status.stdout + status.stderr  # the cluster stays
    finally:
        subprocess.run([ray_bin, "stop", "--force"], capture_output=True, env=env,
                       timeout=120)


def test_forked_and_fresh_workers_record_the_same_bytes(tmp_path: Path) -> None:
    """`srr suite` forks its workers from its own process (it never renders); a fresh
    interpreter records the same bytes, a rendering scene with its perception included."""
    from harness.suite.local import LocalExecutor
    from harness.suite.runner import plan_suite, run_suite

    suite = tmp_path / "suite.yaml"
    scenario = ROOT / "scenarios" / "dock_worker_crossing.yaml"
    suite.write_text(f"scenarios:\n  - {{path: {scenario}, set: {{duration: 1.5}}}}\n",
                     encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    forked = tmp_path / "forked"
    done = subprocess.run([sys.executable, "-m", "harness.cli", "suite", str(suite), "-j", "1",
                           "--out", str(forked), "-q"], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 1, done.stdout + done.stderr  # 1.5 s: not the baseline's config
    fresh = tmp_path / "fresh"
    run_suite(plan_suite([suite]), LocalExecutor(1, fork=False), out=fresh)
    digests = []
    for out in (forked, fresh):
        (run,) = json.loads((out / "summary.json").read_text(encoding="utf-8"))["runs"]
        summary = json.loads((out / run["run_dir"] / "summary.json").read_text())
        assert summary["topics"]["/dock_cam_left_depth"]["count"] == 8
        assert run["peak_rss_mb"] > 80  # the worker's own, measured either way
        digests.append(summary["digest"])
    assert digests[0] == digests[1]


def test_a_process_that_rendered_does_not_fork(tmp_path: Path) -> None:
    """Forking after OpenGL was initialized here would leave the child with the driver's
    locks and no threads: such a process starts fresh interpreters instead."""
    from harness.sim import World
    from harness.sim.render import Renderer
    from harness.suite.local import fork_safe

    sc = api.load(ROOT / "scenarios" / "camera_publishing.yaml")
    world = World.build(sc)
    with Renderer(world.model, world.data) as r:
        r.render(0, 8, 8)
    assert not fork_safe()
