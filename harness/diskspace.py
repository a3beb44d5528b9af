"""Disk space: the bag size a scenario will need, the check before a run, the guard during it.

:func:`estimate_bag_bytes` is a pure function of the scenario: per published stream, the
number of messages (the tick count, or the frames a ``SimulationGate`` lets through) times
the message size plus what MCAP spends per message. Images are counted exactly (rgb8
``w*h*3``, 32FC1 depth ``w*h*4``), JPEG and PNG by an upper bound and h264 by its expected
size (a camera's ``record``; see :func:`_compressed_bound`);
a point cloud as if every pixel were valid (``w*h*16``,
an upper bound: pixels that see nothing are dropped); small messages (odometry, TF, clock,
IMU, camera_info, ground truth) by their recorded sizes; each system under test gets an
allowance of one small message per tick; the file adds its schemas, indexes and summary.
On the bundled scenes the estimate is 1.0-1.6 times the recorded bag (1.5 for the seed 001
camera, whose point cloud drops the sky), never below it.

The free-space probe is a parameter (:data:`FreeSpace`, default :func:`disk_free`), so the
guard can be exercised without filling a disk.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from harness.errors import DiskSpaceError
from harness.recording.bagfile import MESSAGE_OVERHEAD
from harness.scenario import Scenario, gate_step
from harness.scenario.schema import H264Spec

#: At this crf or above, an h264 frame is expected to take a 32nd of its RGB pixels.
H264_EXPECTED_FROM_CRF = 18

__all__ = [
    "LARGE_BAG",
    "BagEstimate",
    "DiskGuard",
    "FreeSpace",
    "check_free_space",
    "disk_free",
    "estimate_bag_bytes",
    "large_bag_notice",
    "mb",
]

FreeSpace = Callable[[Path], int]

MB = 1_000_000
#: An estimated bag at least this large is announced before the run (and by ``srr validate``).
LARGE_BAG = 1000 * MB
# Serialized sizes (CDR payload bytes) of the small messages, as recorded.
HEADER = 64  # an Image/PointCloud2 header, encoding, dimensions
CAMERA_INFO = 365
ODOMETRY = 724
TF_ONE = 108  # a TFMessage with one transform
ROBOT_LINKS_TF = 220  # a robot's per-tick link transforms (tf_tree)
CLOCK = 12
IMU = 324
SUT_ALLOWANCE = 64  # per system under test per tick
POINT_STEP = 16  # x, y, z float32 + padding
# The file itself: header, schemas (in a chunk and again in the summary), channels, the
# rosbag2 metadata record, statistics; and per chunk its record header and indexes.
FILE_OVERHEAD = 32_000
CHUNK_OVERHEAD = 256


@dataclass(frozen=True)
class BagEstimate:
    """Estimated bag size in bytes, with the streams that make it up (name → bytes), and
    whether any of them is a camera's raw rgb or depth images."""

    total: int
    parts: tuple[tuple[str, int], ...]
    raw_images: bool = False

    def largest(self, n: int = 3) -> str:
        top = sorted(self.parts, key=lambda p: -p[1])[:n]
        return ", ".join(f"{name} {mb(size)}" for name, size in top)


def mb(n: float) -> str:
    return f"{n / MB:,.1f} MB"


def _compressed_bound(stream: str, fmt: str, w: int, h: int, h264: H264Spec,
                      fps: float) -> int:
    """The bytes of one compressed frame: JPEG no more than the RGB pixels, PNG than its
    pixels plus filter bytes and zlib's overhead (upper bounds). h264 by what it is expected
    to take, as no useful bound exists (the guard during the run stops it cleanly should the
    disk fill): with ``bitrate_kbps``, twice its average frame (keyframes are larger); at a
    ``crf`` of 18 or more a 32nd of the RGB pixels (at the default 23 the dock's moving scene
    measures 89 times smaller, keyframes included); below, the raw 4:2:0 picture."""
    if fmt == "h264":
        raw = w * h * 3 // 2
        if h264.bitrate_kbps is not None:
            return min(raw, math.ceil(2 * h264.bitrate_kbps * 1000 / 8 / fps))
        return w * h * 3 // 32 if h264.crf >= H264_EXPECTED_FROM_CRF else raw
    if fmt == "jpeg":
        return w * h * 3
    return w * h * (3 if stream == "rgb" else 2) + h + 1024


