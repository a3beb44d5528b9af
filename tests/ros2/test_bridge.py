"""`srr run --ros2` with a real external rclpy node in its own process, in lockstep.

The node (tests/ros2/ext_cmd_node.py) subscribes to odometry (with use_sim_time on /clock) and
publishes cmd_vel from each odometry message alone; the internal route follower is switched
off, so the forklift moves only as the external node commands."""

from __future__ import annotations

import errno
import fcntl
import json
import os
import stat
import sys
import tempfile
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader

from harness import api
from harness.blas import one_blas_thread
from harness.cli import main
from harness.errors import SrrError
from harness.ros2.domain import DomainInUse, lease_domain
from harness.serde.messages import TYPESTORE

if os.environ.get("SRR_REQUIRE_ROS2") == "1":
    import rclpy  # noqa: F401  (an ImportError here is a collection error, never a skip)
pytest.importorskip("rclpy", reason="needs the ros2 extra: pip install -e '.[dev,ros2]'")

pytestmark = [pytest.mark.ros2, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
FORKLIFT = ROOT / "scenarios" / "forklift_warehouse.yaml"
NODE = Path(__file__).with_name("ext_cmd_node.py")


def _overrides(*node_args: str, timeout: float = 10.0) -> list[str]:
    cmd = json.dumps([sys.executable, str(NODE), *node_args])
    return [
        "systems_under_test.route_follower.enabled=false",
        "ros2.enabled=true",
        f"ros2.timeout={timeout}",
        "ros2.outputs=[{topic: /cmd_vel, type: geometry_msgs/msg/Twist, rate_hz: 60}]",
        f"ros2.external=[{{name: commander, cmd: {cmd}}}]",
    ]


def _run(tmp: Path, name: str, *node_args: str, duration: float = 2.0,
         timeout: float = 10.0) -> Any:
    sc = api.load(FORKLIFT, duration=duration, overrides=_overrides(*node_args,
                                                                    timeout=timeout))
    return api.run_scenario(sc, source=str(FORKLIFT), out=tmp / name)


def _messages(run_dir: Path, topic: str) -> list[tuple[int, Any]]:
    (path,) = (run_dir / "bag").glob("*.mcap")
    out = []
    with path.open("rb") as f:
        for schema, _channel, msg in make_reader(f).iter_messages(topics=[topic]):
            out.append((msg.log_time, TYPESTORE.deserialize_cdr(msg.data, schema.name)))
    return out


def test_external_node_drives_the_robot_in_lockstep(tmp_path: Path) -> None:
    a = _run(tmp_path, "a")
    b = _run(tmp_path, "b")
    odom = _messages(a.run_dir, "/odom")
    cmds = _messages(a.run_dir, "/cmd_vel")
    # the bag holds the external node's commands: one per odometry message, at its tick
    assert len(cmds) == len(odom) == 120
    assert [t for t, _ in cmds] == [t for t, _ in odom]
    for (_, o), (_, c) in zip(odom, cmds, strict=True):
        t = o.header.stamp.sec + o.header.stamp.nanosec * 1e-9
        assert c.linear.x == pytest.approx(min(1.2, 0.3 + 0.5 * t), abs=1e-12)
        assert c.angular.z == (0.25 if o.pose.pose.position.y < 0.0 else 0.0)
    # ...and the robot moved as commanded: ~ the integral of the ramp over 2 s
    x_end = odom[-1][1].pose.pose.position.x
    assert 0.9 < abs(x_end) < 1.9
    # two lockstep runs with the same external node: identical recordings
    assert a.summary["digest"] == b.summary["digest"]
    assert a.summary["verdict"] == "MISMATCH"  # 2 s against the 35 s baseline: said so
    # the node was started with sim time in its own process group and stopped with SIGINT
    procs = json.loads((a.run_dir / "ros2" / "processes.json").read_text(encoding="utf-8"))
    assert procs[0]["name"] == "commander" and procs[0]["stopped_with"] == "SIGINT"
    assert procs[0]["exit_code"] == 0
    # tf2_msgs is built for rclpy (harness.ros2.tf2_msgs): TF is bridged too
    assert not any("not published" in w for w in a.summary["warnings"]), a.summary["warnings"]


def test_a_node_that_stops_publishing_makes_the_run_invalid(tmp_path: Path) -> None:
    res = _run(tmp_path, "silent", "--silent-after", "1.0", duration=3.0, timeout=1.0)
    assert res.verdict == "INVALID" and res.exit_code == 3
    gate = next(h for h in res.summary["health"] if h["name"] == "ros2_lockstep")
    assert not gate["ok"]
    assert "/cmd_vel (geometry_msgs/msg/Twist)" in gate["detail"]
    assert "t=1 s" in gate["detail"]
    assert res.summary["stopped"] and (res.run_dir / "summary.json").is_file()
    assert res.summary["ticks"] == 60  # stopped at the tick that waited in vain


def test_an_external_process_that_dies_makes_the_run_invalid(tmp_path: Path) -> None:
    res = _run(tmp_path, "dies", "--exit-after", "0.5", duration=3.0, timeout=30.0)
    assert res.verdict == "INVALID"
    gate = next(h for h in res.summary["health"] if h["name"] == "ros2_lockstep")
    assert "external process commander exited with code 5" in gate["detail"]
    procs = json.loads((res.run_dir / "ros2" / "processes.json").read_text(encoding="utf-8"))
    assert procs[0]["exit_code"] == 5 and procs[0]["stopped_with"] is None


@pytest.mark.parametrize(("srr_set", "seen"), [(True, "unset"), (False, "3")])
def test_an_external_process_gets_the_users_blas_threads_not_srrs(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, srr_set: bool, seen: str) -> None:
    """The ``srr`` command asks its own process for one OpenBLAS thread; the nodes it starts
    see the variable only when the user set it."""
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "SRR_ADDED_OPENBLAS_NUM_THREADS"):
        monkeypatch.delenv(var, raising=False)
    if srr_set:
        assert one_blas_thread() is True  # as `srr` does (monkeypatch restores the variables)
    else:
        monkeypatch.setenv("OPENBLAS_NUM_THREADS", "3")
    cmd = json.dumps(["sh", "-c", 'echo "BLAS=${OPENBLAS_NUM_THREADS-unset}"; exit 5'])
    sc = api.load(FORKLIFT, duration=1.0, overrides=[
        *_overrides(timeout=10.0)[:-1], f"ros2.external=[{{name: probe, cmd: {cmd}}}]"])
    with pytest.raises(SrrError, match="exited with code 5 before it was ready"):
        api.run_scenario(sc, source=str(FORKLIFT), out=tmp_path / "run")
    assert (tmp_path / "run" / "ros2" / "probe.log").read_text().strip() == f"BLAS={seen}"


