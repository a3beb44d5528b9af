"""The local executor's hosts: one long-lived process per slot, forked from the suite's, that
runs its runs one after another. Real suites in a process of their own (this one may have
rendered or have threads: it would not fork): one OpenGL context per host and the bytes a
fresh process records, a crash or an ``os._exit`` that costs its run only, each run's own
log and peak memory, plug-in module state that does not reach the next run, Ctrl-C."""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from harness.suite.timeline import STEPS
from tests.suite.plugins import FROZEN_FILE, HOG_MB, PLANNER_PID, STALLED_FILE

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
FORKLIFT = ROOT / "scenarios" / "forklift_warehouse.yaml"
CROSSING = ROOT / "scenarios" / "dock_worker_crossing.yaml"
PLUGIN = "systems_under_test.route_follower.plugin"

#: Runs a suite file on a forked local executor (hosts), in a process of its own.
SCRIPT = f"""
import os, sys
from pathlib import Path
os.environ["{PLANNER_PID}"] = str(os.getpid())
from harness.suite.local import LocalExecutor
from harness.suite.runner import plan_suite, run_suite
plan = plan_suite([sys.argv[1]])
run_suite(plan, LocalExecutor(int(sys.argv[3]), fork=True), out=Path(sys.argv[2]))
"""


def _suite(tmp_path: Path, text: str, jobs: int = 1,
           env: dict[str, str] | None = None) -> subprocess.Popen[str]:
    suite = tmp_path / "suite.yaml"
    suite.write_text(text, encoding="utf-8")
    return subprocess.Popen([sys.executable, "-c", SCRIPT, str(suite), str(tmp_path / "out"),
                             str(jobs)], cwd=ROOT, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT), **(env or {})},
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)


def _finished(tmp_path: Path, text: str, jobs: int = 1) -> dict[str, dict[str, Any]]:
    proc = _suite(tmp_path, text, jobs)
    log = proc.communicate(timeout=600)[0]
    assert proc.returncode == 0, log
    return _runs(tmp_path / "out")


def _runs(out: Path) -> dict[str, dict[str, Any]]:
    s = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return {r["id"]: r for r in s["runs"]}


def _bag_sha256(out: Path, run: dict[str, Any]) -> str:
    return hashlib.sha256((out / run["run_dir"] / "bag" / "bag.mcap").read_bytes()).hexdigest()


def test_a_host_makes_one_opengl_context_and_records_what_a_fresh_process_records(
        tmp_path: Path) -> None:
    """Three repeats of a rendering scene on one slot: one host runs them all, one after
    another, with the one OpenGL context it made before the first (none made in a run);
    each run's bag is byte for byte the bag of the same run in a fresh interpreter."""
    from harness.suite.local import LocalExecutor
    from harness.suite.runner import plan_suite, run_suite

    text = f"scenarios:\n  - {{path: {CROSSING}, repeat: 3, set: {{duration: 1.0}}}}\n"
    runs = [r for _, r in sorted(_finished(tmp_path, text).items())]
    assert len({r["timings"]["pid"] for r in runs}) == 1  # one host
    # the host made one context, before the first run (its warm-up's), and no run made one;
    # (a run's gl_context_s, the time it took to make the kept one current, is not 0 on a
    # loaded machine: counts, not times, say what was made)
    assert [r["timings"]["gl_contexts"] for r in runs] == [1, 1, 1]
    assert runs[0]["timings"]["warm_gl_s"] > 0  # made before the first run, counted there
    for before, after in itertools.pairwise(runs):
        assert after["timings"]["started_s"] >= before["timings"]["finished_s"]
    for run in runs:
        t = run["timings"]
        assert set(t["steps"]) == {name for name, _, _ in STEPS}
        assert min(t["steps"].values()) >= 0 and t["finished_s"] > t["started_s"]
        # this run's CPU, not the host's since it began: a render thread and the recorder's
        # keep it above 0, and no more CPUs than the machine has
        assert 0 < t["cpus"] <= (os.cpu_count() or 1) + 0.1, t
    assert not list((tmp_path / "out" / "logs").glob("*.clock.json"))  # taken once read
    (tmp_path / "suite.yaml").write_text(text.replace("repeat: 3", "repeat: 1"))
    fresh = tmp_path / "fresh"
    run_suite(plan_suite([tmp_path / "suite.yaml"]), LocalExecutor(1, fork=False), out=fresh)
    (plain,) = _runs(fresh).values()
    assert plain["timings"]["pid"] not in {r["timings"]["pid"] for r in runs}
    assert plain["timings"]["cpu_s"] > 0  # a fresh process times its run's CPU too
    reference = _bag_sha256(fresh, plain)
    assert [_bag_sha256(tmp_path / "out", r) for r in runs] == [reference] * 3
    assert {r["digest"] for r in runs} == {plain["digest"]} and plain["digest"] is not None


