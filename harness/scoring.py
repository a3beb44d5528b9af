"""Score a recorded run: the scenario's ``scoring:`` block → metric functions and health gates.

This is the only place that knows which metric family reads which part of the scenario; the
metric functions themselves stay pure (frames in, results out).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.bus import resolve_topic
from harness.camera_topics import (
    compressed_streams,
    fixed_camera,
    robot_camera,
    unrecorded_topics,
)
from harness.errors import ScenarioError
from harness.frames import Frames, load_frames
from harness.metrics import (
    HealthResult,
    MetricResult,
    OutputSpec,
    Tripwire,
    control_metrics,
    health_gates,
    perception_metrics,
    safety_metrics,
)
from harness.scenario import ControlScoring, RobotSpec, Scenario
from harness.sut.zones import points_in_polygon

__all__ = ["ROBOT_RADIUS", "Scores", "check_scoring", "expected_rates", "odom_topic",
           "robot_radius", "scenario_frames", "score_frames", "score_run"]

# Footprint circle radius per model (half the diagonal of the chassis), for clearance and
# collisions against workers; a model file's is its ``footprint_radius``.
ROBOT_RADIUS = {"forklift": 1.23, "turtlebot3_waffle_pi": 0.21}


def robot_radius(robot: RobotSpec) -> float:
    """The robot's footprint circle radius (m)."""
    model = robot.model_file
    return model.footprint_radius if model is not None else ROBOT_RADIUS[robot.model_name]


@dataclass(frozen=True)
class Scores:
    metrics: tuple[MetricResult, ...]
    health: tuple[HealthResult, ...]


def expected_rates(sc: Scenario) -> dict[str, float]:
    """Topic → expected Hz: what the configuration publishes at a fixed rate, plus the
    scenario's own ``scoring.health.expected_rates``. A sensor is expected at the rate it
    asks for (its ``fps``), not at the rate the tick lets it publish: a rate the tick cannot
    give is refused before the run or warned about (:func:`harness.scenario.rate_warnings`),
    and the gate does not lower its bar to what the run delivered."""
    hz = sc.physics.tick_hz
    rates: dict[str, float] = {}
    if sc.clock.enabled:
        rates[resolve_topic(sc.clock.clock_topic)] = float(hz)
    for robot in sc.robots:
        if not robot.enabled:
            continue
        if robot.odometry.enabled:
            rates[odom_topic(robot)] = float(hz)
        lidar, imu = robot.sensors.lidar, robot.sensors.imu
        if lidar is not None and lidar.enabled and lidar.graph:
            rates[resolve_topic(lidar.topic, robot.ns)] = float(lidar.fps)
        if imu is not None and imu.enabled and imu.graph:
            rates[resolve_topic(imu.topic, robot.ns)] = float(imu.fps)
        camera = robot_camera(sc, robot)
        if camera is not None:
            for cs in compressed_streams(camera):
                rates[cs.topic] = float(camera.fps)
    unrecorded = unrecorded_topics(sc)
    for cam in sc.cameras:
        if not cam.enabled:
            continue
        suffix = {"rgb": "rgb", "depth": "depth", "pointcloud": "pointcloud",
                  "camera_info": "camera_info"}
        for out in cam.outputs:
            topic = resolve_topic(f"{cam.name}_{suffix[out]}")
            if topic not in unrecorded:
                rates[topic] = float(cam.fps)
        for cs in compressed_streams(fixed_camera(sc, cam)):
            rates[cs.topic] = float(cam.fps)
    for topic, value in sc.scoring.health.expected_rates.items():
        rates[resolve_topic(topic)] = value
    return rates


def within_area(frames: Frames, area: Sequence[Sequence[float]]) -> Frames:
    """The frames with ground-truth characters and tracks outside ``area`` left out (robots'
    ground truth is kept: control and safety scoring need it wherever the robot is)."""
    poly = np.asarray(area, dtype=np.float64)
    g = frames.gt_poses
    is_char = g["name"].str.startswith("character_").to_numpy()
    inside = points_in_polygon(g[["x", "y"]].to_numpy(np.float64), poly)
    t = frames.tracks
    t_inside = points_in_polygon(t[["x", "y"]].to_numpy(np.float64), poly)
    return dataclasses.replace(frames, gt_poses=g[~is_char | inside].reset_index(drop=True),
                               tracks=t[t_inside].reset_index(drop=True))


def _gt_names(sc: Scenario) -> list[str]:
    names = [r.name for r in sc.robots if r.enabled]
    # Workers are published by index, as the seed's /gt/character_<i>/tf, whatever their name.
    names += [f"character_{i}" for i, w in enumerate(sc.workers) if w.enabled]
    return names


def odom_topic(robot: RobotSpec) -> str:
    """The robot's odometry topic, resolved in its namespace."""
    return resolve_topic(robot.odometry.odom_topic, robot.ns)


def _control_fields(sc: Scenario) -> list[tuple[str, ControlScoring]]:
    """(field path, block) of every enabled control block, in either form."""
    c = sc.scoring.control
    if isinstance(c, ControlScoring):
        return [("scoring.control", c)] if c.enabled else []
    return [(f"scoring.control[{i}]", b) for i, b in enumerate(c or ()) if b.enabled]


