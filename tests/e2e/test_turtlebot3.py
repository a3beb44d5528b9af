"""The TurtleBot3 seed end to end from the CLI: the seed's topic set, the hand-built TF tree,
the scripted motion in odometry, the lidar and IMU against the room's known geometry, and
determinism. Also the scripted teleop plug-in on its own."""

from __future__ import annotations

import functools
import importlib.util
import json
import math
import os
import subprocess
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness.bus import Bus
from harness.cli import main
from harness.geometry import yaw_from_quat_wxyz
from harness.scenario import load_scenario
from harness.sut.base import SutContext
from harness.sut.errors import PluginError
from harness.sut.teleop import ScriptedTeleop, Segment, command_at
from tests.conftest import ROOT, SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded

SCENARIO = SCENARIOS / "turtlebot3_room.yaml"
SEED_TOPICS = {
    "/clock": "rosgraph_msgs/msg/Clock",
    "/camera/color": "sensor_msgs/msg/Image",
    "/camera/camera_info": "sensor_msgs/msg/CameraInfo",
    "/scan": "sensor_msgs/msg/LaserScan",
    "/imu": "sensor_msgs/msg/Imu",
    "/cmd_vel": "geometry_msgs/msg/Twist",
    "/odom": "nav_msgs/msg/Odometry",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
}
CAMERA_TOPICS = ("/camera/color", "/camera/camera_info")
SPAWN = (-1.5, -1.5)
HALF = 3.0  # inner wall faces of the 6 x 6 m room
V, W = 0.2, 0.5  # the script: 3 s at V, a quarter turn at W, 3 s at V


def gl_env() -> dict[str, str]:
    """The environment of the CLI run: EGL rendering unless MUJOCO_GL says otherwise."""
    return {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}


@functools.cache
def rendering_available() -> bool:
    probe = [sys.executable, "-c", "import mujoco; mujoco.GLContext(8, 8).make_current()"]
    return subprocess.run(probe, env=gl_env(), capture_output=True, timeout=120).returncode == 0


def camera_expected() -> bool:
    """The camera pair is expected once the robot camera graph exists and OpenGL works."""
    return (importlib.util.find_spec("harness.builders.robot_camera") is not None
            and rendering_available())


def expected_topics() -> dict[str, str]:
    if camera_expected():
        return dict(SEED_TOPICS)
    return {k: v for k, v in SEED_TOPICS.items() if k not in CAMERA_TOPICS}


@pytest.fixture(scope="module")
def runs(module_tmp: ModuleTmp) -> Path:
    """``srr run --repeat 2`` in a fresh interpreter (MUJOCO_GL must be set before mujoco is
    imported); without OpenGL the camera is switched off and its topics are not expected."""
    out = module_tmp("tb3")
    cmd = [sys.executable, "-m", "harness.cli", "run", str(SCENARIO), "--repeat", "2",
           "--out", str(out), "-q"]
    if not camera_expected():
        cmd += ["--set", "robots.turtlebot3.sensors.camera.enabled=false"]
    done = subprocess.run(cmd, env=gl_env(), cwd=ROOT, capture_output=True, text=True,
                          timeout=600)
    # The seed scene records but scores nothing: UNSCORED, exit 1, never a silent PASS.
    assert done.returncode == 1, done.stdout + done.stderr
    assert "identical per-topic digests across 2 runs" in done.stdout
    return out


@pytest.fixture(scope="module")
def bag(runs: Path) -> dict[str, list[tuple[int, str, Any]]]:
    by_topic: dict[str, list[tuple[int, str, Any]]] = defaultdict(list)
    for topic, schema, log_ns, msg in decoded(runs / "run_1"):
        by_topic[topic].append((log_ns, schema, msg))
    return by_topic


def stamp(msg: Any) -> int:
    return int(msg.header.stamp.sec) * 10**9 + int(msg.header.stamp.nanosec)


def yaw_of(q: Any) -> float:
    return yaw_from_quat_wxyz((q.w, q.x, q.y, q.z))


slow = pytest.mark.slow  # the tests that need the CLI run (two 10 s runs, about 20 s)


@slow
def test_two_runs_give_identical_digests(runs: Path) -> None:
    report = json.loads((runs / "determinism.json").read_text())
    assert report["identical"] and len(set(report["digests"])) == 1