def estimate_bag_bytes(scenario: Scenario) -> BagEstimate:
    """Estimate the size of the bag ``scenario`` records (see the module docstring)."""
    hz, ticks = scenario.physics.tick_hz, scenario.n_ticks
    parts: list[tuple[str, int]] = []
    raw_images = False

    def stream(name: str, payload: int, count: int) -> None:
        parts.append((name, count * (payload + MESSAGE_OVERHEAD)))

    def frames(fps: float) -> int:
        return math.ceil(ticks / gate_step(hz, fps))

    if scenario.clock.enabled:
        stream("clock", CLOCK, ticks)
    gt_streams = 0
    for r in scenario.robots:
        if not r.enabled:
            continue
        gt_streams += 1
        if r.odometry.enabled:
            stream(f"{r.name} odometry + tf", ODOMETRY + TF_ONE + MESSAGE_OVERHEAD, ticks)
        if r.tf_tree.enabled and r.model != "forklift":
            stream(f"{r.name} link tf", ROBOT_LINKS_TF, ticks)
        cam, lidar, imu = r.sensors.camera, r.sensors.lidar, r.sensors.imu
        if cam is not None and cam.enabled and cam.graph:
            w, h = cam.resolution
            n = frames(cam.fps)
            if "raw" in cam.record.rgb:
                stream(f"{r.name} camera rgb", HEADER + w * h * 3, n)
                raw_images = True
            stream(f"{r.name} camera_info", CAMERA_INFO, n)
            if cam.depth_topic and "raw" in cam.record.depth:
                stream(f"{r.name} camera depth", HEADER + w * h * 4, n)
                raw_images = True
            for stream_name, formats in (("rgb", cam.record.rgb), ("depth", cam.record.depth)):
                for fmt in formats:
                    if fmt != "raw" and (stream_name == "rgb" or cam.depth_topic):
                        stream(f"{r.name} camera {stream_name} {fmt}", HEADER
                               + _compressed_bound(stream_name, fmt, w, h, cam.record.h264,
                                                   cam.fps), n)
        if lidar is not None and lidar.enabled and lidar.graph:
            size = lidar.beams * (8 if lidar.type == "laser_scan" else POINT_STEP)
            stream(f"{r.name} lidar", HEADER + size, frames(lidar.fps))
        if imu is not None and imu.enabled and imu.graph:
            stream(f"{r.name} imu", IMU, frames(imu.fps))
    for c in scenario.cameras:
        if not c.enabled:
            continue
        w, h = c.resolution
        n = frames(c.fps)
        per_pixel = {"rgb": 3, "depth": 4, "pointcloud": POINT_STEP}
        for out in c.outputs:
            if out == "camera_info":
                stream(f"{c.name}_camera_info", CAMERA_INFO, n)
            elif out not in ("rgb", "depth") or "raw" in getattr(c.record, out):
                stream(f"{c.name}_{out}", HEADER + w * h * per_pixel[out], n)
                raw_images = raw_images or out in ("rgb", "depth")
        for stream_name, formats in (("rgb", c.record.rgb), ("depth", c.record.depth)):
            for fmt in formats:
                if fmt != "raw" and stream_name in c.outputs:
                    stream(f"{c.name}_{stream_name} {fmt}", HEADER
                           + _compressed_bound(stream_name, fmt, w, h, c.record.h264, c.fps),
                           n)
        stream(f"{c.name} tf", TF_ONE, ticks)
    if scenario.srr_gt:
        gt_streams += sum(1 for wk in scenario.workers if wk.enabled)
        stream("ground truth", TF_ONE * gt_streams + MESSAGE_OVERHEAD * (gt_streams - 1),
               ticks)
    suts = sum(1 for s in scenario.systems_under_test if s.enabled)
    if suts:
        stream("systems under test", SUT_ALLOWANCE * suts + MESSAGE_OVERHEAD * (suts - 1),
               ticks)
    chunks = math.ceil(scenario.duration / scenario.recording.chunk_s)
    parts.append(("file overhead", FILE_OVERHEAD + CHUNK_OVERHEAD * chunks))
    return BagEstimate(sum(size for _, size in parts), tuple(parts), raw_images)


def large_bag_notice(scenario: Scenario, est: BagEstimate | None = None) -> str | None:
    """One line announcing the bag's estimated size when it is at least :data:`LARGE_BAG`
    (None below), with its largest streams, so a costly default is seen before it is paid."""
    est = est or estimate_bag_bytes(scenario)
    if est.total < LARGE_BAG:
        return None
    return (f"the bag will be up to about {est.total / 1e9:,.1f} GB for "
            f"{scenario.duration:g} s ({est.largest()}); "
            + ("a camera's record: {rgb: [h264], depth: [png]}, " if est.raw_images else "")
            + "a lower fps or resolution, or fewer outputs make it smaller")


def disk_free(path: Path) -> int:
    """Free bytes (for an unprivileged user) on the filesystem ``path`` is, or would be, on."""
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return shutil.disk_usage(p).free


def check_free_space(scenario: Scenario, run_dir: Path, free_space: FreeSpace) -> BagEstimate:
    """Refuse to start (:class:`DiskSpaceError`, exit 2) when the free space at ``run_dir`` is
    below the estimated bag size plus ``recording.min_free_mb``."""
    est = estimate_bag_bytes(scenario)
    margin = int(scenario.recording.min_free_mb * MB)
    free = free_space(run_dir)
    if free < est.total + margin:
        raise DiskSpaceError(
            f"{run_dir}: not enough free disk space to record {scenario.name}: "
            f"{mb(free)} free, the bag needs about {mb(est.total)} ({est.largest()}) "
            f"plus recording.min_free_mb {mb(margin)}")
    return est


class DiskGuard:
    """Probes free space during a run, at most every ``every_ticks`` ticks or every
    ``every_bytes`` serialized bytes, whichever comes first; :meth:`poll` returns why the run
    must stop (free space below ``min_free`` bytes), else None."""

    def __init__(self, path: Path, min_free: int, free_space: FreeSpace, *,
                 every_ticks: int, every_bytes: int = 16 * MB) -> None:
        self.path = Path(path)
        self.min_free = min_free
        self.free_space = free_space
        self.every_ticks = max(1, every_ticks)
        self.every_bytes = every_bytes
        self.probes = 0
        self._tick = 0
        self._bytes = 0

    def poll(self, tick: int, bytes_written: int) -> str | None:
        if (tick - self._tick < self.every_ticks
                and bytes_written - self._bytes < self.every_bytes):
            return None
        self._tick, self._bytes = tick, bytes_written
        self.probes += 1
        free = self.free_space(self.path)
        if free >= self.min_free:
            return None
        return (f"free disk space at {self.path} fell to {mb(free)}, below "
                f"recording.min_free_mb ({mb(self.min_free)})")
