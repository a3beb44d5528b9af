"""Control metrics: how well a robot followed its route, against ground truth.

Pure functions from plain tables (pandas, world frame, ``t_ns`` integer nanoseconds) to
:class:`MetricResult` lists; :func:`control_metrics` wires them to :class:`~harness.frames.Frames`.

Definitions
-----------
* Cross-track error: distance from the robot's reference point to the closest point of the
  route polyline (any segment), per pose sample; mean, RMS and max (m).
* Heading error: ``|wrap(yaw - tangent)|`` where ``tangent`` is the direction of the segment
  holding that closest point (the first one on a tie); mean and max (rad). ``yaw`` is the
  robot's *forward* heading: for ground-truth poses the body yaw plus ``front_yaw`` (π for the
  forklift, whose asset faces -X); odometry already reports the forward heading.
* Goal: reached (1/0) when the robot came within ``tolerance`` of the route's last waypoint at
  any sample; time to goal is from the first pose sample to the first such sample (s, None
  when never reached); final distance to the goal (m).
* Distance travelled: sum of the distances between consecutive pose samples (m).
* Collisions: the robot's footprint is a circle of ``robot_radius`` around its reference point,
  each worker a circle of ``worker_radius`` and each other robot a circle of its own radius;
  clearance = centre distance - both radii, from time-aligned ground-truth poses. A collision
  is one episode of clearance < 0 with one worker or robot (entering contact counts once,
  however long it lasts); the windows list them. The minimum clearance over the run is
  reported too (m; negative means contact).
* ``cmd_vel`` tracking: every odometry sample at or after the first command is compared with
  the last command published at or before it (commands are held); RMS of ``cmd.vx - odom.vx``
  (m/s) and of ``cmd.wz - odom.wz`` (rad/s). Odometry twists are in the body frame, which is
  the frame ``cmd_vel`` is given in.
* Odometry drift: odometry moved into the world frame (see :mod:`harness.frames`) against
  ground truth at the nearest stamp within ``tolerance``; position error at the last aligned
  sample and the maximum (m).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Literal

import numpy as np
import pandas as pd

from harness.frames import Frames
from harness.metrics.types import MetricResult

__all__ = [
    "clearance",
    "cmd_vel_tracking",
    "control_metrics",
    "distance_travelled",
    "goal",
    "odom_drift",
    "path_tracking",
    "robot_poses",
    "route_distance",
]

Point = tuple[float, float]
_CHUNK = 8192


def _m(name: str, value: float | None, unit: str, direction: Literal["lower", "higher", "none"],
       detail: str = "", windows: tuple[tuple[float, float], ...] = ()) -> MetricResult:
    v = None if value is None or not math.isfinite(value) else float(value)
    return MetricResult(name, v, unit, direction, "control", detail, windows)


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def route_distance(xy: np.ndarray, route: Sequence[Point]) -> tuple[np.ndarray, np.ndarray]:
    """(distance to the polyline, tangent angle of the closest segment) for points (N, 2)."""
    pts = np.asarray(route, dtype=np.float64).reshape(-1, 2)
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 1:
        return np.hypot(*(xy - pts[0]).T), np.zeros(len(xy))
    a, b = pts[:-1], pts[1:]
    seg = b - a
    len2 = (seg * seg).sum(axis=1)
    tangent = np.arctan2(seg[:, 1], seg[:, 0])
    dist = np.empty(len(xy))
    which = np.empty(len(xy), dtype=np.int64)
    for s in range(0, len(xy), _CHUNK):
        p = xy[s:s + _CHUNK, None, :]  # (n, 1, 2)
        rel = p - a[None]  # (n, m, 2)
        t = np.divide((rel * seg[None]).sum(axis=2), len2[None],
                      out=np.zeros(rel.shape[:2]), where=len2[None] > 0)
        t = np.clip(t, 0.0, 1.0)
        d = np.hypot(*(rel - t[..., None] * seg[None]).transpose(2, 0, 1))
        which[s:s + _CHUNK] = d.argmin(axis=1)
        dist[s:s + _CHUNK] = d[np.arange(len(d)), which[s:s + _CHUNK]]
    return dist, tangent[which]


def path_tracking(poses: pd.DataFrame, route: Sequence[Point]) -> list[MetricResult]:
    """Cross-track error (mean, RMS, max) and heading error (mean, max) to ``route``.

    ``poses``: columns ``x, y, yaw`` (forward heading)."""
    names = ("control.cross_track_error.mean", "control.cross_track_error.rms",
             "control.cross_track_error.max")
    if len(poses) == 0 or len(route) == 0:
        why = "no pose samples" if len(poses) == 0 else "empty route"
        return ([_m(n, None, "m", "lower", why) for n in names]
                + [_m(f"control.heading_error.{k}", None, "rad", "lower", why)
                   for k in ("mean", "max")])
    d, tangent = route_distance(poses[["x", "y"]].to_numpy(), route)
    herr = np.abs(_wrap(poses["yaw"].to_numpy() - tangent))
    return [
        _m(names[0], d.mean(), "m", "lower"),
        _m(names[1], math.sqrt(float((d * d).mean())), "m", "lower"),
        _m(names[2], d.max(), "m", "lower"),
        _m("control.heading_error.mean", herr.mean(), "rad", "lower"),
        _m("control.heading_error.max", herr.max(), "rad", "lower"),
    ]


def goal(poses: pd.DataFrame, goal_xy: Point, *, tolerance: float = 0.5) -> list[MetricResult]:
    """Goal reached (1/0), time to goal (s) and final distance to the goal (m)."""
    if len(poses) == 0:
        return [_m("control.goal_reached", None, "bool", "higher", "no pose samples"),
                _m("control.time_to_goal", None, "s", "lower", "no pose samples"),
                _m("control.goal_distance_final", None, "m", "lower", "no pose samples")]
    t = poses["t_ns"].to_numpy()
    d = np.hypot(poses["x"].to_numpy() - goal_xy[0], poses["y"].to_numpy() - goal_xy[1])
    hit = np.flatnonzero(d <= tolerance)
    reached = hit.size > 0
    ttg = (t[hit[0]] - t[0]) / 1e9 if reached else None
    return [
        _m("control.goal_reached", 1.0 if reached else 0.0, "bool", "higher",
           f"within {tolerance} m of ({goal_xy[0]}, {goal_xy[1]})"),
        _m("control.time_to_goal", ttg, "s", "lower",
           "" if reached else "goal never reached"),
        _m("control.goal_distance_final", d[-1], "m", "lower"),
    ]


def distance_travelled(poses: pd.DataFrame) -> list[MetricResult]:
    x, y = poses["x"].to_numpy(), poses["y"].to_numpy()
    total = float(np.hypot(np.diff(x), np.diff(y)).sum()) if len(x) > 1 else 0.0
    return [_m("control.distance_travelled", total, "m", "none")]


def _align(left_t: np.ndarray, right: pd.DataFrame, tolerance_ns: int) -> pd.DataFrame:
    """Rows of ``right`` (sorted by ``t_ns``) at the nearest stamp to each of ``left_t``
    within the tolerance; NaN where none."""
    left = pd.DataFrame({"t_ns": left_t.astype(np.int64)})
    r = right.sort_values("t_ns", kind="stable").rename(columns={"t_ns": "t_right"})
    r["t_ns"] = r["t_right"]
    return pd.merge_asof(left, r, on="t_ns", direction="nearest",
                         tolerance=int(tolerance_ns))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) index ranges where ``mask`` is True."""
    if mask.size == 0:
        return []
    m = np.concatenate(([False], mask, [False])).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(),
                    strict=True))


