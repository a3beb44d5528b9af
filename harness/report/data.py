"""What the report shows, computed from a run directory: the summary, the resolved scenario
and the recorded frames turned into time series, intervals and moments.

The series follow the metric definitions (:mod:`harness.metrics`) so that what the plots show
is what was scored: the expected mute state comes from
:func:`harness.metrics.safety.expected_muted`, the cross-track error from
:func:`harness.metrics.control.route_distance`, perception frames are aligned with
:func:`harness.metrics.perception.align_frames` inside the scored area.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from harness.bus import resolve_topic
from harness.errors import SrrError
from harness.frames import Frames
from harness.metrics.control import robot_poses, route_distance
from harness.metrics.perception import align_frames, assign
from harness.metrics.safety import Tripwire, expected_muted
from harness.recording.bagread import ros1_recording
from harness.regression import load_baseline
from harness.scenario import Scenario, load_scenario
from harness.scoring import scenario_frames, within_area
from harness.summary import read_summary

__all__ = [
    "ControlSeries",
    "Edge",
    "Interval",
    "Moment",
    "Outline",
    "PerceptionSeries",
    "RunData",
    "SafetySeries",
    "Track",
    "WorldMap",
    "load_run",
    "metric_windows",
    "read_summary",
    "world_map",
]

Window = tuple[float, float]
MAX_MOMENTS = 8
MIN_CTE_MOMENT = 0.02  # m: a smaller maximum cross-track error is not worth a look


@dataclass(frozen=True)
class Interval:
    """A contiguous run of frames where the actual mute state differs from the expected one.
    ``kind``: ``over`` (muted although it should not be) or ``under``; ``long``: at least the
    scoring's ``min_window_s`` (those are the windows the metrics report)."""

    start_s: float
    end_s: float
    kind: str
    long: bool


@dataclass(frozen=True)
class Edge:
    """A change of the expected mute state at ``t_s`` to ``target`` (True: mute) and when the
    actual state followed (``response_s``; None when it never did before ``limit_s``)."""

    t_s: float
    target: bool
    response_s: float | None
    limit_s: float

    @property
    def lag_s(self) -> float | None:
        return None if self.response_s is None else self.response_s - self.t_s

    @property
    def kind(self) -> str:
        return "mute" if self.target else "unmute"


@dataclass
class SafetySeries:
    robot: str
    topic: str
    t: np.ndarray  # frame times (s)
    inside: np.ndarray
    worker_in_roi: np.ndarray
    expected: np.ndarray
    actual: np.ndarray  # actual state held at each frame
    msg_t: np.ndarray  # /safety/is_muted messages
    msg_v: np.ndarray
    end_s: float
    min_window_s: float
    mismatches: list[Interval]
    edges: list[Edge]


@dataclass
class ControlSeries:
    robot: str
    source: str  # "ground truth" or "odometry"
    t: np.ndarray
    cte: np.ndarray
    collisions: list[Window]
    prefix: str = "control."  # of this robot's metric names (control.<robot>. for several)


@dataclass
class PerceptionSeries:
    cls: str
    topic: str
    gate: float
    err_t: np.ndarray  # one entry per matched pair
    err_v: np.ndarray
    frame_t: np.ndarray  # one entry per scored frame
    n_tracks: np.ndarray
    n_objects: np.ndarray
    n_missed: np.ndarray
    n_false: np.ndarray


@dataclass
class Track:
    """A trajectory for the map: ground truth, plus world-frame odometry for robots."""

    name: str
    kind: str  # "robot" or "worker"
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    odom_x: np.ndarray | None = None
    odom_y: np.ndarray | None = None
    planned: tuple[tuple[float, float], ...] = ()
    source: str = "ground truth"  # of x, y

    def at(self, t_s: float) -> tuple[float, float] | None:
        if self.t.size == 0:
            return None
        i = int(np.clip(np.searchsorted(self.t, t_s), 0, self.t.size - 1))
        if i > 0 and abs(self.t[i - 1] - t_s) < abs(self.t[i] - t_s):
            i -= 1
        return float(self.x[i]), float(self.y[i])