def test_runs_take_different_domains_and_release_them() -> None:
    a, b = lease_domain(None), lease_domain(None)
    try:
        assert a.domain_id != b.domain_id and 1 <= a.domain_id <= 101
    finally:
        a.release()
        b.release()
    named = lease_domain(7)  # as the scenario says, and locked like any other
    try:
        assert named.domain_id == 7
        with pytest.raises(DomainInUse, match="ROS_DOMAIN_ID 7 is in use by another srr run"):
            lease_domain(7)
    finally:
        named.release()
    lease_domain(7).release()  # free again


def test_a_domain_id_another_run_holds_is_refused_in_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Two runs that name the same ros2.domain_id hear each other's /clock, sensors and
    outputs: both recorded something else than alone, and both said RECORDED. The second is
    refused before anything starts, and leaves no run directory."""
    held = lease_domain(43)
    try:
        code = main(["run", str(FORKLIFT), "-q", "--out", str(tmp_path / "run"), "--set",
                     "duration=1", *(f"--set={o}" for o in _overrides()),
                     "--set", "ros2.domain_id=43"])
    finally:
        held.release()
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"srr run: {FORKLIFT}: ros2.domain_id: ROS_DOMAIN_ID 43 is in use")
    assert not (tmp_path / "run").exists()


def test_the_lock_folder_is_shared_by_every_user(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """The first user's run made it 0755 and its lock files 0644, opened for writing: another
    user's run failed with a PermissionError traceback. It is sticky and writable by all, as
    /tmp is, and a lock file is opened read-only."""
    monkeypatch.delenv("SRR_ROS2_LOCK_DIR", raising=False)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    lease = lease_domain(None)
    try:
        assert stat.S_IMODE((tmp_path / "srr-ros2").stat().st_mode) == 0o1777
        assert lease._file is not None and lease._file.mode == "rb"
    finally:
        lease.release()


def test_a_lock_folder_that_cannot_be_made_or_locked_in_is_one_line(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A lock folder this user cannot make (under a file here), or a filesystem whose flock
    fails with another error than 'held' (NFS without write access: EBADF): a free id is
    refused in one line naming the folder, and a named id runs unlocked. Neither is taken for
    'another run holds it'."""
    (tmp_path / "file").write_text("")
    monkeypatch.setenv("SRR_ROS2_LOCK_DIR", str(tmp_path / "file" / "locks"))
    with pytest.raises(SrrError, match=r"^ros2: no free ROS_DOMAIN_ID 1-101: cannot lock in "):
        lease_domain(None)
    lease = lease_domain(9)
    assert lease.domain_id == 9 and lease._file is None
    lease.release()

    monkeypatch.setenv("SRR_ROS2_LOCK_DIR", str(tmp_path / "locks"))

    def no_flock(f: object, op: int) -> None:
        raise OSError(errno.EBADF, "Bad file descriptor")

    monkeypatch.setattr(fcntl, "flock", no_flock)
    with pytest.raises(SrrError, match=r"cannot lock in .*\(Bad file descriptor\)"):
        lease_domain(None)
    lease = lease_domain(9)
    assert lease.domain_id == 9 and lease._file is None