def test_a_crash_or_an_exit_in_a_host_costs_that_run_only(tmp_path: Path) -> None:
    """On one slot: a run, one that segfaults in the same host, one in a fresh host that
    ends its process with os._exit, then one more in a fresh host again: the two are
    INVALID with what happened, the others finish as usual; each log holds its own run's
    output only."""
    text = f"""
scenarios:
  - {{path: {FORKLIFT}, name: first, set: {{duration: 2}}}}
  - {{path: {FORKLIFT}, name: segfault,
     set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:Segfaulter"}}}}
  - {{path: {FORKLIFT}, name: exits, set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:Exits"}}}}
  - {{path: {FORKLIFT}, name: last, set: {{duration: 2}}}}
"""
    runs = _finished(tmp_path, text)
    first, seg, exits, last = (runs[f"{n}#1"] for n in ("first", "segfault", "exits", "last"))
    for ok in (first, last):
        assert ok["verdict"] != "INVALID" and ok["exit_code"] in (0, 1), ok["reasons"]
    assert seg["verdict"] == "INVALID"
    assert seg["crash"] == "killed by signal SIGSEGV (a segmentation fault)"
    assert exits["verdict"] == "INVALID" and exits["crash"] is None
    assert "the worker exited with status 3" in " ".join(exits["reasons"])
    pids = [r["timings"]["pid"] for r in (first, seg, exits, last)]
    assert pids[1] is None and pids[2] is None  # ended mid-run: no clock left
    assert pids[0] != pids[3]  # the last run's host is not the first's: a crash took that
    out = tmp_path / "out"
    texts = {rid: (out / r["log"]).read_text(encoding="utf-8", errors="replace")
             for rid, r in runs.items()}
    assert "exits: leaving the process" in texts["exits#1"]
    assert not any("exits:" in t for rid, t in texts.items() if rid != "exits#1")


def test_each_run_in_a_host_has_its_own_peak_memory_and_log(tmp_path: Path) -> None:
    """One host: a run that holds HOG_MB MiB, then a plain one. The second run's peak is its
    own, not the host's (which includes the first's), and each log has its own lines."""
    text = f"""
scenarios:
  - {{path: {FORKLIFT}, name: hog, set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:Hog"}}}}
  - {{path: {FORKLIFT}, name: plain, set: {{duration: 2}}}}
"""
    runs = _finished(tmp_path, text)
    hog, plain = runs["hog#1"], runs["plain#1"]
    assert hog["timings"]["pid"] == plain["timings"]["pid"]  # one host
    assert hog["verdict"] != "INVALID" and plain["verdict"] != "INVALID"
    assert plain["peak_rss_mb"] > 80  # a MuJoCo run's, measured
    assert hog["peak_rss_mb"] - plain["peak_rss_mb"] > HOG_MB * 0.8
    out = tmp_path / "out"
    hog_log = (out / hog["log"]).read_text(encoding="utf-8")
    assert "hog: holding memory" in hog_log and "hog: on stderr too" in hog_log
    assert "hog:" not in (out / plain["log"]).read_text(encoding="utf-8")


def test_a_host_s_collections_skip_what_it_inherited_from_the_suite(tmp_path: Path) -> None:
    """The suite's process holds srr, NumPy, pandas and SciPy (over 100,000 objects the
    collector tracks) when it forks a host: frozen, the host's collections skip them. Walked
    again by every collection in every run, they cost about 8 % of a run's CPU."""
    frozen = tmp_path / "frozen.txt"
    text = f"""
scenarios:
  - {{path: {FORKLIFT}, name: counts,
     set: {{duration: 1, {PLUGIN}: "tests.suite.plugins:CountsFrozen"}}}}
"""
    proc = _suite(tmp_path, text, env={FROZEN_FILE: str(frozen)})
    log = proc.communicate(timeout=600)[0]
    assert proc.returncode == 0, log
    (run,) = _runs(tmp_path / "out").values()
    assert run["verdict"] != "INVALID", log
    assert int(frozen.read_text()) > 50_000


