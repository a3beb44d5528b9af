"""Sensors on robots from model files measure the scene's known geometry.

A 6 x 6 m room (inner wall faces at x, y = ±3 m). The URDF diff-drive robot stands at
x = 1 m facing +x, its lidar on ``lidar_link`` (straight above base_footprint) moved by an
offset; the MJCF pallet truck's depth camera sits on the file's ``front_camera_mount`` site
(1.05 m ahead of the chassis origin). Each reads the wall where the geometry puts it, the TF
tree places each sensor frame where the sensor is, and an offset IMU feels gravity along the
axis its roll puts upward.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from harness import api
from harness.errors import ScenarioError
from harness.scenario import load_scenario
from tests.conftest import SCENARIOS
from tests.e2e.bagread import decoded
from tests.e2e.test_turtlebot3 import rendering_available

MODELS = SCENARIOS / "models"
WALL = 3.0
OFFSET = (0.05, 0.0, 0.02)


def scene(tmp: Path, robot: dict[str, Any]) -> Path:
    path = tmp / "scene.yaml"
    path.write_text(yaml.safe_dump({
        "format_version": 1, "name": "sensors", "duration": 0.5, "seed": 1,
        "world": {"size": [6.0, 6.0], "wall_height": 2.5, "shelves": [],
                  "dock": {"enabled": False}},
        "robots": [robot]}))
    return path


def diffbot(sensors: dict[str, Any]) -> dict[str, Any]:
    return {"name": "bot", "spawn": {"position": [1.0, 0.0, 0.0]},
            "model": {"urdf": str(MODELS / "srr_diffbot" / "urdf" / "srr_diffbot.urdf"),
                      "package_paths": [str(MODELS)], "frictionless_links": ["caster_link"]},
            "control": {"enabled": False}, "sensors": sensors}


def record(path: Path, out: Path) -> dict[str, list[Any]]:
    api.run_scenario(load_scenario(path), source=str(path), out=out)
    by_topic: dict[str, list[Any]] = defaultdict(list)
    for topic, _, _, msg in decoded(out):
        by_topic[topic].append(msg)
    return by_topic


def static_tf(bag: dict[str, list[Any]]) -> dict[tuple[str, str], Any]:
    return {(t.header.frame_id, t.child_frame_id): t.transform
            for msg in bag["/tf_static"] for t in msg.transforms}


@pytest.mark.slow
def test_offset_lidar_and_imu_on_a_urdf_robot(tmp_path: Path) -> None:
    path = scene(tmp_path, diffbot({
        "lidar": {"link": "lidar_link", "frame_id": "scan_offset", "beams": 360,
                  "range_max": 8.0, "fps": 10,
                  "offset": {"position": list(OFFSET), "rpy_deg": [0, 0, 90]}},
        "imu": {"link": "base_link", "frame_id": "imu_rolled", "fps": 30,
                "offset": {"rpy_deg": [90, 0, 0]}}}))
    bag = record(path, tmp_path / "run")
    scan = bag["/scan"][-1]
    assert scan.header.frame_id == "scan_offset"
    ranges = np.asarray(scan.ranges)
    # beam 0 looks along the offset frame's +x = the world's +y: the wall 3 m away
    assert ranges[0] == pytest.approx(WALL, abs=0.01)
    # beam at -90° looks along the world's +x, from 1 + 0.05 m
    assert ranges[270] == pytest.approx(WALL - 1.0 - OFFSET[0], abs=0.01)
    assert ranges[90] == pytest.approx(WALL + 1.0 + OFFSET[0], abs=0.01)  # the -x wall
    tf = static_tf(bag)
    edge = tf[("lidar_link", "scan_offset")]
    assert (edge.translation.x, edge.translation.y, edge.translation.z) == pytest.approx(OFFSET)
    q = edge.rotation
    assert (q.x, q.y, q.z, q.w) == pytest.approx((0, 0, np.sqrt(0.5), np.sqrt(0.5)), abs=1e-9)
    assert ("base_link", "imu_rolled") in tf
    acc = bag["/imu"][-1].linear_acceleration
    # rolled 90° about x: the sensor's +y points up, where the specific force of gravity is
    assert (acc.x, acc.y, acc.z) == pytest.approx((0.0, 9.81, 0.0), abs=0.05)


@pytest.mark.skipif(not rendering_available(), reason="no OpenGL (MUJOCO_GL=egl or osmesa)")
@pytest.mark.slow
def test_depth_camera_on_an_mjcf_site(tmp_path: Path) -> None:
    spawn_x = -1.0
    path = scene(tmp_path, {
        "name": "truck", "spawn": {"position": [spawn_x, 0.0, 0.0]},
        "model": {"mjcf": str(MODELS / "pallet_truck" / "pallet_truck.xml"),
                  "drive": "swivel_drive"},
        "control": {"enabled": False},
        "sensors": {"camera": {"site": "front_camera_mount", "frame_id": "front_optical",
                               "resolution": [64, 48], "fps": 10, "topic": "front/rgb",
                               "info_topic": "front/info", "depth_topic": "front/depth",
                               "offset": {"position": [0.1, 0.0, 0.0]}}}})
    bag = record(path, tmp_path / "run")
    depth = bag["/front/depth"][-1]
    assert (depth.width, depth.height, depth.encoding, depth.header.frame_id) == \
        (64, 48, "32FC1", "front_optical")
    image = np.frombuffer(bytes(depth.data), np.float32).reshape(48, 64)
    # the site is 1.05 m ahead of the chassis origin, the offset 0.1 m more: the +x wall
    expected = WALL - (spawn_x + 1.05 + 0.1)
    assert float(image[24, 32]) == pytest.approx(expected, abs=0.01)
    edge = static_tf(bag)[("chassis", "front_optical")]
    assert (edge.translation.x, edge.translation.y, edge.translation.z) == \
        pytest.approx((1.15, 0.0, 1.0), abs=1e-9)


@pytest.mark.parametrize(("sensors", "field", "words"), [
    ({"lidar": {"link": "lidar_link", "frame_id": "lidar_link",
                "offset": {"position": [0.1, 0, 0]}}},
     "robots[0].sensors.lidar.frame_id",
     ["the lidar sits off the origin of link 'lidar_link'", "set frame_id to another name"]),
    ({"lidar": {"link": "lidar_link", "frame_id": "lidar_link", "site": "lidar_mount"}},
     "robots[0].sensors.lidar.site", ["srr_diffbot.urdf has no site 'lidar_mount'"]),
])
def test_bad_sensor_mounts_name_the_field(tmp_path: Path, sensors: dict[str, Any], field: str,
                                          words: list[str]) -> None:
    path = scene(tmp_path, diffbot(sensors))
    with pytest.raises(ScenarioError) as err:
        api.validate(load_scenario(path), source=str(path))
    assert (err.value.file, err.value.field) == (str(path), field)
    for word in words:
        assert word in err.value.message