def clearance(robot: pd.DataFrame, workers: pd.DataFrame, *, robot_radius: float,
              worker_radius: float = 0.3, tolerance_ns: int = 8_333_333,
              radii: Mapping[str, float] | None = None) -> list[MetricResult]:
    """Collisions (count of contact episodes) and minimum clearance to workers and other
    robots (m).

    ``robot``: ``t_ns, x, y``; ``workers``: ``t_ns, name, x, y`` (ground truth) of every
    other object; ``radii`` gives an object's footprint radius by name (other robots),
    ``worker_radius`` the rest's."""
    radii = radii or {}
    if len(robot) == 0 or len(workers) == 0:
        why = "no robot ground truth" if len(robot) == 0 else "no worker ground truth"
        return [_m("control.collisions", None, "count", "lower", why),
                _m("control.min_clearance", None, "m", "higher", why)]
    robot = robot.sort_values("t_ns", kind="stable")
    t = robot["t_ns"].to_numpy()
    rx, ry = robot["x"].to_numpy(), robot["y"].to_numpy()
    tick = np.diff(t)
    dt = int(np.median(tick)) if tick.size else 0
    episodes: list[tuple[float, float]] = []
    best = (math.inf, "")
    for name, w in workers.groupby("name", sort=True, observed=True):
        al = _align(t, w[["t_ns", "x", "y"]], tolerance_ns)
        c = np.hypot(al["x"].to_numpy() - rx, al["y"].to_numpy() - ry) - robot_radius \
            - radii.get(str(name), worker_radius)
        if np.isfinite(c).any():
            i = int(np.nanargmin(c))
            if c[i] < best[0]:
                best = (float(c[i]), f"{name} at {t[i] / 1e9:.3f} s")
        for a, b in _runs(np.nan_to_num(c, nan=np.inf) < 0):
            end = t[b] if b < len(t) else t[-1] + dt
            episodes.append((t[a] / 1e9, end / 1e9))
    episodes.sort()
    others = "".join(f", {n} circle {r} m" for n, r in sorted(radii.items()))
    return [
        _m("control.collisions", float(len(episodes)), "count", "lower",
           f"footprint circle {robot_radius} m vs worker circle {worker_radius} m{others}",
           tuple(episodes)),
        _m("control.min_clearance", best[0] if best[1] else None, "m", "higher",
           best[1] or "no time-aligned worker pose"),
    ]