def test_a_plugin_module_starts_afresh_in_every_run_of_a_host(tmp_path: Path) -> None:
    """A plug-in whose behaviour depends on its module's state (how many set-ups it has
    seen): three repeats in one host drive exactly as three fresh processes would, so the
    group is not flaky (the suite's own checks set the plug-in up first, too)."""
    text = f"""
scenarios:
  - {{path: {FORKLIFT}, name: counter, repeat: 3,
     set: {{duration: 1, {PLUGIN}: "tests.suite.plugins:ModuleCounter"}}}}
"""
    runs = _finished(tmp_path, text)
    assert len({r["timings"]["pid"] for r in runs.values()}) == 1  # one host
    assert len({r["digest"] for r in runs.values()}) == 1, runs
    s = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    assert not s["groups"][0]["flaky"]


def test_unseeded_randomness_differs_between_runs_of_a_host(tmp_path: Path) -> None:
    """A plug-in drawing from the global generators unseeded: each run of one host draws
    other numbers, as a fresh process would, so the repeats differ and the group is flaky
    (it once drew the same numbers in every run of a host, and the suite called it PASS)."""
    text = f"""
scenarios:
  - {{path: {FORKLIFT}, name: unseeded, repeat: 3,
     set: {{duration: 1, {PLUGIN}: "tests.suite.plugins:Unseeded"}}}}
"""
    proc = _suite(tmp_path, text)
    log = proc.communicate(timeout=600)[0]
    runs = _runs(tmp_path / "out")
    assert len({r["timings"]["pid"] for r in runs.values()}) == 1, log  # one host
    assert len({r["digest"] for r in runs.values()}) == 3, runs
    s = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    assert s["groups"][0]["flaky"] and s["groups"][0]["verdict"] == "FLAKY"


def test_a_mujoco_callback_set_by_a_run_does_not_reach_the_next(tmp_path: Path) -> None:
    """A plug-in sets MuJoCo's process-wide control callback and leaves it set; the next run
    in the same host records what a fresh process records."""
    from harness.suite.local import LocalExecutor
    from harness.suite.runner import plan_suite, run_suite

    text = f"""
scenarios:
  - {{path: {FORKLIFT}, name: sets,
     set: {{duration: 2, {PLUGIN}: "tests.suite.plugins:SetsMujocoCallback"}}}}
  - {{path: {FORKLIFT}, name: plain, set: {{duration: 1}}}}
"""
    runs = _finished(tmp_path, text)
    sets, plain = runs["sets#1"], runs["plain#1"]
    assert sets["timings"]["pid"] == plain["timings"]["pid"]  # one host, the setter first
    (tmp_path / "alone.yaml").write_text(
        f"scenarios:\n  - {{path: {FORKLIFT}, name: plain, set: {{duration: 1}}}}\n")
    fresh = tmp_path / "fresh"
    run_suite(plan_suite([tmp_path / "alone.yaml"]), LocalExecutor(1, fork=False), out=fresh)
    (alone,) = _runs(fresh).values()
    assert plain["digest"] == alone["digest"] is not None


def test_an_interrupted_suite_starts_nothing_more(tmp_path: Path) -> None:
    """Ctrl-C while the only slot's run is stuck: it is stopped and finalized, the next run
    is reported as not started and leaves nothing (no run directory, no log), and no host is
    left behind."""
    proc = _stuck(tmp_path, quick=True)  # the slow run (the costlier: first) is stuck
    out = tmp_path / "out"
    proc.send_signal(signal.SIGINT)
    log = proc.communicate(timeout=300)[0]
    assert proc.returncode == 0, log
    runs = _runs(out)
    slow = runs["slow#1"]
    assert slow["verdict"] == "INTERRUPTED" and slow["run_dir"]
    quick = runs["quick#1"]
    assert quick["verdict"] == "INTERRUPTED" and quick["reasons"] == [
        "not started: the suite was interrupted"]
    assert quick["run_dir"] is None and not (out / "runs" / "quick").exists()
    assert sorted(p.name for p in (out / "logs").iterdir()) == ["slow_1.log"]
    with pytest.raises(ProcessLookupError):  # the host went with the suite's process
        os.killpg(slow["timings"]["pid"], 0)