def test_a_missing_external_command_is_named_with_the_scenario_file(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`srr validate` named the file; `srr run` said only `ros2.external[0].cmd: cannot
    start ...`."""
    code = main(["run", str(FORKLIFT), "-q", "--out", str(tmp_path / "run"),
                 *(f"--set={o}" for o in _overrides()[:-1]),
                 "--set", "ros2.external=[{cmd: [no-such-node-binary]}]"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err == (f"srr run: {FORKLIFT}: ros2.external[0].cmd: "
                                 "'no-such-node-binary' is not an executable file or on PATH")
    assert not (tmp_path / "run").exists()


def _inline_node(body: str) -> str:
    """``ros2.external`` with one rclpy node written inline (``python -c``)."""
    code = ("import rclpy\nfrom geometry_msgs.msg import Twist, TwistStamped\n"
            "from nav_msgs.msg import Odometry\nrclpy.init()\nn = rclpy.create_node('probe')\n"
            f"{body}\ntry:\n    rclpy.spin(n)\nexcept BaseException:\n    pass\n")
    return f"ros2.external=[{{name: probe, cmd: {json.dumps([sys.executable, '-c', code])}}}]"


@pytest.mark.parametrize(("body", "words"), [
    ("n.create_publisher(TwistStamped, '/cmd_vel', 10)",
     "still waiting on /cmd_vel (published as geometry_msgs/msg/TwistStamped, not the "
     "declared geometry_msgs/msg/Twist)"),
    ("n.create_publisher(Twist, '/cmd_vell', 10)",
     "still waiting on /cmd_vel (nothing publishes it; /cmd_vell (geometry_msgs/msg/Twist) "
     "is published: misspelt or in another namespace?)"),
    ("n.create_publisher(Twist, '/forklift/cmd_vel', 10)",
     "still waiting on /cmd_vel (nothing publishes it; /forklift/cmd_vel"),
    ("from rclpy.qos import qos_profile_sensor_data\n"
     "n.create_publisher(Twist, '/cmd_vel', qos_profile_sensor_data)",
     "still waiting on /cmd_vel (its publisher's QoS does not match the bridge's subscription: "
     "best effort publisher and reliable subscription; set ros2.qos: {/cmd_vel: "
     "{reliability: best_effort, durability: volatile}})"),
])
def test_a_node_never_ready_is_told_what_the_graph_has_instead(
        tmp_path: Path, body: str, words: str) -> None:
    """A publisher of the output of another type, QoS, or of a misspelt or namespaced name:
    the error said only `still waiting on /cmd_vel`, though `ros2 topic list` showed one."""
    # 6 s: time for a loaded machine to start Python and rclpy (2 s was not, once)
    sc = api.load(FORKLIFT, duration=1.0, overrides=[
        *_overrides()[:-1], _inline_node(body), "ros2.external.0.ready_timeout=6"])
    with pytest.raises(SrrError, match="not ready within 6 s") as err:
        api.run_scenario(sc, source=str(FORKLIFT), out=tmp_path / "run")
    assert words in str(err.value)


def test_a_node_that_has_not_joined_the_graph_is_said_to_be_late(tmp_path: Path) -> None:
    """A node still starting when the ready timeout ends (it sleeps before rclpy): the error
    says that no external node has joined the graph yet, and what to raise."""
    node = json.dumps([sys.executable, "-c", "import time; time.sleep(30)"])
    sc = api.load(FORKLIFT, duration=1.0, overrides=[
        *_overrides()[:-1], f"ros2.external=[{{name: slow, cmd: {node}, ready_timeout: 1}}]"])
    with pytest.raises(SrrError, match="not ready within 1 s") as err:
        api.run_scenario(sc, source=str(FORKLIFT), out=tmp_path / "run")
    assert ("still waiting on /cmd_vel; no external node has joined the ROS graph yet: a "
            "node may take seconds to start, raise ros2.external[].ready_timeout;") \
        in str(err.value)


def test_a_lockstep_timeout_names_a_misspelt_input(tmp_path: Path) -> None:
    """The node subscribes to /odm, which nothing publishes, so it never answers: the error
    said only that no /cmd_vel came."""
    body = ("p = n.create_publisher(Twist, '/cmd_vel', 10)\n"
            "n.create_subscription(Odometry, '/odm', lambda m: p.publish(Twist()), 10)")
    sc = api.load(FORKLIFT, duration=1.0, overrides=[
        *_overrides(timeout=1.0)[:-1], _inline_node(body)])
    res = api.run_scenario(sc, source=str(FORKLIFT), out=tmp_path / "run")
    gate = next(h for h in res.summary["health"] if h["name"] == "ros2_lockstep")
    assert "the external nodes subscribe to /odm, which nothing publishes (did you mean " \
        "/odom?)" in gate["detail"]


def test_external_safety_monitor_is_scored_like_the_built_in(tmp_path: Path) -> None:
    """The dock scene with the built-in safety monitor off and an external rclpy one in its
    place (fed by the built-in perception's /perception/tracks over ROS 2): scored with the
    same metrics, against the same baseline as the built-in monitor. It places the odometry
    in the world with /tf_static, received over ROS 2 (tf2_msgs built for rclpy)."""
    dock = ROOT / "scenarios" / "dock_worker_crossing.yaml"
    node = json.dumps([sys.executable, str(Path(__file__).with_name("ext_safety_node.py"))])
    sc = api.load(dock, overrides=[
        "systems_under_test.safety_monitor.enabled=false",
        "ros2.enabled=true",
        "ros2.outputs=[{topic: /safety/is_muted, type: std_msgs/msg/Bool, rate_hz: 5},"
        " {topic: /safety/alarm, type: std_msgs/msg/Bool, rate_hz: 5}]",
        f"ros2.external=[{{name: safety, cmd: {node}}}]",
    ])
    res = api.run_scenario(sc, source=str(dock), out=tmp_path / "dock")
    metrics = {m["name"]: m["value"] for m in res.summary["metrics"]}
    assert res.summary["topics"]["/safety/is_muted"]["count"] == 180  # 5 Hz for 36 s
    assert metrics["safety.match_rate"] > 95.0  # PASS band; the built-in gets 99.1 %
    assert metrics["safety.mute_never_engaged"] == 0
    assert metrics["safety.mute_lag.max"] < 0.3
    assert Path(res.summary["baseline"]["path"]).name == "dock_worker_crossing.json"
    assert res.verdict == "PASS", res.summary["reasons"]


@pytest.mark.parametrize(("extra", "words"), [
    (["ros2.outputs=[{topic: /cmd_vel, type: geometry_msgs/msg/Twist}]"],
     "ros2.outputs[0].rate_hz: geometry_msgs/msg/Twist has no header stamp"),
    (["ros2.outputs=[{topic: /cmd_vel, type: geometry_msgs/msg/Twst, rate_hz: 20}]"],
     "ros2.outputs[0].type: no rclpy type support for 'geometry_msgs/msg/Twst'"),
    (["ros2.outputs=[{topic: /cmd_vel, type: geometry_msgs/msg/Twist, rate_hz: 20}]",
      "ros2.external=[{cmd: [no-such-node-binary]}]"],
     "ros2.external[0].cmd: 'no-such-node-binary' is not an executable"),
])
def test_validate_checks_the_ros2_block_before_a_run(extra: list[str], words: str) -> None:
    sc = api.load(FORKLIFT, overrides=["systems_under_test.route_follower.enabled=false",
                                       "ros2.enabled=true", *extra])
    with pytest.raises(SrrError) as err:
        api.validate(sc, str(FORKLIFT))
    assert str(err.value) == f"{FORKLIFT}: {words}" or words in str(err.value)
    assert str(err.value).startswith(str(FORKLIFT) + ": ros2.")


def test_validate_counts_external_outputs_as_publishers() -> None:
    sc = api.load(FORKLIFT, overrides=[
        "systems_under_test.route_follower.enabled=false", "ros2.enabled=true",
        "ros2.outputs=[{topic: /cmd_vel, type: geometry_msgs/msg/Twist, rate_hz: 20}]"])
    warnings = api.validate(sc, str(FORKLIFT))
    assert not any("/cmd_vel" in w for w in warnings)  # the external node publishes it
    off = api.load(FORKLIFT, overrides=["systems_under_test.route_follower.enabled=false"])
    with pytest.raises(SrrError, match="nothing in the scenario publishes /cmd_vel"):
        api.validate(off, str(FORKLIFT))


def test_a_lockstep_timeout_says_a_stamped_outputs_latest_stamp(tmp_path: Path) -> None:
    """A stamped output without rate_hz is due at every tick; a node that answers a 5 Hz
    camera only waited in vain at the second tick, and the error did not say why."""
    body = ("p = n.create_publisher(TwistStamped, '/det', 10)\n"
            "def on(m):\n    if m.header.stamp.nanosec == 0 and m.header.stamp.sec == 0:\n"
            "        t = TwistStamped(); t.header = m.header; p.publish(t)\n"
            "n.create_subscription(Odometry, '/odom', on, 10)")
    sc = api.load(FORKLIFT, duration=1.0, overrides=[  # the route follower drives
        "ros2.enabled=true", "ros2.timeout=1", _inline_node(body),
        "ros2.outputs=[{topic: /det, type: geometry_msgs/msg/TwistStamped}]"])
    res = api.run_scenario(sc, source=str(FORKLIFT), out=tmp_path / "run")
    gate = next(h for h in res.summary["health"] if h["name"] == "ros2_lockstep")
    assert ("no /det (geometry_msgs/msg/TwistStamped; the latest was stamped 0 s, and without "
            "rate_hz one stamped at or after every tick is due)") in gate["detail"], gate
