"""Seed 000's graph helpers, verbatim, as a scenario's ``graphs:`` builder
(``seed000_graphs.py`` / ``.yaml``), with the real node types: ``srr run`` records the seed's
topics and the recording, read back with an independent reader, holds what the seed
publishes.

The seed's nodes are Isaac Sim's ROS 1 bridge nodes (``omni.isaac.ros_bridge.ROS1*``), so the
run records ROS 1 by itself: MCAP with the ``ros1`` profile, read back with mcap +
mcap-ros1-support (genpy messages); with ``output.format=bag`` a ROS 1 bag, read back with
rosbags' AnyReader from the bag's own message definitions; with ``output.ros=2`` a rosbag2
directory, read back with mcap + mcap-ros2-support. Each run also has ground truth and a
control score, which must not depend on the format.

The robot (a scenario field: ``robots[0].model``) stands 1 m from the +x wall of a 6 x 6 m
room, facing it, and drives forward at 0.2 m/s (scripted teleop) for the 1 s run.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros1.decoder import DecoderFactory as Ros1DecoderFactory
from rosbags.highlevel import AnyReader

from harness import api
from harness import graph as og
from harness.engine import Simulation
from harness.frames import load_frames
from harness.report.images import nearest_images
from harness.scenario import load_scenario
from tests.conftest import ROOT, ModuleTmp
from tests.e2e.bagread import decoded
from tests.e2e.test_turtlebot3 import gl_env, rendering_available

SCENARIO = Path(__file__).with_name("seed000_graphs.yaml")
TICKS = 60
WALL_X, SPAWN_X = 3.0, 1.0  # inner face of the +x wall; the robot's base_footprint
SCAN_X = -0.064  # base_scan in base_link (the Waffle Pi's URDF)
# The seed's add_diff_teleop passes wheel_radius 0.066, twice the Waffle Pi's 0.033 m, so the
# robot drives at half the commanded 0.2 m/s, as it would in Isaac Sim.
DRIVEN = 0.2 * 0.033 / 0.066
STATIC = {("base_footprint", "base_link"), ("base_link", "camera_link"),
          ("base_link", "caster_back_left_link"), ("base_link", "caster_back_right_link"),
          ("base_link", "imu_link"), ("base_link", "base_scan")}
DYNAMIC = {("odom", "base_footprint"), ("base_link", "wheel_left_link"),
           ("base_link", "wheel_right_link")}
# Ground truth and a control score (a route straight ahead), so scoring runs on each format.
SCORED = ["--srr-gt", "--set", "routes={ahead: {waypoints: [[1.0, 0.0], [2.0, 0.0]]}}",
          "--set", "scoring.control={robot: turtlebot3, route: ahead}"]
# MD5 sums of the ROS 1 definitions, as ROS 1 Noetic's own packages give them.
MD5 = {"tf2_msgs/TFMessage": "94810edda583a504dfda3829e70d7eec",
       "rosgraph_msgs/Clock": "a9c97c1d230cfc112e270351a944ee47",
       "sensor_msgs/Image": "060021388200f6f0f447d0fcd9c64743",
       "nav_msgs/Odometry": "cd5e73d190d741a2f92e81eda573aca7"}
FORMATS = {"ros1-mcap": [], "ros1-bag": ["--set", "output.format=bag"],
           "ros2": ["--set", "output.ros=2"]}


@dataclass
class Recorded:
    """One run, read back: messages per topic, the type each topic was recorded as, its MD5
    sum (ROS 1), whether it is latched, and the summary."""

    run_dir: Path
    summary: dict[str, Any]
    msgs: dict[str, list[Any]] = field(default_factory=lambda: defaultdict(list))
    types: dict[str, str] = field(default_factory=dict)
    md5: dict[str, str] = field(default_factory=dict)
    latched: set[str] = field(default_factory=set)


def _read_ros1_mcap(rec: Recorded) -> None:
    (path,) = sorted((rec.run_dir / "bag").glob("*.mcap"))
    assert not (rec.run_dir / "bag" / "metadata.yaml").exists()  # not a rosbag2 bag
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[Ros1DecoderFactory()])
        assert reader.get_header().profile == "ros1"
        for schema, channel, _, msg in reader.iter_decoded_messages():
            assert (schema.encoding, channel.message_encoding) == ("ros1msg", "ros1")
            rec.msgs[channel.topic].append(msg)
            rec.types[channel.topic] = schema.name
            rec.md5[schema.name] = type(msg)._md5sum  # genpy's, from the schema's text
            if channel.metadata.get("latching") == "true":
                rec.latched.add(channel.topic)


def _read_ros1_bag(rec: Recorded) -> None:
    (path,) = sorted((rec.run_dir / "bag").glob("*.bag"))
    with AnyReader([path]) as reader:  # types parsed from the bag's own definitions
        for conn in reader.connections:
            name = conn.msgtype.replace("/msg/", "/")
            rec.types[conn.topic] = name
            rec.md5[name] = conn.digest
            if conn.ext.latching:
                rec.latched.add(conn.topic)
        for conn, _, raw in reader.messages():
            rec.msgs[conn.topic].append(reader.deserialize(raw, conn.msgtype))


def _read_ros2(rec: Recorded) -> None:
    for topic, schema, _, msg in decoded(rec.run_dir):
        rec.msgs[topic].append(msg)
        rec.types[topic] = schema


READERS = {"ros1-mcap": _read_ros1_mcap, "ros1-bag": _read_ros1_bag, "ros2": _read_ros2}


@pytest.fixture(scope="module", params=list(FORMATS))
def bag(request: pytest.FixtureRequest, module_tmp: ModuleTmp) -> Recorded:
    if not rendering_available():
        pytest.skip("no OpenGL for the seed's camera (MUJOCO_GL=egl or osmesa)")
    out = module_tmp(f"seed000-{request.param}")
    done = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(SCENARIO), "--out",
                           str(out), "-q", *SCORED, *FORMATS[request.param]], env=gl_env(),
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 1, done.stderr  # FAIL: no baseline, and the goal is 1 m off
    rec = Recorded(out, json.loads((out / "summary.json").read_text()))
    READERS[request.param](rec)
    return rec


# -- field access that works on genpy (ROS 1), rosbags and mcap-ros2 messages


def sec_ns(t: Any) -> int:
    sec = t.sec if hasattr(t, "sec") else t.secs
    nsec = t.nanosec if hasattr(t, "nanosec") else t.nsecs
    return int(sec) * 1_000_000_000 + int(nsec)


def stamp(msg: Any) -> int:
    return sec_ns(msg.header.stamp)


def k_of(info: Any) -> Any:
    return info.k if hasattr(info, "k") else info.K


@pytest.mark.slow
def test_the_seed_topics_are_recorded(bag: Recorded) -> None:
    assert {t: len(m) for t, m in bag.msgs.items()} == {
        "/clock": TICKS, "/camera/color": TICKS, "/camera/camera_info": TICKS,
        "/scan": TICKS, "/imu": TICKS, "/cmd_vel": 10, "/gt/turtlebot3/tf": TICKS,
        # add_odometry wires PubComputeOdometry's execIn from the tick and from ComputeOdometry
        "/odom": 2 * TICKS,
        "/tf": 2 * TICKS, "/tf_static": 2}
    assert [sec_ns(m.clock) for m in bag.msgs["/clock"]] == [
        k * 1_000_000_000 // 60 for k in range(TICKS)]


@pytest.mark.slow
def test_camera_image_has_the_render_product_size(bag: Recorded) -> None:
    """The seed sets no size: IsaacCreateRenderProduct's default, 1280 x 720."""
    image, info = bag.msgs["/camera/color"][-1], bag.msgs["/camera/camera_info"][-1]
    assert (image.width, image.height, image.encoding, image.header.frame_id) == \
        (1280, 720, "rgb8", "camera")
    pixels = np.frombuffer(bytes(image.data), np.uint8).reshape(720, 1280, 3)
    assert pixels.std() > 5  # the wall, the floor: not a blank frame
    assert (info.width, info.height, k_of(info)[2], k_of(info)[5]) == (1280, 720, 639.5, 359.5)