@dataclass(frozen=True)
class Outline:
    """A static shape of a world file on the map: its name and convex outline (world XY)."""

    name: str
    points: tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class WorldMap:
    """The world file's static geometry as the run recorded it (``summary.json``'s
    ``world_map``): the file, its mode (``replace`` or ``extend``) and the outlines."""

    file: str
    mode: str
    outlines: tuple[Outline, ...]


def world_map(summary: dict[str, Any]) -> WorldMap | None:
    """The run's :class:`WorldMap`, or None (no world file). Entries that do not read as
    outlines (three or more finite [x, y] points) are left out."""
    raw = summary.get("world_map")
    if not isinstance(raw, dict):
        return None
    outlines = []
    for item in raw.get("footprints") or []:
        if not isinstance(item, dict) or not isinstance(item.get("points"), list):
            continue
        try:
            pts = tuple((float(p[0]), float(p[1])) for p in item["points"])
        except (TypeError, ValueError, IndexError):
            continue
        if len(pts) >= 3 and all(math.isfinite(c) for p in pts for c in p):
            outlines.append(Outline(str(item.get("name", "")), pts))
    return WorldMap(str(raw.get("file", "")), str(raw.get("mode", "replace")),
                    tuple(outlines))


@dataclass(frozen=True)
class Moment:
    """A time worth a look: numbered M1… on the map, the time axis and the keyframes."""

    number: int
    t_s: float
    label: str
    kind: str  # "over", "under", "collision", "control", "perception"


@dataclass
class RunData:
    run_dir: Path
    summary: dict[str, Any]
    scenario_text: str
    scenario: Scenario | None = None
    frames: Frames | None = None
    safety: SafetySeries | None = None
    control: list[ControlSeries] = field(default_factory=list)
    perception: list[PerceptionSeries] = field(default_factory=list)
    tracks: list[Track] = field(default_factory=list)
    moments: list[Moment] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    # The baseline's reference recording, read like a run (same scenario: like for like),
    # for the report's "against the baseline" overlays; None without one.
    reference: RunData | None = None

    @property
    def end_s(self) -> float:
        s = self.summary.get("simulated_s")
        if isinstance(s, (int, float)) and s > 0:
            return float(s)
        if self.frames is not None and self.frames.end_ns > 0:
            return self.frames.end_ns / 1e9
        return float(self.summary.get("duration_s") or 1.0)

    def metric(self, name: str) -> dict[str, Any] | None:
        return next((m for m in self.summary.get("metrics", []) if m.get("name") == name),
                    None)


# --------------------------------------------------------------------------- loading


def load_run(run_dir: str | Path, *, summary: dict[str, Any] | None = None,
             scenario: Scenario | None = None, frames: Frames | None = None) -> RunData:
    """Everything the report needs from ``run_dir``. Missing or unreadable parts (no bag, a
    scenario that no longer loads) are listed in ``problems``, not raised: a report of a
    broken run is still worth reading."""
    run_dir = Path(run_dir)
    summary = summary if summary is not None else read_summary(run_dir)
    sc_file = run_dir / "scenario.yaml"
    text = sc_file.read_text(encoding="utf-8") if sc_file.is_file() else ""
    data = RunData(run_dir, summary, text)
    if scenario is None and text:
        try:
            scenario = load_scenario(sc_file)
        except SrrError as err:
            data.problems.append(f"scenario.yaml does not load: {err}")
    data.scenario = scenario
    if frames is None and ((run_dir / "bag" / "metadata.yaml").is_file()
                           or ros1_recording(run_dir / "bag") is not None):
        try:
            frames = scenario_frames(scenario, run_dir / "bag")
        except SrrError as err:
            data.problems.append(f"bag does not read back: {err}")
    elif frames is None:
        data.problems.append("bag/metadata.yaml: missing (no recorded data to plot)")
    data.frames = frames
    if scenario is not None and frames is not None:
        _series(data, scenario, frames)
        data.reference = _reference(data, scenario)
    data.moments = _moments(data)
    return data


