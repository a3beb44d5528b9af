"""`srr replay --ros2`: a recording played into real external rclpy nodes, in lockstep.

The recording is a short dock run whose safety monitor is the external rclpy node of
tests/ros2/ext_safety_node.py (recorded with `srr run --ros2`, blessed as its own baseline in
a scratch folder): the forklift starts just before the trailer, so the mute engages within a
few seconds of simulated time. Each replay plays that recording back into the same node (or a
changed one) on a ROS 2 graph of its own and records what the node publishes."""

from __future__ import annotations

import json
import os
import re
import shlex
import sys
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader

from harness import api
from harness.cli import main
from harness.summary import replay_note
from tests.live.foxglove_client import LiveClient

if os.environ.get("SRR_REQUIRE_ROS2") == "1":
    import rclpy  # noqa: F401  (an ImportError here is a collection error, never a skip)
pytest.importorskip("rclpy", reason="needs the ros2 extra: pip install -e '.[dev,ros2]'")

pytestmark = [pytest.mark.ros2, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
DOCK = ROOT / "scenarios" / "dock_worker_crossing.yaml"
NODE = Path(__file__).with_name("ext_safety_node.py")
TAP = Path(__file__).with_name("tap_node.py")
TAPPED = {"/clock": "rosgraph_msgs/msg/Clock", "/odom": "nav_msgs/msg/Odometry",
          "/tf_static": "tf2_msgs/msg/TFMessage"}
MUTED = "/safety/is_muted"


def _cmd(*args: str) -> list[str]:
    return [sys.executable, str(NODE), *args]


@pytest.fixture(scope="session")
def nightly(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """Last night's run: 5 s of the dock with the external safety monitor, blessed."""
    tmp = tmp_path_factory.mktemp("nightly")
    sc = api.load(DOCK, duration=5.0, overrides=[
        "robots.forklift.spawn.position=[14.5, 0.0, 0.0]",
        "routes.dock_approach.waypoints=[[14.5, 0.0], [18.0, 0.0]]",
        "systems_under_test.safety_monitor.enabled=false",
        "ros2.enabled=true",
        "ros2.outputs=[{topic: /safety/is_muted, type: std_msgs/msg/Bool, rate_hz: 5},"
        " {topic: /safety/alarm, type: std_msgs/msg/Bool, rate_hz: 5}]",
        f"ros2.external=[{{name: safety, cmd: {json.dumps(_cmd())}}}]",
    ])
    return api.run_scenario(sc, source=str(DOCK), out=tmp / "run",
                            baselines=tmp / "baselines", update_baseline=True)


def _topic(run_dir: Path, topic: str) -> list[tuple[int, bytes]]:
    (path,) = (run_dir / "bag").glob("*.mcap")
    with path.open("rb") as f:
        return [(m.log_time, bytes(m.data))
                for _s, _c, m in make_reader(f).iter_messages(topics=[topic])]


def _digests(res: Any) -> dict[str, str]:
    return {t: v["sha256"] for t, v in res.summary["topics"].items()}


def test_replay_into_the_same_node_reproduces_the_recording(nightly: Any,
                                                            tmp_path: Path) -> None:
    assert nightly.verdict == "RECORDED" and nightly.blessed is not None, nightly.summary["reasons"]
    recorded = _topic(nightly.run_dir, MUTED)
    assert any(raw[4] == 1 for _, raw in recorded)  # the mute engaged in the recording
    # the recorded ros2 block, its node made slower (+30 ms of wall clock per answer): the
    # replay waits for it, so it misses nothing and answers as it did
    # replay the nightly with a raw tap node beside it: what the graph carried
    heavy = shlex.join(_cmd("--work-ms", "30"))
    tap = [sys.executable, str(TAP), str(tmp_path / "tap.json"),
           *(f"{t}={ty}" for t, ty in TAPPED.items())]
    both = (f"ros2.external=[{{name: safety, cmd: {json.dumps(_cmd())}}}, "
            f"{{name: tap, cmd: {json.dumps(tap)}, ready_topic: /tap/ready}}]")
    a = api.replay(nightly.run_dir, out=tmp_path / "a", overrides=[both],
                   externals=[f"safety={heavy}"])
    seen = json.loads((tmp_path / "tap.json").read_text(encoding="utf-8"))
    for topic in TAPPED:  # the recorded bytes, every message, in order
        assert seen["messages"][topic] == [raw.hex() for _, raw in
                                           _topic(nightly.run_dir, topic)], topic
    # with the recorded QoS: /tf_static latched (the tap joined late, as a subscriber would)
    assert seen["offered"]["/tf_static"] == [{"durability": "TRANSIENT_LOCAL",
                                              "reliability": "RELIABLE"}]
    assert seen["offered"]["/clock"][0]["durability"] == "VOLATILE"
    # again, watched live (--foxglove): the played-back topics and the node's new outputs
    watched = ["/clock", "/odom", "/tf_static", MUTED]
    clients: list[LiveClient] = []

    def notice(line: str) -> None:
        found = re.match(r"live view on ws://127\.0\.0\.1:(\d+) ", line)
        if found is not None:
            clients.append(LiveClient(int(found.group(1)), watched, confirm=True).start())
            clients[0].confirmed.wait(60)

    b = api.replay(nightly.run_dir, out=tmp_path / "b", ros2=True, notice=notice,
                   live=api.LiveConfig(port=0, wait_s=60.0))
    # the node's outputs come from the node, in lockstep: the recorded ones exactly
    assert _topic(a.run_dir, MUTED) == recorded
    assert a.summary["replay_of"]["mode"] == "ros2-lockstep"
    assert MUTED in a.summary["replay_of"]["withheld"]
    assert "replay into external ROS 2 nodes in lockstep of" in str(replay_note(a.summary))
    assert a.verdict == "PASS", a.summary["reasons"]
    # two replays: the same bytes on every topic, and the recording's
    assert _digests(a) == _digests(b) == _digests(nightly)
    procs = json.loads((a.run_dir / "ros2" / "processes.json").read_text(encoding="utf-8"))
    assert procs[0]["name"] == "safety" and procs[0]["stopped_with"] == "SIGINT"
    (client,) = clients
    got = client.join()
    for topic in watched:  # served live: what the replay recorded
        assert got.messages[topic] == _topic(b.run_dir, topic), topic


def test_a_slower_node_is_regressed_on_the_lag_metrics(nightly: Any, tmp_path: Path) -> None:
    slow = shlex.join(_cmd("--mute-after", "4"))  # mutes 3 tracks messages (0.6 s) later
    res = api.replay(nightly.run_dir, out=tmp_path / "slow",
                     externals=[f"safety={slow}"])
    assert res.verdict == "REGRESSED", res.summary["reasons"]
    assert any("safety.mute_lag" in r for r in res.summary["reasons"]), res.summary["reasons"]
    assert _topic(res.run_dir, MUTED) != _topic(nightly.run_dir, MUTED)
    assert "--mute-after" in res.summary["replay_of"]["overrides"][-1]
    procs = json.loads((res.run_dir / "ros2" / "processes.json").read_text(encoding="utf-8"))
    assert "--mute-after" in procs[0]["cmd"]


def test_a_node_that_exits_mid_replay_makes_it_invalid(nightly: Any, tmp_path: Path) -> None:
    dies = shlex.join(_cmd("--exit-after", "2.0"))
    # with the built-in monitor switched back on too: two publishers of /safety/is_muted
    res = api.replay(nightly.run_dir, out=tmp_path / "dies", externals=[f"safety={dies}"],
                     overrides=["systems_under_test.safety_monitor.enabled=true"])
    assert any(w.endswith("ros2_bridge publishes /safety/is_muted, which safety_monitor "
                          "publishes too") for w in res.summary["warnings"])
    assert res.verdict == "INVALID" and res.exit_code == 3
    gate = next(h for h in res.summary["health"] if h["name"] == "ros2_lockstep")
    assert "external process safety exited with code 7" in gate["detail"]
    assert res.summary["ticks"] < 5 * 60


@pytest.mark.parametrize(("given", "words"), [
    ("saftey=python n.py", "--ros2-external: saftey: no external process named 'saftey' in "
                           "the ros2 block of"),
    ("safety=no-such-node --x", "--ros2-external: safety: 'no-such-node' is not an executable"),
    ("safety=", "--ros2-external: safety: the command is empty"),
])
def test_a_bad_ros2_external_is_one_clear_line(nightly: Any, tmp_path: Path, given: str,
                                               words: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "x"
    code = main(["replay", str(nightly.run_dir), "--ros2-external", given, "--out", str(out),
                 "-q"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert words in err, err
    assert not out.exists()


def test_a_run_refused_after_its_nodes_started_leaves_no_directory(tmp_path: Path) -> None:
    """The external nodes start (and write their logs into the run directory) before the
    live view takes its port: a port in use then is refused, exit 2, and the directory goes
    with the logs (a second try with the same --out is not refused as not empty)."""
    import socket

    held = socket.socket()
    held.bind(("127.0.0.1", 0))
    held.listen()
    port = held.getsockname()[1]
    out = tmp_path / "run"
    try:
        code = main(["run", str(DOCK), "--duration", "1", "-q", "--out", str(out),
                     "--foxglove", "--foxglove-port", str(port),
                     "--set", "systems_under_test.safety_monitor.enabled=false",
                     "--set", "ros2.enabled=true",
                     "--set", "ros2.outputs=[{topic: /safety/is_muted, type: "
                              "std_msgs/msg/Bool, rate_hz: 5}]",
                     "--set", f"ros2.external=[{{name: safety, cmd: {json.dumps(_cmd())}}}]"])
    finally:
        held.close()
    assert code == 2 and not out.exists()


def _running(marker: str) -> list[int]:
    """Pids of live processes whose command line holds ``marker``."""
    pids = []
    for proc in Path("/proc").iterdir():
        if proc.name.isdigit():
            try:
                cmd = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode()
                state = (proc / "stat").read_text().split(") ", 1)[1][0]
            except (OSError, IndexError):
                continue
            if marker in cmd and state != "Z":
                pids.append(int(proc.name))
    return pids


def test_a_killed_srr_takes_its_external_nodes_with_it(tmp_path: Path) -> None:
    """kill -9 of srr, which cannot stop its nodes then: each node (in a session of its own)
    still ends, by its parent-death signal, instead of running on alone on the domain."""
    import signal
    import subprocess
    import time

    marker = f"--node-of-{tmp_path.name}"  # an argument of this test's node only
    out = tmp_path / "run"
    cmd = json.dumps([*_cmd(), marker])
    proc = subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "run", str(DOCK), "--duration", "30", "-q",
         "--out", str(out), "--set", "systems_under_test.safety_monitor.enabled=false",
         "--set", "ros2.enabled=true",
         "--set", "ros2.outputs=[{topic: /safety/is_muted, type: std_msgs/msg/Bool, rate_hz: 5}]",
         "--set", f"ros2.external=[{{name: safety, cmd: {cmd}}}]"],
        cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while not (out / "bag").is_dir() and time.monotonic() < deadline:  # ticking
            time.sleep(0.2)
        assert _running(marker), "the node did not start"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    deadline = time.monotonic() + 20
    while _running(marker) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = _running(marker)
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert not left, f"node processes left running: {left}"
