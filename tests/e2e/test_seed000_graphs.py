"""Seed 000's graph helpers, verbatim, as a scenario's ``graphs:`` builder
(``seed000_graphs.py`` / ``.yaml``), with the real node types: ``srr run`` records the seed's
topics and the bag, read back with mcap + mcap-ros2-support, holds what the seed publishes.

The robot (a scenario field: ``robots[0].model``) stands 1 m from the +x wall of a 6 x 6 m
room, facing it, and drives forward at 0.2 m/s (scripted teleop) for the 1 s run.
"""

from __future__ import annotations

import subprocess
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness import graph as og
from harness.engine import Simulation
from harness.scenario import load_scenario
from tests.conftest import ROOT
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


def stamp(msg: Any) -> int:
    return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[Any]]:
    if not rendering_available():
        pytest.skip("no OpenGL for the seed's camera (MUJOCO_GL=egl or osmesa)")
    out = tmp_path_factory.mktemp("seed000")
    done = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(SCENARIO), "--out",
                           str(out), "-q"], env=gl_env(), cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 1, done.stderr  # UNSCORED: recorded, nothing to score
    by_topic: dict[str, list[Any]] = defaultdict(list)
    for topic, _, _, msg in decoded(out):
        by_topic[topic].append(msg)
    return by_topic


def test_the_seed_topics_are_recorded(bag: dict[str, list[Any]]) -> None:
    assert {t: len(m) for t, m in bag.items()} == {
        "/clock": TICKS, "/camera/color": TICKS, "/camera/camera_info": TICKS,
        "/scan": TICKS, "/imu": TICKS, "/cmd_vel": 10,
        # add_odometry wires PubComputeOdometry's execIn from the tick and from ComputeOdometry
        "/odom": 2 * TICKS,
        "/tf": 2 * TICKS, "/tf_static": 2}


def test_camera_image_has_the_render_product_size(bag: dict[str, list[Any]]) -> None:
    """The seed sets no size: IsaacCreateRenderProduct's default, 1280 x 720."""
    image, info = bag["/camera/color"][-1], bag["/camera/camera_info"][-1]
    assert (image.width, image.height, image.encoding, image.header.frame_id) == \
        (1280, 720, "rgb8", "camera")
    pixels = np.frombuffer(bytes(image.data), np.uint8).reshape(720, 1280, 3)
    assert pixels.std() > 5  # the wall, the floor: not a blank frame
    assert (info.width, info.height, info.k[2], info.k[5]) == (1280, 720, 639.5, 359.5)


def test_scan_ranges_to_the_wall(bag: dict[str, list[Any]]) -> None:
    """Beam 0 (+x) ends on the wall ahead at 3 − (1 + odom x − 0.064) m, every scan; the side
    walls are 3 m away (beams 90, 270); the wall behind is beyond range_max (inf)."""
    odom = {stamp(m): m.pose.pose.position.x for m in bag["/odom"]}
    for scan in bag["/scan"]:
        ahead = WALL_X - (SPAWN_X + odom[stamp(scan)] + SCAN_X)
        assert scan.ranges[0] == pytest.approx(ahead, abs=2e-3)
        assert (scan.ranges[90], scan.ranges[270]) == pytest.approx((3.0, 3.0), abs=2e-3)
        assert scan.ranges[180] == np.inf and scan.header.frame_id == "laser"
    assert bag["/scan"][0].ranges[0] == pytest.approx(2.064, abs=1e-4)


def test_imu_feels_gravity(bag: dict[str, list[Any]]) -> None:
    imu = bag["/imu"]
    assert imu[0].header.frame_id == "IMU"
    z = [m.linear_acceleration.z for m in imu if stamp(m) >= 100_000_000]
    assert np.mean(z) == pytest.approx(9.81, abs=0.02)


def test_odometry_moves_under_cmd_vel(bag: dict[str, list[Any]]) -> None:
    first, last = bag["/odom"][0], bag["/odom"][-1]
    assert (last.header.frame_id, last.child_frame_id) == ("odom", "base_footprint")
    assert first.pose.pose.position.x == 0.0
    assert last.twist.twist.linear.x == pytest.approx(DRIVEN, rel=0.02)
    assert last.pose.pose.position.x == pytest.approx(0.95 * DRIVEN, abs=0.01)
    assert abs(last.pose.pose.position.y) < 1e-6


def test_hand_built_tf_tree(bag: dict[str, list[Any]]) -> None:
    static = {(t.header.frame_id, t.child_frame_id): t.transform.translation
              for m in bag["/tf_static"] for t in m.transforms}
    dynamic = {(t.header.frame_id, t.child_frame_id) for m in bag["/tf"] for t in m.transforms}
    assert set(static) == STATIC and dynamic == DYNAMIC
    scan = static[("base_link", "base_scan")]
    assert (scan.x, scan.y, scan.z) == pytest.approx((SCAN_X, 0.0, 0.122))


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