def test_only_the_projects_own_modules_are_dropped_between_runs(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """What a host re-imports for each run: modules under the project folder (the current
    directory, where plug-ins import from), never a package installed elsewhere (a
    ``PYTHONPATH`` or ``pip --target`` folder, as on a machine given wheels), nor one in a
    ``site-packages`` inside the project, nor srr's own."""
    import importlib.util

    import harness.suite.results
    from harness.suite.host import _is_plugin

    def module_at(path: Path) -> Any:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("STATE = 0\n", encoding="utf-8")
        spec = importlib.util.spec_from_file_location(path.stem, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    project, elsewhere = tmp_path / "project", tmp_path / "target"
    plugin = module_at(project / "plugins" / "mine.py")
    installed = module_at(elsewhere / "somelib" / "core.py")
    vendored = module_at(project / ".venv" / "lib" / "site-packages" / "lib.py")
    assert _is_plugin(plugin, str(project))
    assert not _is_plugin(installed, str(project))
    assert not _is_plugin(vendored, str(project))
    assert not _is_plugin(harness.suite.results, str(ROOT))
    assert not _is_plugin(json, str(project))


def test_srr_suite_imports_no_scipy_stats_before_its_runs() -> None:
    """What ``srr suite`` imports before its hosts are forked and the suite is checked (the
    serial start-up): SciPy's statistics, a quarter of it, are loaded only when the groups
    are judged."""
    code = ("import sys, harness.cli, harness.api, harness.suite.runner, harness.suite.local; "
            "print('scipy.stats' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": str(ROOT)}, check=True, timeout=120)
    assert out.stdout.strip() == "False", out.stderr


def test_a_host_stops_and_finalizes_its_run_when_the_suite_is_killed(tmp_path: Path) -> None:
    """``kill -9`` of the suite's process while its host runs a run stuck mid-way (it never
    ends on its own): the host gets SIGTERM, the run finalizes its bag and summary
    (interrupted), and the host ends instead of running on alone."""
    proc = _stuck(tmp_path)  # the run is stuck mid-way, in its host
    children = _children(proc.pid)
    assert len(children) == 1, children
    host = children[0]
    proc.kill()
    proc.communicate(timeout=60)
    deadline = time.monotonic() + 120  # a guard only: it ends once its run has finalized
    while _alive(host):
        assert time.monotonic() < deadline, "the host ran on after the suite was killed"
        time.sleep(0.05)
    summary = json.loads((tmp_path / "out" / "runs" / "slow" / "nominal" / "r1" /
                          "summary.json").read_text(encoding="utf-8"))
    assert summary["interrupted"] and summary["topics"]["/clock"]["count"] > 0


def test_an_idle_host_ends_once_no_run_is_left_to_start(tmp_path: Path) -> None:
    """Once every run has started, a host whose run is done ends at once (its process and
    OpenGL context go beside the runs still going), not when the last run is done."""
    proc = _stuck(tmp_path, quick=True, jobs=2)
    quick = tmp_path / "out" / "runs" / "quick"
    while not any(quick.rglob("summary.json")):
        assert proc.poll() is None, proc.communicate()[0]
        time.sleep(0.05)
    deadline = time.monotonic() + 120  # a guard only: the quick run's host ends by itself
    while len(_children(proc.pid)) > 1:
        assert time.monotonic() < deadline, f"idle hosts ran on: {_children(proc.pid)}"
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    log = proc.communicate(timeout=300)[0]
    runs = _runs(tmp_path / "out")
    assert runs["quick#1"]["verdict"] not in ("INTERRUPTED", "INVALID"), log  # it finished
    assert runs["slow#1"]["verdict"] == "INTERRUPTED", log


def _stuck(tmp_path: Path, *, quick: bool = False, jobs: int = 1) -> subprocess.Popen[str]:
    """A suite whose run ``slow`` gets stuck mid-way (and, with ``quick``, a short run
    ``quick`` after it), returned once ``slow`` is stuck."""
    stalled = tmp_path / "stalled"
    text = f"""
scenarios:
  - path: {FORKLIFT}
    name: slow
    set: {{duration: 3, {PLUGIN}: "tests.suite.plugins:Staller"}}
"""
    if quick:
        text += f"""  - path: {FORKLIFT}
    name: quick
    set: {{duration: 1}}
"""
    proc = _suite(tmp_path, text, jobs=jobs, env={STALLED_FILE: str(stalled)})
    while not stalled.exists():
        assert proc.poll() is None, proc.communicate()[0]
        time.sleep(0.05)
    return proc


def _children(pid: int) -> list[int]:
    """The live child processes of ``pid`` (a suite's: its hosts)."""
    return [int(p.name) for p in Path("/proc").iterdir() if p.name.isdigit()
            and _ppid(p) == pid and _alive(int(p.name))]


def _ppid(proc_dir: Path) -> int | None:
    try:
        stat = (proc_dir / "stat").read_text()
    except OSError:
        return None
    return int(stat.rsplit(")", 1)[1].split()[1])


def _alive(pid: int) -> bool:
    """Whether ``pid`` still runs (a zombie left for its new parent to reap does not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def _srr_suite(tmp_path: Path, text: str, jobs: int) -> dict[str, dict[str, Any]]:
    """``srr suite`` itself (its hosts forked before the suite is checked)."""
    tmp_path.mkdir()
    suite = tmp_path / "suite.yaml"
    suite.write_text(text, encoding="utf-8")
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "suite", str(suite), "--jobs",
                           str(jobs), "--out", str(tmp_path / "out"), "-q"], cwd=ROOT, text=True,
                          env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True,
                          timeout=600, check=False)
    assert proc.returncode in (0, 1), proc.stdout + proc.stderr
    return _runs(tmp_path / "out")


def test_srr_suite_hosts_make_an_opengl_context_only_when_the_runs_render(
        tmp_path: Path) -> None:
    """The hosts ``srr suite`` forks before it checks the suite make their OpenGL context once
    the check meets a run that renders: none for a suite without cameras (they made one each,
    which slowed the runs: contexts are costly when many processes make one), one per host,
    before its first run, for a suite with cameras."""
    cpu = _srr_suite(tmp_path / "cpu", f"scenarios:\n  - {{path: {FORKLIFT}, repeat: 2, "
                     "set: {duration: 0.5}}\n", jobs=2)
    assert len(cpu) == 2
    assert [r["timings"]["gl_contexts"] for r in cpu.values()] == [0, 0]
    assert [r["timings"]["warm_gl_s"] for r in cpu.values()] == [0, 0]
    # a suite whose second entry renders: found while checking, after the first
    cams = _srr_suite(tmp_path / "cams", f"scenarios:\n  - {{path: {FORKLIFT}, repeat: 1, "
                      f"set: {{duration: 0.5}}}}\n  - {{path: {CROSSING}, repeat: 1, "
                      "set: {duration: 0.5}}\n", jobs=2)
    assert len(cams) == 2
    by_pid: dict[int, list[dict[str, Any]]] = {}
    for run in sorted(cams.values(), key=lambda r: r["timings"]["started_s"]):
        by_pid.setdefault(run["timings"]["pid"], []).append(run)
    for runs in by_pid.values():  # made before the host's first run, none during a run
        assert runs[0]["timings"]["warm_gl_s"] > 0
        assert all(r["timings"]["gl_contexts"] == 1 for r in runs)


#: Hosts' turns to make an OpenGL context: the suite's process forks a host (which makes the
#: shared semaphore), then children of it each take a turn and hold it; each prints when it
#: held one.
TURNS = """
import os, sys, time
from harness.suite.host import fork_host, warm_slot
if sys.argv[1:] == ["no-semaphores"]:  # a platform without a working sem_open
    import multiprocessing.context

    def refuse(self, value=1):
        raise OSError(38, "Function not implemented")

    multiprocessing.context.BaseContext.Semaphore = refuse
fork_host().stop()
r, w = os.pipe()
kids = []
for _ in range(8):
    pid = os.fork()
    if pid == 0:
        with warm_slot():
            start = time.monotonic()
            time.sleep(0.8)
            os.write(w, f"{start} {time.monotonic()}\\n".encode())
        os._exit(0)
    kids.append(pid)
os.close(w)
for pid in kids:
    os.waitpid(pid, 0)
print(os.read(r, 65536).decode())
"""


def _turns(*args: str) -> int:
    """How many of TURNS' children held a turn at once, at most."""
    out = subprocess.run([sys.executable, "-c", TURNS, *args], cwd=ROOT, capture_output=True,
                         text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0, out.stderr
    spans = [tuple(map(float, line.split())) for line in out.stdout.split("\n") if line]
    assert len(spans) == 8
    # how many held a turn at each instant one began
    return max(sum(a <= start < b for a, b in spans) for start, _ in spans)


def test_hosts_make_their_opengl_contexts_a_few_at_a_time() -> None:
    from harness.suite.host import WARM_AT_ONCE

    assert 2 <= _turns() <= WARM_AT_ONCE
    # where no semaphore can be made, hosts still start, without the limit
    assert _turns("no-semaphores") > WARM_AT_ONCE


def test_forking_a_host_leaves_the_suite_s_own_collections_as_they_were() -> None:
    """The suite's process thaws once the host is forked: a program that runs suite after
    suite (a notebook, a Ray driver) still collects what it made before each fork."""
    proc = subprocess.run([sys.executable, "-c", """
import gc
from harness.suite.host import fork_host
fork_host().stop()
print(gc.get_freeze_count())
"""], cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split()[-1] == "0"