@pytest.mark.slow
def test_scan_ranges_to_the_wall(bag: Recorded) -> None:
    """Beam 0 (+x) ends on the wall ahead at 3 − (1 + odom x − 0.064) m, every scan; the side
    walls are 3 m away (beams 90, 270); the wall behind is beyond range_max (inf)."""
    odom = {stamp(m): m.pose.pose.position.x for m in bag.msgs["/odom"]}
    for scan in bag.msgs["/scan"]:
        ahead = WALL_X - (SPAWN_X + odom[stamp(scan)] + SCAN_X)
        assert scan.ranges[0] == pytest.approx(ahead, abs=2e-3)
        assert (scan.ranges[90], scan.ranges[270]) == pytest.approx((3.0, 3.0), abs=2e-3)
        assert scan.ranges[180] == np.inf and scan.header.frame_id == "laser"
    assert bag.msgs["/scan"][0].ranges[0] == pytest.approx(2.064, abs=1e-4)


@pytest.mark.slow
def test_imu_feels_gravity(bag: Recorded) -> None:
    imu = bag.msgs["/imu"]
    assert imu[0].header.frame_id == "IMU"
    z = [m.linear_acceleration.z for m in imu if stamp(m) >= 100_000_000]
    assert np.mean(z) == pytest.approx(9.81, abs=0.02)


