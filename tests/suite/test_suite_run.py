"""Real suites end to end: worker processes (local) and a real local Ray cluster, with a
worker that segfaults, one that hangs past its timeout, one whose output depends on its
process id (flaky), and a sweep of three values; Ctrl-C; the bundled scenarios over repeats."""

from __future__ import annotations

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

ROOT = Path(__file__).resolve().parents[2]
FORKLIFT = ROOT / "scenarios" / "forklift_warehouse.yaml"
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
    timeout: 10  # room for a slow worker start on a loaded 2-core machine
    set: {{duration: 3, {PLUGIN}: "tests.suite.plugins:Sleeper"}}
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
    # the hang: stopped at its timeout, INVALID, its partial run directory kept
    hang = runs["hang#1"]
    assert hang["verdict"] == "INVALID" and hang["timed_out"]
    assert "timed out after 10 s" in hang["reasons"][0]
    assert hang["wall_s"] < 10 + 12  # stopped: SIGTERM, then SIGKILL after the grace period
    assert hang["run_dir"] and (out / hang["run_dir"] / "summary.json").is_file()
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
    assert len(cases) == len(s["runs"]) == 1 + 1 + 2 + 3
    by_name = {c.get("name"): c for c in cases}
    assert by_name["segfault#1"].find("error").get("type") == "crash"
    assert by_name["hang#1"].find("error").get("type") == "timeout"
    assert all(by_name[f"pid#{k}"].find("failure").get("type") == "flaky" for k in (1, 2))
    assert junit.get("errors") == "2"
    assert (out / "index.html").is_file()


def test_local_suite_survives_crash_timeout_and_catches_flaky(suite_file: Path,
                                                             tmp_path: Path) -> None:
    out = tmp_path / "out"
    res = api.suite([suite_file], executor="local", jobs=2, out=out)
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


def test_cli_ctrl_c_keeps_finished_runs(tmp_path: Path) -> None:
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"""
scenarios:
  - path: {FORKLIFT}
    name: quick
    set: {{duration: 1}}
  - path: {FORKLIFT}
    name: slow
    set: {{duration: 3, {PLUGIN}: "tests.suite.plugins:Sleeper"}}
""", encoding="utf-8")
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "harness.cli", "suite", str(suite), "-j",
                             "2", "--out", str(out), "-q"], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 60
    slow_bag = out / "runs" / "slow" / "nominal" / "r1" / "bag"
    while not ((out / "runs" / "quick" / "nominal" / "r1" / "summary.json").is_file()
               and any(slow_bag.glob("*.mcap"))):  # the quick run done, the slow one recording
        assert time.monotonic() < deadline and proc.poll() is None, proc.communicate()[0]
        time.sleep(0.1)
    time.sleep(1.0)  # the slow run is mid-way (50 ms a tick: about 20 of its 180 ticks)
    proc.send_signal(signal.SIGINT)
    text = proc.communicate(timeout=60)[0]
    assert proc.returncode == 130, text
    s = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert s["interrupted"] and s["verdict"] == "INTERRUPTED" and s["exit_code"] == 130
    runs = _by_id(s, "runs")
    assert runs["quick#1"]["verdict"] == "MISMATCH"  # finished before Ctrl-C: kept as it was
    assert runs["slow#1"]["verdict"] == "INTERRUPTED"  # stopped cleanly: bag and summary valid
    slow = json.loads((out / runs["slow#1"]["run_dir"] / "summary.json").read_text())
    assert slow["interrupted"] and slow["topics"]["/clock"]["count"] > 0
    assert "Traceback" not in text


def test_cli_bad_suite_is_one_line_exit_2(tmp_path: Path) -> None:
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"scenarios: [{{path: {FORKLIFT}, sweep: {{seed: []}}}}]\n",
                     encoding="utf-8")
    from harness.cli import main

    out = tmp_path / "out"
    assert main(["suite", str(suite), "--out", str(out)]) == 2
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


@pytest.mark.ray
def test_ray_suite_joins_an_existing_cluster(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """``--address``: a cluster started beforehand with ``ray start``; the project folder
    travels as the job's working_dir and the cluster keeps running afterwards."""
    pytest.importorskip("ray")
    import socket

    monkeypatch.chdir(ROOT)
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    ray_bin = str(Path(sys.executable).parent / "ray")
    # one machine, loopback only: no token to share between `ray start` and this driver
    monkeypatch.setenv("RAY_AUTH_MODE", "disabled")
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0"}
    subprocess.run([ray_bin, "start", "--head", f"--port={port}", "--num-cpus=1",
                    "--include-dashboard=false", "--node-ip-address=127.0.0.1"], check=True,
                   capture_output=True, env=env, timeout=120)
    try:
        suite = tmp_path / "suite.yaml"
        suite.write_text(f"scenarios: [{{path: {FORKLIFT}, "
                         f"set: {{duration: 1}}}}]\n", encoding="utf-8")
        res = api.suite([suite], executor="ray", address=f"127.0.0.1:{port}",
                        out=tmp_path / "out")
        run = res.summary["runs"][0]
        assert res.summary["address"] == f"127.0.0.1:{port}"
        assert run["verdict"] == "MISMATCH", run["reasons"]
        assert (tmp_path / "out" / run["report"]).is_file()
        import ray

        assert not ray.is_initialized()  # srr left, the cluster stays
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