def _series(data: RunData, scenario: Scenario, frames: Frames) -> None:
    data.tracks = _tracks(scenario, frames)
    data.safety = _safety(scenario, frames)
    data.control = _control(scenario, frames, data.summary)
    data.perception = _perception(scenario, frames)


def _blessed_since(base: Mapping[str, Any]) -> bool:
    """Whether the baseline file the run was judged against now holds another recording
    (its ``digest`` is not the one the run's summary recorded of it)."""
    try:
        now = load_baseline(Path(str(base.get("path"))))
    except SrrError:
        return False  # unreadable (or gone: None): the reference file says what there is
    return now is not None and bool(base.get("digest")) and now.digest != base.get("digest")


def _reference(data: RunData, scenario: Scenario) -> RunData | None:
    """The baseline's reference recording as a run of the same scenario, when the run was
    compared like for like with a baseline that has one (``summary.baseline.reference``)."""
    base = data.summary.get("baseline")
    if not isinstance(base, dict) or not base.get("reference") or base.get(
            "config_differences"):
        return None
    path = Path(str(base["reference"]))
    if not path.is_file():
        data.problems.append(f"the baseline's reference recording {path} is gone: no overlay")
        return None
    if _blessed_since(base):
        data.problems.append(f"the baseline {base.get('path')} was blessed again after this run "
                             "was judged: its reference recording is another run's, so it is "
                             "not drawn against this one (the verdict is the one judged then)")
        return None
    try:
        frames = scenario_frames(scenario, path)
    except SrrError as err:
        data.problems.append(f"the baseline's reference recording does not read: {err}")
        return None
    metrics = [{"name": e["name"], "value": e.get("baseline"), "windows": []}
               for e in data.summary.get("comparison", []) if isinstance(e, dict)]
    ref = RunData(path, {"metrics": metrics, "simulated_s": data.summary.get("simulated_s")},
                  "", scenario, frames)
    _series(ref, scenario, frames)
    return ref


# --------------------------------------------------------------------------- series


def _tracks(sc: Scenario, frames: Frames) -> list[Track]:
    out = []
    for robot in sc.robots:
        if not robot.enabled:
            continue
        gt = robot_poses(frames, robot.name, source="gt")
        odom = pd.DataFrame()
        if robot.odometry.enabled:
            topic = resolve_topic(robot.odometry.odom_topic, robot.ns)
            odom = robot_poses(frames, robot.name, source="odom", odom_topic=topic)
        if len(gt) == 0 and len(odom) == 0:
            continue
        if len(gt):
            out.append(Track(robot.name, "robot", gt["t_ns"].to_numpy() / 1e9,
                             gt["x"].to_numpy(), gt["y"].to_numpy(),
                             odom["x"].to_numpy() if len(odom) else None,
                             odom["y"].to_numpy() if len(odom) else None))
        else:  # no ground truth recorded: the odometry is all there is
            out.append(Track(robot.name, "robot", odom["t_ns"].to_numpy() / 1e9,
                             odom["x"].to_numpy(), odom["y"].to_numpy(), source="odometry"))
    for i, w in enumerate(sc.workers):
        if not w.enabled:
            continue
        g = frames.gt(f"character_{i}")
        out.append(Track(sc.worker_name(i), "worker", g["t_ns"].to_numpy() / 1e9,
                         g["x"].to_numpy(), g["y"].to_numpy(), planned=tuple(w.route)))
    return out


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    m = np.concatenate(([False], mask, [False])).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(),
                    strict=True))