def check_scoring(sc: Scenario, *, srr_gt: bool, source: str = "<scenario>") -> None:
    """Refuse a ``scoring:`` block that cannot be scored, before anything runs."""
    s = sc.scoring
    file = sc.file_for("scoring", source)
    need_gt = bool(s.control_blocks) or any(block is not None and block.enabled
                                            for block in (s.perception, s.safety))
    if s.record_only and need_gt:
        scored = next(n for n, on in (("control", bool(s.control_blocks)), ("perception",
                      s.perception is not None and s.perception.enabled),
                      ("safety", s.safety is not None and s.safety.enabled)) if on)
        raise ScenarioError(file, "scoring.record_only", f"a record-only scenario scores "
                            f"nothing, and scoring.{scored} is enabled: remove one of them")
    if need_gt and not srr_gt:
        raise ScenarioError(file, "scoring", "scoring needs ground truth: set srr_gt: true "
                            "or run with --srr-gt")
    robots = [r.name for r in sc.robots if r.enabled]
    for where, block in _control_fields(sc):
        if block.route not in sc.routes:
            raise ScenarioError(file, f"{where}.route", f"no route named {block.route!r} "
                                f"(routes: {', '.join(sorted(sc.routes)) or 'none'})")
        if block.robot not in robots:
            raise ScenarioError(file, f"{where}.robot", f"no enabled robot named "
                                f"{block.robot!r} (robots: {', '.join(robots) or 'none'})")
    if s.safety is not None and s.safety.enabled:
        if sc.zones.trailer_tripwire is None or len(sc.zones.loading_roi) < 3:
            raise ScenarioError(sc.file_for("zones", source), "zones", "safety scoring needs "
                                "zones.loading_roi and zones.trailer_tripwire")
        if s.safety.robot not in robots:
            raise ScenarioError(file, "scoring.safety.robot", f"no enabled robot named "
                                f"{s.safety.robot!r} (robots: {', '.join(robots) or 'none'})")


def score_frames(sc: Scenario, frames: Frames, *, srr_gt: bool,
                 published: Mapping[str, int] | None = None,
                 recorded: Mapping[str, int] | None = None,
                 duration_s: float | None = None, source: str = "<scenario>") -> Scores:
    """Metrics and health gates for one run's frames."""
    check_scoring(sc, srr_gt=srr_gt, source=source)
    s = sc.scoring
    metrics: list[MetricResult] = []
    workers = [w for w in sc.workers if w.enabled]
    radii = {r.name: robot_radius(r) for r in sc.robots if r.enabled}
    for block in s.control_blocks:
        robot = sc.robot(block.robot)
        metrics += control_metrics(
            frames, robot=robot.name, route=sc.routes[block.route].waypoints,
            goal_tolerance=block.goal_tolerance,
            robot_radius=robot_radius(robot),
            worker_radius=workers[0].radius if workers else 0.25,
            odom_topic=odom_topic(robot),
            cmd_topic=resolve_topic(robot.control_spec.cmd_vel_topic, robot.ns),
            other_robots=radii, prefix=s.control_prefix(robot.name))
    if s.perception is not None and s.perception.enabled:
        topic = s.perception.marker_topics[0] if s.perception.marker_topics else None
        scored = within_area(frames, s.perception.area) if s.perception.area else frames
        for cls in s.perception.classes:
            metrics += perception_metrics(scored, cls=cls, gate=s.perception.gate,
                                          topic=resolve_topic(topic) if topic else None)
    if s.safety is not None and s.safety.enabled:
        wire = sc.zones.trailer_tripwire
        assert wire is not None  # check_scoring
        metrics += safety_metrics(frames, tripwire=Tripwire(wire.a, wire.b, wire.inside),
                                  roi=sc.zones.loading_roi, robot=s.safety.robot,
                                  min_window_s=s.safety.min_window_s)
    outputs = {resolve_topic(t): OutputSpec(min_count=1, first_within_s=silence,
                                            max_silence_s=silence)
               for t, silence in s.health.sut_outputs.items()}
    health = health_gates(
        frames, expected_hz=expected_rates(sc), recorded=recorded, published=published,
        gt_expected=_gt_names(sc) if srr_gt else None,
        robots={r.name: odom_topic(r) for r in sc.robots if r.enabled and r.odometry.enabled},
        outputs=outputs, duration_s=duration_s, min_fraction=s.health.rate_fraction)
    return Scores(tuple(metrics), tuple(health))


def scenario_frames(sc: Scenario | None, bag_dir: Path) -> Frames:
    """The frames of a bag as ``sc``'s scoring reads them (its marker and muted topics; the
    defaults without a scenario)."""
    markers = None
    muted = "/safety/is_muted"
    if sc is not None:
        p, s = sc.scoring.perception, sc.scoring.safety
        if p is not None and p.marker_topics:
            markers = [resolve_topic(t) for t in p.marker_topics]
        if s is not None:
            muted = resolve_topic(s.muted_topic)
    return load_frames(bag_dir, marker_topics=markers, muted_topic=muted)


def score_run(sc: Scenario, bag_dir: Path, *, srr_gt: bool,
              published: Mapping[str, int] | None = None,
              recorded: Mapping[str, int] | None = None, duration_s: float | None = None,
              source: str = "<scenario>") -> Scores:
    return score_frames(sc, scenario_frames(sc, bag_dir), srr_gt=srr_gt, published=published,
                        recorded=recorded, duration_s=duration_s, source=source)
