"""Synthetic rosbag2 (MCAP) writer: a forklift shuttling in and out of a trailer, workers
walking loops, a noisy person tracker, a lagging safety monitor.

Used by the frames tests and by ``benchmarks/bench_scoring.py``. Everything is derived from
closed-form motion and a seeded generator, so the known answers can be computed in the test.

Layout (world frame, metres): route along y = 0 from x = 3 to x = 21; trailer tripwire at
x = 15 (inside is x > 15); loading ROI the box x in [10, 15], y in [-3, 3]. ``character_0``
walks a circle that crosses the ROI; the others stay away from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer

from harness.geometry import quat_wxyz_from_yaw, wxyz_to_xyzw
from harness.serde.messages import (
    TYPESTORE,
    clock,
    header,
    msg_type,
    odometry,
    tf_message,
    transform_stamped,
    twist,
)

__all__ = ["ROI", "TRIPWIRE", "SynthSpec", "character_xy", "forklift_xy", "write_synthetic_bag"]

TRIPWIRE = ((15.0, -1.3), (15.0, 1.3))  # inside (x > 15) is on the right of a → b
ROI = ((10.0, -3.0), (15.0, -3.0), (15.0, 3.0), (10.0, 3.0))
ODOM_ORIGIN = (3.0, 0.0)  # world → odom translation (identity rotation)
X0, X1 = 3.0, 21.0


@dataclass(frozen=True)
class SynthSpec:
    duration_s: float = 10.0
    tick_hz: int = 60
    n_characters: int = 4
    marker_hz: int = 30
    cmd_hz: int = 20
    muted_hz: int = 20
    mute_lag_s: float = 0.25
    noise_m: float = 0.05
    seed: int = 0
    frame_prefix: str = ""  # e.g. "forklift/" to name odom frames per robot


def forklift_xy(t: float, period: float = 24.0) -> tuple[float, float, float]:
    """Triangle wave along the route: (x, y, heading)."""
    u = (t % period) / period
    if u < 0.5:
        return X0 + (X1 - X0) * 2 * u, 0.0, 0.0
    return X1 - (X1 - X0) * 2 * (u - 0.5), 0.0, math.pi


def character_xy(i: int, t: float) -> tuple[float, float]:
    if i == 0:  # circle of radius 4 around (10, 0): crosses the ROI
        a = 0.25 * t
        return 10.0 + 4.0 * math.cos(a), 4.0 * math.sin(a)
    cx, cy = -10.0 + 4.0 * i, 7.0 if i % 2 else -7.0
    a = 0.3 * t + i
    return cx + 1.5 * math.cos(a), cy + 1.0 * math.sin(a)


def _inside(x: float, y: float) -> bool:
    return x > 15.0


def _in_roi(x: float, y: float) -> bool:
    return 10.0 <= x <= 15.0 and -3.0 <= y <= 3.0


def expected_muted(t: float, n_characters: int) -> bool:
    fx, fy, _ = forklift_xy(t)
    return _inside(fx, fy) and not any(_in_roi(*character_xy(i, t))
                                       for i in range(n_characters))


def _marker(ns_: int, name: str, track_id: int, x: float, y: float, action: int = 0) -> Any:
    m = msg_type("visualization_msgs/msg/Marker")
    pose = msg_type("geometry_msgs/msg/Pose")(
        position=msg_type("geometry_msgs/msg/Point")(x=x, y=y, z=0.9),
        orientation=msg_type("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0))
    return m(
        header=header(ns_, "world"), ns=name, id=track_id, type=3, action=action, pose=pose,
        scale=msg_type("geometry_msgs/msg/Vector3")(x=0.5, y=0.5, z=1.8),
        color=msg_type("std_msgs/msg/ColorRGBA")(r=0.0, g=1.0, b=0.0, a=1.0),
        lifetime=msg_type("builtin_interfaces/msg/Duration")(sec=0, nanosec=0),
        frame_locked=False, points=[], colors=[], texture_resource="",
        texture=msg_type("sensor_msgs/msg/CompressedImage")(
            header=header(0, ""), format="", data=np.zeros(0, dtype=np.uint8)),
        uv_coordinates=[], text="", mesh_resource="",
        mesh_file=msg_type("visualization_msgs/msg/MeshFile")(
            filename="", data=np.zeros(0, dtype=np.uint8)),
        mesh_use_embedded_materials=False)


def write_synthetic_bag(path: Path, spec: SynthSpec = SynthSpec()) -> int:
    """Write the bag at ``path`` (must not exist); return the number of messages written."""
    rng = np.random.default_rng(spec.seed)
    n_ticks = round(spec.duration_s * spec.tick_hz)
    odom_frame = f"{spec.frame_prefix}odom"
    base_frame = f"{spec.frame_prefix}base_link"
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    conns: dict[str, Any] = {}
    count = 0

    def write(topic: str, msgtype: str, t_ns: int, msg: Any) -> None:
        nonlocal count
        if topic not in conns:
            conns[topic] = writer.add_connection(topic, msgtype, typestore=TYPESTORE)
        writer.write(conns[topic], t_ns, bytes(TYPESTORE.serialize_cdr(msg, msgtype)))
        count += 1

    tf = "tf2_msgs/msg/TFMessage"
    write("/tf_static", tf, 0, tf_message([transform_stamped(
        0, "world", odom_frame, (*ODOM_ORIGIN, 0.0), (0.0, 0.0, 0.0, 1.0))]))
    names = ["forklift"] + [f"character_{i}" for i in range(spec.n_characters)]
    lag_ticks = round(spec.mute_lag_s * spec.tick_hz)
    id_offset = 0
    for k in range(n_ticks):
        t_ns = k * 1_000_000_000 // spec.tick_hz
        t = t_ns / 1e9
        write("/clock", "rosgraph_msgs/msg/Clock", t_ns, clock(t_ns))
        fx, fy, fyaw = forklift_xy(t)
        q = wxyz_to_xyzw(quat_wxyz_from_yaw(fyaw))
        speed = 1.5 if fyaw == 0.0 else -1.5
        write("/odom", "nav_msgs/msg/Odometry", t_ns, odometry(
            t_ns, odom_frame, base_frame, (fx - ODOM_ORIGIN[0], fy - ODOM_ORIGIN[1], 0.0), q,
            (abs(speed), 0.0, 0.0), (0.0, 0.0, 0.0)))
        write("/tf", tf, t_ns, tf_message([transform_stamped(
            t_ns, odom_frame, base_frame, (fx - ODOM_ORIGIN[0], fy - ODOM_ORIGIN[1], 0.0), q)]))
        for name in names:
            if name == "forklift":
                x, y, qq = fx, fy, q
            else:
                x, y = character_xy(int(name.split("_")[1]), t)
                qq = (0.0, 0.0, 0.0, 1.0)
            write(f"/gt/{name}/tf", tf, t_ns, tf_message([transform_stamped(
                t_ns, "world", name, (x, y, 0.0), qq)]))
        if k % (spec.tick_hz // spec.cmd_hz) == 0:
            write("/cmd_vel", "geometry_msgs/msg/Twist", t_ns,
                  twist((1.5, 0.0, 0.0), (0.0, 0.0, 0.0)))
        if k % (spec.tick_hz // spec.muted_hz) == 0:
            lagged = max(k - lag_ticks, 0) * 1_000_000_000 // spec.tick_hz / 1e9
            write("/safety/is_muted", "std_msgs/msg/Bool", t_ns,
                  msg_type("std_msgs/msg/Bool")(data=expected_muted(lagged, spec.n_characters)))
        if k % (spec.tick_hz // spec.marker_hz) == 0:
            if k % (spec.tick_hz * 20) == 0 and k:
                id_offset += 100  # every 20 s every track gets a new id: ID switches
            markers = [_marker(t_ns, "", 0, 0.0, 0.0, action=3)]  # DELETEALL
            for i in range(spec.n_characters):
                if rng.random() < 0.05:
                    continue  # missed detection
                x, y = character_xy(i, t)
                dx, dy = rng.normal(0.0, spec.noise_m, 2)
                markers.append(_marker(t_ns, "person", id_offset + i, x + dx, y + dy))
            if rng.random() < 0.05:  # clutter
                markers.append(_marker(t_ns, "person", 999, float(rng.uniform(-14, 14)),
                                       float(rng.uniform(-9, 9))))
            write("/perception/tracks", "visualization_msgs/msg/MarkerArray", t_ns,
                  msg_type("visualization_msgs/msg/MarkerArray")(markers=markers))
    writer.close()
    return count