@slow
def test_topic_set_and_types_are_the_seeds(runs: Path,
                                           bag: dict[str, list[tuple[int, str, Any]]]) -> None:
    expected = expected_topics()
    assert {t: msgs[0][1] for t, msgs in bag.items()} == expected
    summary = json.loads((runs / "run_1" / "summary.json").read_text())
    assert summary["verdict"] == "UNSCORED" and summary["ticks"] == 600
    assert summary["exit_code"] == 1 and "nothing was scored" in summary["reasons"][0]
    counts = {t: len(m) for t, m in bag.items()}
    assert counts["/clock"] == counts["/odom"] == counts["/imu"] == 600
    assert counts["/scan"] == 50  # 5 Hz: gate step 12
    assert counts["/cmd_vel"] == 100  # 10 Hz teleop


@slow
def test_tf_static_holds_the_hand_built_tree(bag: dict[str, list[tuple[int, str, Any]]]) -> None:
    static = {(t.header.frame_id, t.child_frame_id): t.transform
              for _, _, msg in bag["/tf_static"] for t in msg.transforms}
    assert set(static) == {
        ("world", "odom"), ("base_footprint", "base_link"),
        ("base_link", "camera_link"), ("base_link", "caster_back_left_link"),
        ("base_link", "caster_back_right_link"), ("base_link", "imu_link"),
        ("base_link", "base_scan"),
        *([("camera_link", "camera")] if camera_expected() else [])}
    scan_tf = static[("base_link", "base_scan")].translation
    assert (scan_tf.x, scan_tf.y, scan_tf.z) == pytest.approx((-0.064, 0.0, 0.122), abs=1e-6)
    odom_tf = static[("world", "odom")].translation
    assert (odom_tf.x, odom_tf.y) == pytest.approx(SPAWN, abs=1e-3)
    dynamic = {(t.header.frame_id, t.child_frame_id)
               for _, _, msg in bag["/tf"] for t in msg.transforms}
    assert dynamic == {("odom", "base_footprint"), ("base_link", "wheel_left_link"),
                       ("base_link", "wheel_right_link")}
    frames = {c for _, c in static} | {c for _, c in dynamic} | {"world"}
    for topic in ("/scan", "/imu", *[t for t in CAMERA_TOPICS if t in bag]):
        assert {m.header.frame_id for _, _, m in bag[topic]} <= frames, topic


@slow
def test_odometry_follows_the_script(bag: dict[str, list[tuple[int, str, Any]]]) -> None:
    odom = [(stamp(m) / 1e9, m.pose.pose.position, m.pose.pose.orientation)
            for _, _, m in bag["/odom"]]

    def at(t: float) -> tuple[float, float, float]:
        _, p, q = min(odom, key=lambda row: abs(row[0] - t))
        return p.x, p.y, yaw_of(q)

    x, y, yaw = at(3.0)
    assert x == pytest.approx(V * 3.0, rel=0.1) and abs(y) < 0.01 and abs(yaw) < 0.02
    x2, y2, yaw2 = at(6.3)
    assert yaw2 == pytest.approx(math.pi / 2, rel=0.1)
    assert math.hypot(x2 - x, y2 - y) < 0.03  # turned on the spot
    x3, y3, yaw3 = at(9.9)
    assert y3 - y2 == pytest.approx(V * 3.0, rel=0.1)
    assert abs(x3 - x2) < 0.05 and yaw3 == pytest.approx(yaw2, abs=0.02)
    cmd = [m for _, _, m in bag["/cmd_vel"]]
    assert (cmd[0].linear.x, cmd[35].angular.z) == (V, W)
    assert cmd[-1].linear.x == 0.0 and cmd[-1].angular.z == 0.0  # script over: zero