def _safety(sc: Scenario, frames: Frames) -> SafetySeries | None:
    s = sc.scoring.safety
    wire = sc.zones.trailer_tripwire
    if s is None or not s.enabled or wire is None or len(sc.zones.loading_roi) < 3:
        return None
    g = frames.gt_poses
    fork = g[g["name"] == s.robot]
    if len(fork) == 0:
        return None
    workers = g[g["name"].str.startswith("character_")]
    exp = expected_muted(fork, workers, tripwire=Tripwire(wire.a, wire.b, wire.inside),
                         roi=sc.zones.loading_roi)
    t_ns = exp["t_ns"].to_numpy(np.int64)
    expected = exp["expected"].to_numpy(bool)
    m = frames.muted.sort_values("t_ns", kind="stable")
    mt = m["t_ns"].to_numpy(np.int64)
    mv = m["value"].to_numpy(bool)
    idx = np.searchsorted(mt, t_ns, side="right") - 1
    actual = (np.where(idx >= 0, mv[np.clip(idx, 0, None)], False) if mv.size
              else np.zeros(t_ns.size, dtype=bool))
    dt = int(np.median(np.diff(t_ns))) if t_ns.size > 1 else 0
    t_end = int(t_ns[-1]) + dt
    min_ns = round(s.min_window_s * 1e9)
    mism: list[Interval] = []
    for kind, mask in (("over", actual & ~expected), ("under", ~actual & expected)):
        for a, b in _runs(mask):
            end = int(t_ns[b]) if b < t_ns.size else t_end
            mism.append(Interval(t_ns[a] / 1e9, end / 1e9, kind, end - int(t_ns[a]) >= min_ns))
    mism.sort(key=lambda w: w.start_s)
    edges = []
    change = np.flatnonzero(expected[1:] != expected[:-1]) + 1
    for k, i in enumerate(change):
        te = int(t_ns[i])
        target = bool(expected[i])
        limit = int(t_ns[change[k + 1]]) if k + 1 < change.size else t_end
        if bool(actual[i]) == target:
            resp: float | None = te / 1e9
        else:
            later = np.flatnonzero((mt > te) & (mv == target))
            resp = int(mt[later[0]]) / 1e9 if later.size and int(mt[later[0]]) < limit \
                else None
        edges.append(Edge(te / 1e9, target, resp, limit / 1e9))
    return SafetySeries(s.robot, resolve_topic(s.muted_topic), t_ns / 1e9,
                        exp["inside"].to_numpy(bool), exp["worker_in_roi"].to_numpy(bool),
                        expected, actual, mt / 1e9, mv, t_end / 1e9, s.min_window_s, mism,
                        edges)


def _control(sc: Scenario, frames: Frames, summary: dict[str, Any]) -> list[ControlSeries]:
    """One series per scored robot (``scoring.control``, one block or a list)."""
    out = []
    for c in sc.scoring.control_blocks:
        if c.route not in sc.routes:
            continue
        try:
            robot = sc.robot(c.robot)
        except KeyError:
            continue
        poses = robot_poses(frames, robot.name, source="gt")
        source = "ground truth"
        if len(poses) == 0:
            poses = robot_poses(frames, robot.name, source="odom",
                                odom_topic=resolve_topic(robot.odometry.odom_topic, robot.ns))
            source = "odometry"
        if len(poses) == 0:
            continue
        d, _ = route_distance(poses[["x", "y"]].to_numpy(), sc.routes[c.route].waypoints)
        prefix = sc.scoring.control_prefix(robot.name)
        coll = next((m for m in summary.get("metrics", [])
                     if m.get("name") == f"{prefix}collisions"), None)
        windows = [(float(a), float(b)) for a, b in (coll or {}).get("windows", [])]
        out.append(ControlSeries(robot.name, source, poses["t_ns"].to_numpy() / 1e9, d,
                                 windows, prefix))
    return out


def _xy_by_frame(rows: pd.DataFrame) -> dict[int, np.ndarray]:
    """``rows``' ``x, y`` per ``frame``, each frame's rows in table order (what a groupby
    gives, split with numpy: a pandas group costs ~0.1 ms, and a run has thousands)."""
    f = rows["frame"].to_numpy(np.int64)
    if f.size == 0:
        return {}
    order = np.argsort(f, kind="stable")
    keys, starts = np.unique(f[order], return_index=True)
    parts = np.split(rows[["x", "y"]].to_numpy(np.float64)[order], starts[1:])
    return dict(zip(keys.tolist(), parts, strict=True))