@pytest.mark.slow
def test_odometry_moves_under_cmd_vel(bag: Recorded) -> None:
    first, last = bag.msgs["/odom"][0], bag.msgs["/odom"][-1]
    assert (last.header.frame_id, last.child_frame_id) == ("odom", "base_footprint")
    assert first.pose.pose.position.x == 0.0
    assert last.twist.twist.linear.x == pytest.approx(DRIVEN, rel=0.02)
    assert last.pose.pose.position.x == pytest.approx(0.95 * DRIVEN, abs=0.01)
    assert abs(last.pose.pose.position.y) < 1e-6


@pytest.mark.slow
def test_hand_built_tf_tree(bag: Recorded) -> None:
    static = {(t.header.frame_id, t.child_frame_id): t.transform.translation
              for m in bag.msgs["/tf_static"] for t in m.transforms}
    dynamic = {(t.header.frame_id, t.child_frame_id) for m in bag.msgs["/tf"]
               for t in m.transforms}
    assert set(static) == STATIC and dynamic == DYNAMIC
    scan = static[("base_link", "base_scan")]
    assert (scan.x, scan.y, scan.z) == pytest.approx((SCAN_X, 0.0, 0.122))


@pytest.mark.slow
def test_ros1_types_definitions_and_header_seq(bag: Recorded) -> None:
    """ROS 1 spelling and definitions (the MD5 sums ROS 1 itself gives them), /tf as
    tf2_msgs/TFMessage as Isaac's ROS 1 bridge publishes it, latched /tf_static, and each
    topic's header seq counting from 0; headers nested in a TFMessage keep 0."""
    if bag.summary["output"]["ros"] == 2:
        assert bag.types["/camera/color"] == "sensor_msgs/msg/Image"
        assert bag.summary["output"]["because"] == "output.ros"
        return
    assert bag.types["/camera/color"] == "sensor_msgs/Image"
    assert bag.types["/tf"] == bag.types["/tf_static"] == "tf2_msgs/TFMessage"
    assert {name: bag.md5[name] for name in MD5} == MD5
    assert bag.latched == {"/tf_static"}
    for topic in ("/scan", "/odom", "/camera/color", "/imu"):
        assert [m.header.seq for m in bag.msgs[topic]] == list(range(len(bag.msgs[topic])))
    assert {t.header.seq for m in bag.msgs["/tf"] for t in m.transforms} == {0}
    assert bag.summary["topics"]["/camera/color"]["type"] == "sensor_msgs/Image"
    assert bag.summary["output"]["because"].startswith("graphs[0] builds ROS 1 bridge nodes") \
        or bag.summary["output"]["because"] == "output.format: bag"


