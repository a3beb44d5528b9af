"""Control metrics on hand-built poses with known answers."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from harness.metrics.control import (
    clearance,
    cmd_vel_tracking,
    control_metrics,
    distance_travelled,
    goal,
    odom_drift,
    path_tracking,
    route_distance,
)
from tests.metrics.helpers import gt_rows, make_frames, t_ns


def by_name(results: list) -> dict:
    return {r.name: r for r in results}


def poses(x, y, yaw=0.0, ticks=None) -> pd.DataFrame:
    x = np.asarray(x, dtype=float)
    ticks = np.arange(x.size) if ticks is None else ticks
    return pd.DataFrame({"t_ns": t_ns(ticks), "x": x, "y": np.asarray(y, dtype=float),
                         "yaw": np.broadcast_to(yaw, x.shape).astype(float)})


def test_cross_track_of_a_straight_route_with_known_offsets() -> None:
    offsets = np.array([0.1, -0.2, 0.3, 0.0, -0.4])
    p = poses([1.0, 2.0, 3.0, 4.0, 5.0], offsets)
    r = by_name(path_tracking(p, [(0.0, 0.0), (10.0, 0.0)]))
    assert r["control.cross_track_error.mean"].value == pytest.approx(0.2)
    assert r["control.cross_track_error.rms"].value == pytest.approx(
        math.sqrt((0.01 + 0.04 + 0.09 + 0.16) / 5))
    assert r["control.cross_track_error.max"].value == pytest.approx(0.4)
    assert r["control.heading_error.max"].value == pytest.approx(0.0)
    assert r["control.cross_track_error.rms"].unit == "m"
    assert r["control.cross_track_error.rms"].direction == "lower"


def test_cross_track_uses_the_closest_segment_and_its_tangent() -> None:
    route = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)]
    d, tangent = route_distance(np.array([[5.0, 1.0], [11.0, 5.0], [12.0, -1.0],
                                          [-3.0, 4.0]]), route)
    assert d == pytest.approx([1.0, 1.0, math.sqrt(5.0), 5.0])
    assert tangent == pytest.approx([0.0, math.pi / 2, 0.0, 0.0])
    p = poses([5.0, 11.0], [1.0, 5.0], yaw=[0.1, math.pi / 2 - 0.3])
    r = by_name(path_tracking(p, route))
    assert r["control.heading_error.mean"].value == pytest.approx(0.2)
    assert r["control.heading_error.max"].value == pytest.approx(0.3)


def test_heading_error_wraps_around() -> None:
    r = by_name(path_tracking(poses([1.0], [0.0], yaw=[math.pi - 0.1]),
                              [(0.0, 0.0), (-10.0, 0.0)]))  # route heads -X (tangent π)
    assert r["control.heading_error.max"].value == pytest.approx(0.1)


def test_goal_reached_time_and_distance() -> None:
    x = np.linspace(0.0, 10.0, 101)  # 0.1 m per tick
    r = by_name(goal(poses(x, np.zeros(101)), (10.0, 0.0), tolerance=0.5))
    assert r["control.goal_reached"].value == 1.0
    assert r["control.time_to_goal"].value == pytest.approx(int(t_ns(95)) / 1e9)
    assert r["control.goal_distance_final"].value == pytest.approx(0.0)
    miss = by_name(goal(poses(x[:50], np.zeros(50)), (10.0, 0.0), tolerance=0.5))
    assert miss["control.goal_reached"].value == 0.0
    assert miss["control.time_to_goal"].value is None
    assert "never" in miss["control.time_to_goal"].detail
    assert by_name(distance_travelled(poses(x, np.zeros(101))))[
        "control.distance_travelled"].value == pytest.approx(10.0)


def test_collisions_are_contact_episodes_and_clearance_is_the_minimum() -> None:
    ticks = np.arange(0, 600)
    robot = poses(np.zeros(600), np.zeros(600), ticks=ticks)
    # worker 0 closes in to 1.0 m (clearance -0.3) during 2-3 s and 6-7 s; worker 1 stays far
    wx = np.full(600, 5.0)
    wx[(ticks >= 120) & (ticks < 180)] = 1.0
    wx[(ticks >= 360) & (ticks < 420)] = 1.0
    workers = pd.concat([gt_rows("character_0", ticks, wx, np.zeros(600)),
                         gt_rows("character_1", ticks, np.full(600, 9.0), np.zeros(600))])
    r = by_name(clearance(robot, workers, robot_radius=1.0, worker_radius=0.3))
    assert r["control.collisions"].value == 2
    assert r["control.collisions"].windows == ((2.0, 3.0), (6.0, 7.0))
    assert r["control.min_clearance"].value == pytest.approx(-0.3)
    assert "character_0" in r["control.min_clearance"].detail
    far = by_name(clearance(robot, workers, robot_radius=0.5, worker_radius=0.3))
    assert far["control.collisions"].value == 0
    assert far["control.min_clearance"].value == pytest.approx(0.2)


def test_cmd_vel_tracking_holds_the_last_command() -> None:
    cmd = pd.DataFrame({"t_ns": [int(t_ns(10)), int(t_ns(30))], "vx": [1.0, 2.0],
                        "wz": [0.0, 0.5]})
    ticks = np.arange(0, 40)
    odom = pd.DataFrame({"t_ns": t_ns(ticks), "vx": np.full(40, 1.5), "wz": np.zeros(40)})
    r = by_name(cmd_vel_tracking(cmd, odom))
    # ticks 10..29 hold 1.0 (error -0.5), 30..39 hold 2.0 (error 0.5); 0..9 precede commands
    assert r["control.cmd_vel_tracking.vx_rms"].value == pytest.approx(0.5)
    assert r["control.cmd_vel_tracking.wz_rms"].value == pytest.approx(
        math.sqrt(10 * 0.25 / 30))
    assert "30 odometry samples" in r["control.cmd_vel_tracking.vx_rms"].detail


def test_odom_drift_final_and_max() -> None:
    ticks = np.arange(0, 10)
    gt = poses(np.arange(10.0), np.zeros(10), ticks=ticks)
    err = np.array([0, 0.1, 0.2, 0.5, 0.3, 0.2, 0.2, 0.2, 0.2, 0.25])
    odom = poses(np.arange(10.0), err, ticks=ticks)
    r = by_name(odom_drift(odom, gt))
    assert r["control.odom_drift.final"].value == pytest.approx(0.25)
    assert r["control.odom_drift.max"].value == pytest.approx(0.5)


def test_control_metrics_on_frames_prefers_ground_truth() -> None:
    ticks = np.arange(0, 120)
    x = -12.0 + ticks * 0.05
    gt = gt_rows("forklift", ticks, x, np.full(120, -3.0), yaw=math.pi)  # faces -X
    odom = pd.DataFrame({"t_ns": t_ns(ticks), "topic": "/odom", "frame": "world", "x": x,
                         "y": np.full(120, -2.9), "yaw": 0.0, "vx": 3.0, "wz": 0.0})
    cmd = pd.DataFrame({"t_ns": [0], "topic": ["/cmd_vel"], "vx": [3.0], "wz": [0.0]})
    frames = make_frames(gt_poses=gt, odom=odom, cmd_vel=cmd)
    route = [(-12.0, -3.0), (0.0, -3.0)]
    r = by_name(control_metrics(frames, robot="forklift", route=route, front_yaw=math.pi))
    assert r["control.cross_track_error.max"].value == pytest.approx(0.0)
    assert r["control.heading_error.max"].value == pytest.approx(0.0, abs=1e-12)
    assert r["control.odom_drift.max"].value == pytest.approx(0.1)
    assert r["control.cmd_vel_tracking.vx_rms"].value == pytest.approx(0.0)
    assert r["control.collisions"].value is None  # no workers in this run
    # without ground truth the path metrics fall back to odometry and say so
    no_gt = by_name(control_metrics(make_frames(odom=odom, cmd_vel=cmd), robot="forklift",
                                    route=route))
    assert no_gt["control.cross_track_error.max"].value == pytest.approx(0.1)
    assert "from odometry" in no_gt["control.cross_track_error.max"].detail
    assert no_gt["control.odom_drift.max"].value is None