def cmd_vel_tracking(cmd: pd.DataFrame, odom: pd.DataFrame) -> list[MetricResult]:
    """RMS of commanded minus measured body velocity, commands held between messages.

    ``cmd``: ``t_ns, vx, wz``; ``odom``: ``t_ns, vx, wz``."""
    names = (("control.cmd_vel_tracking.vx_rms", "m/s"),
             ("control.cmd_vel_tracking.wz_rms", "rad/s"))
    if len(cmd) == 0 or len(odom) == 0:
        why = "no cmd_vel messages" if len(cmd) == 0 else "no odometry"
        return [_m(n, None, u, "lower", why) for n, u in names]
    c = cmd[["t_ns", "vx", "wz"]].sort_values("t_ns", kind="stable")
    o = odom[["t_ns", "vx", "wz"]].sort_values("t_ns", kind="stable")
    al = pd.merge_asof(o, c, on="t_ns", direction="backward", suffixes=("_odom", "_cmd"))
    al = al.dropna(subset=["vx_cmd"])
    if len(al) == 0:
        return [_m(n, None, u, "lower", "no odometry after the first command")
                for n, u in names]
    ex = al["vx_cmd"].to_numpy() - al["vx_odom"].to_numpy()
    ew = al["wz_cmd"].to_numpy() - al["wz_odom"].to_numpy()
    detail = f"{len(al)} odometry samples against held commands"
    return [_m(names[0][0], math.sqrt(float((ex * ex).mean())), "m/s", "lower", detail),
            _m(names[1][0], math.sqrt(float((ew * ew).mean())), "rad/s", "lower", detail)]


def odom_drift(odom: pd.DataFrame, gt: pd.DataFrame, *, tolerance_ns: int = 8_333_333
               ) -> list[MetricResult]:
    """Final and maximum position error of world-frame odometry against ground truth.

    ``odom``, ``gt``: ``t_ns, x, y`` in the world frame."""
    names = ("control.odom_drift.final", "control.odom_drift.max")
    if len(odom) == 0 or len(gt) == 0:
        why = "no odometry" if len(odom) == 0 else "no ground truth"
        return [_m(n, None, "m", "lower", why) for n in names]
    o = odom.sort_values("t_ns", kind="stable")
    al = _align(o["t_ns"].to_numpy(), gt[["t_ns", "x", "y"]], tolerance_ns)
    err = np.hypot(o["x"].to_numpy() - al["x"].to_numpy(),
                   o["y"].to_numpy() - al["y"].to_numpy())
    ok = np.isfinite(err)
    if not ok.any():
        return [_m(n, None, "m", "lower", "no odometry sample has ground truth near it")
                for n in names]
    e = err[ok]
    detail = f"{int(ok.sum())} time-aligned samples"
    return [_m(names[0], e[-1], "m", "lower", detail), _m(names[1], e.max(), "m", "lower",
                                                          detail)]