@pytest.mark.slow
def test_scores_and_health_do_not_depend_on_the_format(bag: Recorded) -> None:
    """The same drive, scored from the ROS 1 or the ROS 2 recording: the same metrics, every
    health gate passes (rates, recorded == published, /clock monotonic, ground truth)."""
    metrics = {m["name"]: m["value"] for m in bag.summary["metrics"]}
    assert metrics["control.distance_travelled"] == pytest.approx(0.0955, abs=5e-4)
    assert metrics["control.cross_track_error.max"] < 1e-4
    assert all(h["ok"] for h in bag.summary["health"]) and len(bag.summary["health"]) == 4
    FIRST.setdefault("metrics", metrics)
    assert metrics == FIRST["metrics"]  # identical to the format the fixture ran first


FIRST: dict[str, Any] = {}  # the metrics of the first format run in this session


@pytest.mark.slow
def test_report_keyframes_read_the_recording(bag: Recorded) -> None:
    """The report's camera keyframes decode the recorded image, whatever the format."""
    found = nearest_images(bag.run_dir / "bag", [500_000_000])[500_000_000]
    assert [(topic, t) for topic, t, _ in found] == [("/camera/color", 500_000_000)]
    pixels = found[0][2]
    image = bag.msgs["/camera/color"][30]
    full = np.frombuffer(bytes(image.data), np.uint8).reshape(720, 1280, 3)
    assert np.array_equal(pixels, full[::4, ::4])  # shrunk to 320 wide


@pytest.mark.parametrize("bag", ["ros1-bag"], indirect=True)  # on the ROS 1 bag alone
@pytest.mark.slow
def test_replay_diff_and_bless_a_ros1_bag(bag: Recorded, tmp_path: Path) -> None:
    """``srr replay`` plays the ROS 1 recording into the scripted teleop again and records
    the same bytes, per topic; ``srr diff`` finds the two identical; blessing the run keeps a
    ``ros1``-profile reference recording that reads back."""
    assert bag.summary["output"] == {"ros": 1, "format": "bag", "because": "output.format: bag"}
    out = tmp_path / "replay"
    replayed = api.replay(bag.run_dir, out=out).summary
    assert sorted((out / "bag").iterdir()) == [out / "bag" / "bag.bag"]
    assert replayed["output"]["ros"] == 1
    assert {t: v["sha256"] for t, v in replayed["topics"].items()} == \
        {t: v["sha256"] for t, v in bag.summary["topics"].items()}
    diff = api.diff_runs(bag.run_dir, out)
    assert diff.equal and {t.status for t in diff.topics} == {"identical"}
    baseline = api.bless(bag.run_dir, "ROS 1 reference", baselines=tmp_path / "baselines",
                         allow_failing=True)  # a short run: its route's goal not reached
    reference = baseline.with_suffix(".mcap")
    with reference.open("rb") as f:
        assert make_reader(f).get_header().profile == "ros1"
    ref = load_frames(reference)
    assert len(ref.odom) == 2 * TICKS and len(ref.gt_poses) == TICKS and len(ref.tf) == 6


@pytest.mark.slow
def test_ros1_runs_are_deterministic(tmp_path: Path) -> None:
    """Two runs of the seed's scene recorded as ROS 1 give identical per-topic digests."""
    if not rendering_available():
        pytest.skip("no OpenGL for the seed's camera (MUJOCO_GL=egl or osmesa)")
    sc = api.load(SCENARIO, duration=0.1)
    rep = api.run_repeat(sc, 2, source=str(SCENARIO), out=tmp_path)
    assert rep.identical and rep.differing_topics == ()
    summary = rep.runs[0].summary
    assert summary["output"]["ros"] == 1 and summary["topics"]["/clock"]["count"] == 6
    assert rep.runs[0].summary["digest"] == rep.runs[1].summary["digest"]


def test_verbatim_add_tf_sends_the_whole_tree_to_tf() -> None:
    """Without the call site's fix the seed's add_tf leaves every TF node on its default
    topic: the static links would be republished on /tf each tick, as in Isaac Sim."""
    sc = load_scenario(SCENARIO, [("graphs.TurtleBot3Seed.params.set_tf_topics", False)])
    sim = Simulation(sc, source=str(SCENARIO))
    with sim.stage:
        topics = {name: og.Controller.get(f"/World/TurtleBot3SeedGraph/{name}.inputs:topicName")
                  for name in ("PubTFBaseStatic", "PubTFStatic", "PubTFWheels")}
    sim.close()
    assert set(topics.values()) == {"tf"}