def _perception(sc: Scenario, frames: Frames) -> list[PerceptionSeries]:
    p = sc.scoring.perception
    if p is None or not p.enabled:
        return []
    scored = within_area(frames, p.area) if p.area else frames
    tf = scored.track_frames
    topic = resolve_topic(p.marker_topics[0]) if p.marker_topics else None
    if topic is None:
        topics = sorted(str(t) for t in set(tf["topic"]))
        if len(topics) != 1:
            return []
        topic = topics[0]
    tf = tf[tf["topic"] == topic].sort_values(["t_ns", "frame"], kind="stable")
    gt = scored.gt_poses
    if len(tf) == 0 or len(gt) == 0:
        return []
    stamps = np.unique(gt["t_ns"].to_numpy(np.int64))
    tol = int(np.median(np.diff(stamps)) // 2) if stamps.size > 1 else 0
    objects = [n for n in scored.gt_names if n.startswith("character_")]
    frame_t = tf["t_ns"].to_numpy(np.int64)
    aligned, objs = align_frames(frame_t, gt, tolerance_ns=tol, objects=objects)
    frame_ids = tf["frame"].to_numpy(np.int64)
    obj_by_frame = _xy_by_frame(objs)
    out = []
    for cls in p.classes:
        tr = scored.tracks[(scored.tracks["cls"] == cls).to_numpy(bool)]
        tr_by_frame = _xy_by_frame(tr)
        err_t: list[float] = []
        err_v: list[float] = []
        ft, nt, no, nm, nf = [], [], [], [], []
        empty = np.zeros((0, 2))
        for k in np.flatnonzero(aligned):
            o = obj_by_frame.get(int(k), empty)
            h = tr_by_frame.get(int(frame_ids[k]), empty)
            pairs: list[tuple[int, int]] = []
            if len(o) and len(h):
                cost = np.hypot(o[:, None, 0] - h[None, :, 0], o[:, None, 1] - h[None, :, 1])
                cost[cost > p.gate] = np.inf
                pairs = assign(cost)
                for i, j in pairs:
                    err_t.append(frame_t[k] / 1e9)
                    err_v.append(float(cost[i, j]))
            ft.append(frame_t[k] / 1e9)
            nt.append(len(h))
            no.append(len(o))
            nm.append(len(o) - len(pairs))
            nf.append(len(h) - len(pairs))
        out.append(PerceptionSeries(cls, topic, p.gate, np.asarray(err_t), np.asarray(err_v),
                                    np.asarray(ft), np.asarray(nt), np.asarray(no),
                                    np.asarray(nm), np.asarray(nf)))
    return out


# --------------------------------------------------------------------------- explanations


def _frame_runs(t: np.ndarray, mask: np.ndarray) -> list[Window]:
    """Runs of flagged frames as windows, each frame lasting one median frame period."""
    if t.size == 0 or not mask.any():
        return []
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    return [(float(t[a]), float(t[b - 1]) + dt) for a, b in _runs(mask)]


def _longest(windows: Sequence[Window], n: int = 4) -> list[Window]:
    return sorted(sorted(windows, key=lambda w: w[0] - w[1])[:n])


def metric_windows(name: str, data: RunData) -> list[Window]:
    """The sim-time windows (s) that explain a metric's value; a point is ``(t, t)``.

    The metric's own ``windows`` when it has some, else derived from the series: mismatch
    windows for the match rate, edge → response for reaction lags, the moment of a maximum,
    frames with misses or false tracks for perception ratios."""
    m = data.metric(name) or {}
    own = [(float(a), float(b)) for a, b in m.get("windows", [])]
    if own:
        return own
    s = data.safety
    c = next((cs for cs in data.control if name.startswith(cs.prefix)), None)
    tail = name.removeprefix(c.prefix) if c is not None else ""
    if s is not None and name.startswith("safety."):
        if name == "safety.match_rate":
            longs = [(w.start_s, w.end_s) for w in s.mismatches if w.long]
            return longs or _longest([(w.start_s, w.end_s) for w in s.mismatches])
        lag = re.match(r"safety\.(mute|unmute)_lag\.(\w+)$", name)
        if lag:
            es = [e for e in s.edges if e.kind == lag.group(1) and e.lag_s is not None]
            if lag.group(2) == "max" and es:
                es = [max(es, key=lambda e: e.lag_s or 0.0)]
            return [(e.t_s, e.response_s or e.t_s) for e in es]
        never = {"safety.mute_never_engaged": True, "safety.unmute_never_released": False}
        if name in never:
            return [(e.t_s, e.limit_s) for e in s.edges
                    if e.target == never[name] and e.response_s is None]
        return []
    if c is not None and tail.startswith("cross_track_error") and c.cte.size:
        if name.endswith(".max"):
            i = int(np.argmax(c.cte))
            return [(float(c.t[i]), float(c.t[i]))]
        base = next((e.get("baseline") for e in data.summary.get("comparison", [])
                     if e.get("name") == name), None)
        level = float(base) if isinstance(base, (int, float)) else float(np.mean(c.cte))
        return _longest(_frame_runs(c.t, c.cte > level))
    if c is not None and tail == "min_clearance":
        hit = re.search(r"at ([0-9.]+) s", str(m.get("detail", "")))
        return [(float(hit.group(1)), float(hit.group(1)))] if hit else []
    if name.startswith("perception.") and data.perception:
        p = data.perception[0]
        if name in ("perception.position_error.p95", "perception.position_error.max") \
                and p.err_v.size:
            i = int(np.argmax(p.err_v))
            return [(float(p.err_t[i]), float(p.err_t[i]))]
        if name.startswith("perception.recall"):
            return _longest(_frame_runs(p.frame_t, p.n_missed > 0))
        if name == "perception.precision":
            return _longest(_frame_runs(p.frame_t, p.n_false > 0))
        if name.split(".")[-1] in ("f1", "mota", "idf1", "id_switches"):
            return _longest(_frame_runs(p.frame_t, (p.n_missed + p.n_false) > 0))
    return []


def _moments(data: RunData) -> list[Moment]:
    """Up to :data:`MAX_MOMENTS` times, most telling first: the start of every safety
    mismatch window, every collision, then the worst control and perception moments."""
    cands: list[tuple[float, str, str]] = []
    s = data.safety
    if s is not None:
        wins = [w for w in s.mismatches if w.long] or _top_short(s.mismatches)
        for w in wins:
            what = "over-mute (muted, should alarm)" if w.kind == "over" \
                else "under-mute (alarm, should be muted)"
            cands.append((w.start_s, f"start of {what} {w.start_s:.2f}–{w.end_s:.2f} s",
                          w.kind))
    several = len(data.control) > 1
    for c in data.control:
        who = f"{c.robot}: " if several else ""
        for a, b in c.collisions:
            cands.append((a, f"{who}collision {a:.2f}–{b:.2f} s", "collision"))
        if c.cte.size and float(np.max(c.cte)) >= MIN_CTE_MOMENT:
            i = int(np.argmax(c.cte))
            cands.append((float(c.t[i]), f"{who}max cross-track error {c.cte[i]:.3f} m",
                          "control"))
    for p in data.perception:
        if p.err_v.size:
            i = int(np.argmax(p.err_v))
            cands.append((float(p.err_t[i]),
                          f"max {p.cls} position error {p.err_v[i]:.3f} m", "perception"))
    chosen: list[tuple[float, str, str]] = []
    for t, label, kind in cands:
        if len(chosen) >= MAX_MOMENTS:
            break
        if all(abs(t - u) > 0.25 for u, _, _ in chosen) and math.isfinite(t):
            chosen.append((t, label, kind))
    chosen.sort(key=lambda m: m[0])
    return [Moment(i + 1, t, label, kind) for i, (t, label, kind) in enumerate(chosen)]


def _top_short(ws: Sequence[Interval], n: int = 2) -> list[Interval]:
    return sorted(sorted(ws, key=lambda w: w.start_s - w.end_s)[:n], key=lambda w: w.start_s)