@slow
def test_scan_and_imu_match_the_room(bag: dict[str, list[tuple[int, str, Any]]]) -> None:
    first = bag["/scan"][0][2]
    assert first.header.frame_id == "base_scan"
    ranges = np.asarray(first.ranges)
    lidar_x, lidar_y = SPAWN[0] - 0.064, SPAWN[1]
    assert ranges[180] == pytest.approx(lidar_x + HALF, abs=0.02)  # west wall, noise 5 mm
    assert ranges[270] == pytest.approx(lidar_y + HALF, abs=0.02)  # south wall
    assert ranges[0] == np.inf  # east wall 4.56 m away, beyond range_max 3.5
    every = np.concatenate([np.asarray(m.ranges) for _, _, m in bag["/scan"]])
    assert np.isfinite(every).any() and every[np.isfinite(every)].min() > 0.5  # no self-hits

    imu = [(stamp(m) / 1e9, m) for _, _, m in bag["/imu"]]
    still = [m.linear_acceleration.z for t, m in imu if 1.0 < t < 3.0]
    assert np.mean(still) == pytest.approx(9.81, abs=0.05)
    turning = [m.angular_velocity.z for t, m in imu if 3.6 < t < 6.0]
    assert np.mean(turning) == pytest.approx(W, rel=0.05)


@slow
def test_camera_streams_at_10_hz_in_the_optical_frame(
        bag: dict[str, list[tuple[int, str, Any]]]) -> None:
    if not camera_expected():
        pytest.skip("no robot camera graph or no OpenGL (set MUJOCO_GL=egl or osmesa)")
    color = [m for _, _, m in bag["/camera/color"]]
    info = [m for _, _, m in bag["/camera/camera_info"]]
    assert len(color) == len(info) == 100  # 10 Hz: gate step 6
    assert [stamp(m) for m in color] == [stamp(m) for m in info]
    assert {m.header.frame_id for m in color + info} == {"camera"}
    assert (color[0].width, color[0].height, info[0].width, info[0].height) == (320, 240) * 2


def test_validate_and_graph_list_the_sensor_graphs(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(SCENARIO)]) == 0
    assert main(["graph", str(SCENARIO), "--format", "json"]) == 0
    text = capsys.readouterr().out
    assert "/World/turtlebot3_LidarGraph" in text and "/World/turtlebot3_ImuGraph" in text


# ---------------------------------------------------------------- the teleop plug-in alone

def _teleop(params: dict[str, Any]) -> tuple[ScriptedTeleop, list[Any]]:
    bus = Bus(lambda: 0)
    got: list[Any] = []
    bus.add_tap(lambda env: got.append((env.topic, env.msg)))
    ctx = SutContext(name="teleop", params=params, scenario=load_scenario(SCENARIO), seed=0,
                     field="systems_under_test[0]", bus=bus)
    sut = ScriptedTeleop()
    sut.setup(ctx)
    return sut, got


def test_teleop_plays_segments_on_a_fixed_grid_then_zero() -> None:
    segs = (Segment(duration=0.5, linear=0.1), Segment(duration=0.25, angular=-0.3))
    assert command_at(segs, 0) == (0.1, 0.0)
    assert command_at(segs, 499_999_999) == (0.1, 0.0)
    assert command_at(segs, 500_000_000) == (0.0, -0.3)
    assert command_at(segs, 750_000_000) == (0.0, 0.0)
    sut, got = _teleop({"segments": [{"duration": 0.5, "linear": 0.1},
                                     {"duration": 0.25, "angular": -0.3}],
                        "rate_hz": 4, "cmd_vel_topic": "/robot/cmd_vel"})
    for k in range(61):  # one second of 60 Hz ticks
        sut.step(k * 10**9 // 60)
    assert [t for t, _ in got] == ["/robot/cmd_vel"] * 5  # 0, 0.25, 0.5, 0.75, 1.0 s
    assert [(m.linear.x, m.angular.z) for _, m in got] == [
        (0.1, 0.0), (0.1, 0.0), (0.0, -0.3), (0.0, 0.0), (0.0, 0.0)]


@pytest.mark.parametrize(("params", "match"), [
    ({}, r"segments"),
    ({"segments": []}, r"at least one segment"),
    ({"segments": [{"duration": -1.0}]}, r"segments\[0\]\.duration"),
    ({"segments": [{"duration": 1.0, "speed": 2.0}]}, r"speed"),
    ({"segments": [{"duration": 1.0}], "rate_hz": 0}, r"rate_hz"),
])
def test_teleop_params_are_validated(params: dict[str, Any], match: str) -> None:
    with pytest.raises(PluginError, match=match):
        _teleop(params)
