"""Score a recorded run: the scenario's ``scoring:`` block → metric functions and health gates.

This is the only place that knows which metric family reads which part of the scenario; the
metric functions themselves stay pure (frames in, results out).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from harness.bus import resolve_topic
from harness.camera_topics import (
    compressed_streams,
    fixed_camera,
    robot_camera,
    unrecorded_topics,
)
from harness.errors import ScenarioError
from harness.metrics.specs import as_bool, held, spec_metric, tick_grid
from harness.metrics.types import HealthResult, MetricResult
from harness.scenario import ControlScoring, RobotSpec, Scenario
from harness.scenario.checks import spec_context
from harness.scenario.specs import Formula, SignalRef, parse_formula
from harness.sut.zones import points_in_polygon

if TYPE_CHECKING:
    from harness.frames import Frames

__all__ = ["GT_SIGNALS", "ROBOT_RADIUS", "Scores", "check_scoring", "expected_rates",
           "odom_topic", "robot_radius", "scenario_frames", "score_frames", "score_run",
           "spec_fields", "spec_metrics"]

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
    specs = [(i, spec) for i, spec in enumerate(sc.specs) if spec.enabled]
    if s.record_only and specs:
        raise ScenarioError(sc.file_for("specs", source), f"specs[{specs[0][0]}]",
                            "a record-only scenario scores nothing, and this spec is "
                            "enabled: remove one of them (or disable the spec)")
    if specs and not srr_gt:
        ctx = spec_context(sc)
        for i, spec in specs:
            gt = [r.text for r in parse_formula(spec.formula, ctx).signals
                  if r.name in GT_SIGNALS]
            if gt:
                raise ScenarioError(sc.file_for("specs", source), f"specs[{i}].formula",
                                    f"spec {spec.name!r}: {gt[0]} needs ground truth: set "
                                    "srr_gt: true or run with --srr-gt")
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
    # imported here, as in scenario_frames and _signal: the metrics (pandas, SciPy) are needed
    # once a run has been recorded, and check_scoring, used before a run starts, needs none
    from harness.metrics import (
        OutputSpec,
        Tripwire,
        control_metrics,
        health_gates,
        perception_metrics,
        safety_metrics,
    )

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
    metrics += spec_metrics(sc, frames)
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
    from harness.frames import load_frames  # the bag readers and pandas (see score_frames)

    markers = None
    muted = "/safety/is_muted"
    if sc is not None:
        p, s = sc.scoring.perception, sc.scoring.safety
        if p is not None and p.marker_topics:
            markers = [resolve_topic(t) for t in p.marker_topics]
        if s is not None:
            muted = resolve_topic(s.muted_topic)
    return load_frames(bag_dir, marker_topics=markers, muted_topic=muted,
                       fields=spec_fields(sc) if sc is not None else ())


def score_run(sc: Scenario, bag_dir: Path, *, srr_gt: bool,
              published: Mapping[str, int] | None = None,
              recorded: Mapping[str, int] | None = None, duration_s: float | None = None,
              source: str = "<scenario>") -> Scores:
    return score_frames(sc, scenario_frames(sc, bag_dir), srr_gt=srr_gt, published=published,
                        recorded=recorded, duration_s=duration_s, source=source)


# --------------------------------------------------------------------------- specs

#: Signals computed from ground truth (``/gt/<name>/tf``): a spec using one needs srr_gt.
GT_SIGNALS = frozenset({"clearance", "distance", "speed", "in_zone", "tracking_error"})
#: Where the ``alarm`` signal is read (the reference safety monitor's ``alarm_topic``).
ALARM_TOPIC = "/safety/alarm"


def _formulas(sc: Scenario) -> list[tuple[str, bool, Formula]]:
    """(name, required, parsed formula) of every enabled spec."""
    if not sc.specs:
        return []
    ctx = spec_context(sc)
    return [(spec.name, spec.required, parse_formula(spec.formula, ctx))
            for spec in sc.specs if spec.enabled]


def _topic_field(ref: SignalRef) -> tuple[str, str]:
    return resolve_topic(ref.args[0]), ref.args[1]


def _bool_topic(sc: Scenario, ref: SignalRef) -> str:
    if ref.name == "alarm":
        return ALARM_TOPIC
    s = sc.scoring.safety
    return resolve_topic(s.muted_topic if s is not None else "/safety/is_muted")


def spec_fields(sc: Scenario) -> list[tuple[str, str]]:
    """(topic, field path) of every ``topic(...)`` and safety signal the specs read."""
    out: list[tuple[str, str]] = []
    for _, _, f in _formulas(sc):
        for ref in f.signals:
            key = _topic_field(ref) if ref.name == "topic" else \
                (_bool_topic(sc, ref), "data") if ref.name in ("alarm", "muted") else None
            if key is not None and key not in out:
                out.append(key)
    return out


def _gt_name(sc: Scenario, name: str) -> tuple[str, float]:
    """The ground-truth name (``/gt/<name>/tf``) and footprint radius of a robot or a
    worker named in a formula."""
    for r in sc.robots:
        if r.enabled and r.name == name:
            return r.name, robot_radius(r)
    for i, w in enumerate(sc.workers):
        if w.enabled and name in (sc.worker_name(i), f"character_{i}"):
            return f"character_{i}", w.radius
    raise KeyError(name)  # pragma: no cover - parse_formula checked the name


def _signal(sc: Scenario, frames: Frames, ref: SignalRef, grid: np.ndarray
            ) -> tuple[np.ndarray, str]:
    """A signal's values on ``grid`` (NaN where undefined), or why it has none at all."""
    from harness.metrics.control import route_distance  # see score_frames
    from harness.metrics.safety import Tripwire

    def xy(name: str) -> tuple[np.ndarray, str]:
        gt_name, _ = _gt_name(sc, name)
        g = frames.gt(gt_name)
        if len(g) == 0:
            return np.zeros((0, 2)), f"no ground truth /gt/{gt_name}/tf in the recording"
        t = g["t_ns"].to_numpy(np.int64)
        return np.stack([held(t, g["x"].to_numpy(), grid),
                         held(t, g["y"].to_numpy(), grid)], axis=1), ""

    if ref.name in ("alarm", "muted"):
        f = frames.fields[(_bool_topic(sc, ref), "data")]
        if f.error and f.t_ns.size == 0 and not f.error.endswith("no messages"):
            return np.zeros(0), f.error
        return as_bool(held(f.t_ns, f.value, grid, before=0.0)), ""
    if ref.name == "topic":
        f = frames.fields[_topic_field(ref)]
        return (np.zeros(0), f.error) if f.error else (held(f.t_ns, f.value, grid), "")
    if ref.name == "speed":
        gt_name, _ = _gt_name(sc, ref.args[0])
        g = frames.gt(gt_name)
        if len(g) < 2:
            return np.zeros(0), f"fewer than two ground-truth samples of {gt_name}"
        t = g["t_ns"].to_numpy(np.int64)
        dt = np.diff(t) / 1e9
        step = np.hypot(np.diff(g["x"].to_numpy()), np.diff(g["y"].to_numpy()))
        v = np.divide(step, dt, out=np.full(step.shape, np.nan), where=dt > 0)
        return held(t[1:], v, grid), ""
    p, why = xy(ref.args[0])
    if why:
        return p, why
    undefined = np.isnan(p[:, 0])
    if ref.name in ("clearance", "distance"):
        q, why = xy(ref.args[1])
        if why:
            return q, why
        d = np.hypot(*(p - q).T)
        if ref.name == "clearance":
            d = d - _gt_name(sc, ref.args[0])[1] - _gt_name(sc, ref.args[1])[1]
        return d, ""
    if ref.name == "in_zone":
        if ref.args[1] == "loading_roi":
            inside = points_in_polygon(p, sc.zones.loading_roi)
        else:
            wire = sc.zones.trailer_tripwire
            assert wire is not None  # parse_formula checked the zone
            inside = Tripwire(wire.a, wire.b, wire.inside).past(p[:, 0], p[:, 1])
        return as_bool(np.where(undefined, np.nan, inside.astype(np.float64))), ""
    assert ref.name == "tracking_error"
    block = next(b for b in sc.scoring.control_blocks if (b.robot or ref.args[0]) == ref.args[0])
    d, _ = route_distance(np.nan_to_num(p), sc.routes[block.route].waypoints)
    return np.where(undefined, np.nan, d), ""


def spec_metrics(sc: Scenario, frames: Frames) -> list[MetricResult]:
    """``spec.<name>.robustness`` of every enabled spec (:mod:`harness.metrics.specs`)."""
    formulas = _formulas(sc)
    if not formulas:
        return []
    grid = tick_grid(frames.end_ns, sc.physics.tick_hz)
    out = []
    for name, required, formula in formulas:
        signals: dict[str, np.ndarray] = {}
        undefined: dict[str, str] = {}
        for ref in formula.signals:
            values, why = _signal(sc, frames, ref, grid)
            if why:
                undefined[ref.var] = why
            else:
                signals[ref.var] = values
        out.append(spec_metric(name, formula, signals, grid, required=required,
                               undefined=undefined))
    return out
