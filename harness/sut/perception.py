"""Reference perception system under test: people tracking from fixed depth cameras.

For each camera it subscribes to ``<camera>_depth`` (32FC1 metres), ``<camera>_camera_info``
and ``/tf`` (world → the camera's optical frame). On every tick with new depth it

1. back-projects the depth pixels within ``max_range`` into the world frame;
2. keeps points between ``z_min`` and ``z_max`` inside the ``watch_area`` polygon (the floor
   area the cameras guard; shelves and walls stay outside it);
3. bins them on an XY grid of ``cell`` metres and labels connected cells;
4. calls a cluster a person when its footprint is at most ``person_max_extent`` across and
   its top is between ``person_min_height`` and ``z_max``;
5. tracks detections with a constant-velocity filter and gated optimal assignment;

and publishes confirmed tracks as ``visualization_msgs/MarkerArray`` in the world frame
(``ns`` = class, ``id`` = track id) on ``tracks_topic``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy import ndimage
from scipy.optimize import linear_sum_assignment

from harness.geometry import dot_floats, mat_from_quat_wxyz, rotate_rows, xyzw_to_wxyz
from harness.scenario.schema import num
from harness.serde.messages import header, make
from harness.sut.base import SutContext, SystemUnderTest, sut_params
from harness.sut.errors import PluginError
from harness.sut.zones import points_in_polygon

__all__ = ["DepthPeopleTracker", "PerceptionParams", "Track", "cluster_people"]


@dataclass(frozen=True)
class PerceptionParams:
    cameras: tuple[str, ...]
    watch_area: tuple[tuple[float, float], ...] = ()
    tracks_topic: str = "/perception/tracks"
    world_frame: str = "world"
    tf_topic: str = "/tf"
    max_range: float = num(12.0, 0.0, 1000.0, lo_open=True)
    z_min: float = num(0.3, -100.0, 100.0)
    z_max: float = num(2.2, -100.0, 100.0)
    cell: float = num(0.15, 0.0, 10.0, lo_open=True)
    min_points: int = num(12, 1, 10_000_000)
    person_max_extent: float = num(1.1, 0.0, 100.0, lo_open=True)
    person_min_height: float = num(1.2, -100.0, 100.0)
    gate: float = num(1.0, 0.0, 100.0, lo_open=True)
    min_hits: int = num(2, 1, 1_000_000)
    max_missed: int = num(5, 0, 1_000_000)
    pixel_stride: int = num(1, 1, 1024)


@dataclass
class Track:
    track_id: int
    position: np.ndarray
    velocity: np.ndarray
    last_ns: int
    hits: int = 1
    missed: int = 0


def cluster_people(points: np.ndarray, p: PerceptionParams) -> list[np.ndarray]:
    """XY centres of person-shaped clusters among world points (N, 3)."""
    if len(points) < p.min_points:
        return []
    cells = np.floor(points[:, :2] / p.cell).astype(np.int64)
    lo = cells.min(axis=0)
    idx = cells - lo
    shape = tuple(int(v) + 1 for v in idx.max(axis=0))
    grid = np.zeros(shape, dtype=bool)
    grid[idx[:, 0], idx[:, 1]] = True
    labels, n = ndimage.label(grid, structure=np.ones((3, 3), dtype=bool))
    point_labels = labels[idx[:, 0], idx[:, 1]]
    people = []
    for label in range(1, n + 1):
        pts = points[point_labels == label]
        if len(pts) < p.min_points:
            continue
        extent = pts[:, :2].max(axis=0) - pts[:, :2].min(axis=0)
        top = float(pts[:, 2].max())
        if float(extent.max()) <= p.person_max_extent and p.person_min_height <= top <= p.z_max:
            people.append(pts[:, :2].mean(axis=0))
    return people


class _Camera:
    """The latest depth, intrinsics and pose of one camera."""

    def __init__(self) -> None:
        self.k: np.ndarray | None = None
        self.frame_id = ""
        self.pose: tuple[np.ndarray, np.ndarray] | None = None
        self.depth: Any = None
        self.rays: tuple[np.ndarray, np.ndarray] | None = None


class DepthPeopleTracker(SystemUnderTest):
    def setup(self, ctx: SutContext) -> None:
        self.p: PerceptionParams = sut_params(PerceptionParams, ctx)
        if self.p.z_max <= self.p.z_min:
            raise PluginError(f"{ctx.field}.params.z_max: must be above z_min "
                              f"({self.p.z_min:g}), got {self.p.z_max:g}")
        if self.p.watch_area and len(self.p.watch_area) < 3:
            raise PluginError(f"{ctx.field}.params.watch_area: a polygon needs at least "
                              f"three points, got {len(self.p.watch_area)}")
        self.cams = {name: _Camera() for name in self.p.cameras}
        for name, cam in self.cams.items():
            # Named callbacks rather than lambdas: mypy cannot type a lambda's default argument.
            def on_depth(m: Any, c: _Camera = cam) -> None:
                c.depth = m

            def on_info(m: Any, c: _Camera = cam) -> None:
                self._on_info(c, m)

            ctx.subscribe(f"{name}_depth", "sensor_msgs/msg/Image", on_depth)
            ctx.subscribe(f"{name}_camera_info", "sensor_msgs/msg/CameraInfo", on_info)
        ctx.subscribe(self.p.tf_topic, "tf2_msgs/msg/TFMessage", self._on_tf)
        self.pub = ctx.publisher(self.p.tracks_topic, "visualization_msgs/msg/MarkerArray")
        self.area = np.array(self.p.watch_area, dtype=np.float64) if self.p.watch_area else None
        self.tracks: list[Track] = []
        self.next_id = 1

    def _on_info(self, cam: _Camera, msg: Any) -> None:
        cam.k = np.asarray(msg.k, dtype=np.float64).reshape(3, 3)
        cam.frame_id = msg.header.frame_id

    def _on_tf(self, msg: Any) -> None:
        for tf in msg.transforms:
            if tf.header.frame_id != self.p.world_frame:
                continue
            for cam in self.cams.values():
                if cam.frame_id and tf.child_frame_id == cam.frame_id:
                    t, r = tf.transform.translation, tf.transform.rotation
                    cam.pose = (np.array([t.x, t.y, t.z]), xyzw_to_wxyz([r.x, r.y, r.z, r.w]))

    def _world_points(self, cam: _Camera) -> npt.NDArray[np.float64]:
        msg = cam.depth
        if cam.k is None or cam.pose is None:
            return np.empty((0, 3))
        depth = np.frombuffer(bytes(msg.data), dtype=np.float32).reshape(msg.height, msg.width)
        s = self.p.pixel_stride
        depth = depth[::s, ::s]
        if cam.rays is None or cam.rays[0].shape != depth.shape:
            v, u = np.mgrid[0:msg.height:s, 0:msg.width:s].astype(np.float64)
            fx, fy, cx, cy = cam.k[0, 0], cam.k[1, 1], cam.k[0, 2], cam.k[1, 2]
            cam.rays = ((u - cx) / fx, (v - cy) / fy)
        ok = np.isfinite(depth) & (depth > 0) & (depth <= self.p.max_range)
        d = depth[ok].astype(np.float64)
        optical = np.stack([cam.rays[0][ok] * d, cam.rays[1][ok] * d, d], axis=1)
        t, q = cam.pose
        world: npt.NDArray[np.float64] = _rotate_many(q, optical) + t
        keep = (world[:, 2] >= self.p.z_min) & (world[:, 2] <= self.p.z_max)
        world = world[keep]
        if self.area is not None and len(world):
            world = world[points_in_polygon(world[:, :2], self.area)]
        return world

    def _update(self, detections: list[np.ndarray], now_ns: int) -> None:
        for tr in self.tracks:
            dt = (now_ns - tr.last_ns) / 1e9
            tr.position = tr.position + tr.velocity * dt
            tr.last_ns = now_ns
        matched: set[int] = set()
        if self.tracks and detections:
            cost = np.array([[_distance(tr.position, d) for d in detections]
                             for tr in self.tracks])
            rows, cols = linear_sum_assignment(np.where(cost <= self.p.gate, cost, 1e6))
            for r, c in zip(rows, cols, strict=True):
                if cost[r, c] > self.p.gate:
                    continue
                tr = self.tracks[r]
                innovation = detections[c] - tr.position
                tr.position = tr.position + 0.6 * innovation
                tr.velocity = 0.7 * tr.velocity + 0.3 * innovation * 10.0
                tr.hits += 1
                tr.missed = 0
                matched.add(c)
            for r in set(range(len(self.tracks))) - set(rows[cost[rows, cols] <= self.p.gate]):
                self.tracks[r].missed += 1
        else:
            for tr in self.tracks:
                tr.missed += 1
        for i, d in enumerate(detections):
            if i not in matched:
                self.tracks.append(Track(self.next_id, d.copy(), np.zeros(2), now_ns))
                self.next_id += 1
        self.tracks = [t for t in self.tracks if t.missed <= self.p.max_missed]

    def _publish(self, now_ns: int) -> None:
        # DELETEALL first: each array is the complete current set of tracks.
        markers = [make("visualization_msgs/msg/Marker",
                        header=header(now_ns, self.p.world_frame), action=3)]
        for tr in self.tracks:
            if tr.hits < self.p.min_hits or tr.missed > 0:
                continue
            markers.append(_person_marker(now_ns, self.p.world_frame, tr))
        self.pub.publish(make("visualization_msgs/msg/MarkerArray", markers=markers))

    def step(self, now_ns: int) -> None:
        fresh = [c for c in self.cams.values() if c.depth is not None]
        if not fresh:
            return
        points = [self._world_points(c) for c in fresh]
        for c in fresh:
            c.depth = None
        cloud = np.concatenate(points) if points else np.empty((0, 3))
        self._update(cluster_people(cloud, self.p), now_ns)
        self._publish(now_ns)


def _rotate_many(q: np.ndarray, v: np.ndarray) -> npt.NDArray[np.float64]:
    """Rotate rows of ``v`` by the (w, x, y, z) quaternion ``q``."""
    return rotate_rows(v, mat_from_quat_wxyz(q))


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    """Euclidean distance of two points, the same on every CPU (no BLAS)."""
    gap = (a - b).tolist()
    return math.sqrt(dot_floats(gap, gap))


def _person_marker(now_ns: int, frame: str, tr: Track) -> Any:
    pose = make("geometry_msgs/msg/Pose",
                position=make("geometry_msgs/msg/Point", x=float(tr.position[0]),
                              y=float(tr.position[1]), z=0.9),
                orientation=make("geometry_msgs/msg/Quaternion", w=1.0))
    return make("visualization_msgs/msg/Marker", header=header(now_ns, frame), ns="person",
                id=tr.track_id, type=3, action=0, pose=pose,  # CYLINDER, ADD
                scale=make("geometry_msgs/msg/Vector3", x=0.5, y=0.5, z=1.8),
                color=make("std_msgs/msg/ColorRGBA", r=1.0, g=0.8, b=0.0, a=0.8))