def robot_poses(frames: Frames, robot: str, *, source: Literal["gt", "odom"] = "gt",
                odom_topic: str | None = None, front_yaw: float = 0.0) -> pd.DataFrame:
    """``t_ns, x, y, yaw`` of a robot in the world frame, sorted by time.

    ``gt``: the ``/gt/<robot>/tf`` poses, yaw turned by ``front_yaw`` onto the forward axis.
    ``odom``: the odometry topic (default: ``/<robot>/odom``, else the only odometry topic),
    rows not in the world frame dropped."""
    if source == "gt":
        g = frames.gt(robot)
        return pd.DataFrame({"t_ns": g["t_ns"].to_numpy(), "x": g["x"].to_numpy(),
                             "y": g["y"].to_numpy(),
                             "yaw": _wrap(g["yaw"].to_numpy() + front_yaw)})
    topic = odom_topic or _default_topic(frames.odom, robot, "odom")
    o = frames.odom
    o = o[(o["topic"] == topic) & (o["frame"] == frames.world_frame)]
    o = o.sort_values("t_ns", kind="stable")
    return pd.DataFrame({"t_ns": o["t_ns"].to_numpy(), "x": o["x"].to_numpy(),
                         "y": o["y"].to_numpy(), "yaw": o["yaw"].to_numpy()})


def _default_topic(table: pd.DataFrame, robot: str, leaf: str) -> str:
    topics = sorted(set(table["topic"]))
    own = f"/{robot}/{leaf}"
    if own in topics:
        return own
    if len(topics) == 1:
        return str(topics[0])
    return f"/{leaf}"


def control_metrics(frames: Frames, *, robot: str, route: Sequence[Point],
                    goal_tolerance: float = 0.5, robot_radius: float = 1.0,
                    worker_radius: float = 0.3, worker_prefix: str = "character_",
                    front_yaw: float = 0.0, odom_topic: str | None = None,
                    cmd_topic: str | None = None, tolerance_ns: int = 8_333_333,
                    other_robots: Mapping[str, float] | None = None,
                    prefix: str = "control.") -> list[MetricResult]:
    """Every control metric for ``robot`` following ``route`` (world-frame waypoints).

    The path metrics use ground truth when the run has it for the robot, else world-frame
    odometry (their detail then says so); collisions, clearance and drift need ground truth.
    ``other_robots`` (name → footprint radius) count in collisions and clearance like workers.
    Metric names start with ``prefix`` (``control.<robot>.`` to score several robots).
    """
    gt = robot_poses(frames, robot, source="gt", front_yaw=front_yaw)
    odom_t = odom_topic or _default_topic(frames.odom, robot, "odom")
    cmd_t = cmd_topic or _default_topic(frames.cmd_vel, robot, "cmd_vel")
    od = frames.odom[frames.odom["topic"] == odom_t]
    od_world = od[od["frame"] == frames.world_frame]
    poses = gt if len(gt) else robot_poses(frames, robot, source="odom", odom_topic=odom_t)
    out = path_tracking(poses, route)
    goal_xy = (float(route[-1][0]), float(route[-1][1])) if len(route) else (math.nan, math.nan)
    out += goal(poses, goal_xy, tolerance=goal_tolerance)
    out += distance_travelled(poses)
    if not len(gt):
        out = [MetricResult(r.name, r.value, r.unit, r.direction, r.group,
                            "; ".join(s for s in (r.detail, "from odometry (no ground truth)")
                                      if s), r.windows) for r in out]
    g = frames.gt_poses
    others = dict(other_robots or {})
    others.pop(robot, None)
    names = g["name"].astype(str)
    workers = g[names.str.startswith(worker_prefix) | names.isin(list(others))]
    out += clearance(gt, workers, robot_radius=robot_radius, worker_radius=worker_radius,
                     tolerance_ns=tolerance_ns, radii=others)
    out += cmd_vel_tracking(frames.cmd_vel[frames.cmd_vel["topic"] == cmd_t], od)
    out += odom_drift(od_world, gt, tolerance_ns=tolerance_ns)
    if prefix != "control.":
        out = [dataclasses.replace(m, name=prefix + m.name.removeprefix("control."))
               for m in out]
    return out
