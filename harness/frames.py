"""Recorded frames: a run's bag read back into pandas tables that the metrics score.

:func:`load_frames` reads a rosbag2 directory once, keeps the raw CDR payloads of the topics
the metrics need and decodes them per topic in batches. Every other topic is only counted.

Decoding is columnar. For each topic a *template* message is walked with a small CDR cursor
that records where every wanted field sits and which bytes decide the layout (string lengths
and contents, sequence lengths, the encapsulation). Every message of the same length whose
layout bytes equal the template's has its fields at the same offsets, so they are read for all
of those messages at once with numpy. Messages that fit no template are decoded one by one
with ``rosbags``' ``deserialize_cdr``; both paths give the same values (a test checks it).
A ROS 1 recording (:mod:`harness.recording.bagread`) is read the same way: the cursor walks ROS 1
serialization instead (no encapsulation or alignment, a ``seq`` in every header, ROS 1's
shorter ``Marker``) and the slow path decodes with rosbags' Noetic types, so every table
below is the same whichever ROS the run recorded.

Tables (all times are simulation time in integer nanoseconds):

* ``clock``: ``t_ns`` (the ``/clock`` value), ``log_ns``.
* ``gt_poses``: ``t_ns, name, x, y, z, yaw`` from every ``/gt/<name>/tf`` topic; the name
  comes from the topic. A message with several transforms gives the one whose
  ``child_frame_id`` is the name, else its first.
* ``odom``: ``t_ns, topic, frame, x, y, yaw, vx, wz`` per ``nav_msgs/Odometry`` topic, moved
  into the world frame with the ``/tf_static`` chain from the world frame to the message's
  ``header.frame_id``; ``frame`` is the world frame's name, or the odom frame's own when no
  static chain reaches it (the pose is then left in that frame). ``vx``/``wz`` are the twist
  in the child (body) frame, as published.
* ``cmd_vel``: ``t_ns, topic, vx, wz`` per ``geometry_msgs/Twist`` topic (log time).
* ``track_frames``: ``frame, t_ns, log_ns, topic``: one row per ``MarkerArray`` message,
  including empty ones (an empty array is a frame in which nothing was tracked).
* ``tracks``: ``frame, t_ns, topic, cls, track_id, x, y``: every ADD/MODIFY marker; ``cls``
  is the marker's ``ns``. DELETE and DELETEALL markers are not tracks. Each message is the
  full set of tracked objects at its time; ``t_ns`` is the frame's time: the header stamp of
  its first track, or its log time when that stamp is zero or the frame is empty.
* ``muted``: ``t_ns, value`` from ``/safety/is_muted`` (log time; Bool has no header).
* ``topics``: ``name, type, count, first_ns, last_ns, max_gap_ns`` for every topic in the
  bag (log times).
* ``tf``: ``t_ns, log_ns, topic, tree, static, parent, child, x, y, z, qx, qy, qz, qw``: every
  transform on a TF-tree topic (``/tf``, ``/tf_static``, ``/<ns>/tf``...; not ``/gt/*``),
  ``tree`` its namespace (:func:`~harness.bus.endpoints.tf_tree_of`), ``static`` whether
  the topic is a ``tf_static`` one, ``t_ns`` the header stamp. A ROS 1 recording's latched
  ``tf_static`` topics hold in each message every static transform sent so far (as ROS 1's
  static broadcaster sends them; :mod:`harness.recording.ros1bag`): a transform is a row
  where it was sent, not again in each later message that carries it unchanged (the same
  parent, stamp and pose as that child frame's transform before), so the rows are those of
  the same run recorded as ROS 2.
* ``tf_static``: ``parent, child, x, y, z, qx, qy, qz, qw``: the static rows of ``tf``, the
  chain that places odometry in the world frame.
* ``fields``: ``(topic, field path) →`` :class:`FieldSeries`, the numeric fields asked for
  with ``fields=`` (the ``topic(...)`` signals of a scenario's specs), by log time.

Few-valued string columns (``name``, ``topic``, ``frame``, ``cls``) are pandas categoricals;
they compare and filter like strings. Tables keep the bag's order (time order per topic).
"""

from __future__ import annotations

import re
import struct
from array import array
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from dataclasses import field as dataclass_field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from pandas.api.types import union_categoricals
from rosbags.serde import SerdeError

from harness.bus.endpoints import is_static_tf_topic, tf_tree_of
from harness.geometry import (
    quat_xyzw_mul_columns,
    quat_xyzw_rotate_columns,
    yaw_from_quat_xyzw_columns,
)
from harness.recording.bagread import DECODE_ERRORS, Encoding, open_indexed, ros1_recording
from harness.recording.errors import BagError
from harness.recording.ros1bag import accumulates_static_tf
from harness.serde.messages import TYPESTORE
from harness.serde.ros1 import deserialize_ros1

__all__ = [
    "CLOCK",
    "GT_TOPIC",
    "MARKER_ARRAY",
    "ODOMETRY",
    "SUPPORTED_TYPES",
    "TF_MESSAGE",
    "TWIST",
    "FieldSeries",
    "Frames",
    "decode_batch",
    "load_frames",
]

CLOCK = "rosgraph_msgs/msg/Clock"
BOOL = "std_msgs/msg/Bool"
TWIST = "geometry_msgs/msg/Twist"
ODOMETRY = "nav_msgs/msg/Odometry"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
MARKER_ARRAY = "visualization_msgs/msg/MarkerArray"
SUPPORTED_TYPES = (CLOCK, BOOL, TWIST, ODOMETRY, TF_MESSAGE, MARKER_ARRAY)

GT_TOPIC = re.compile(r"^/gt/(?P<name>[^/]+)/tf$")

_MARKER_ADD = 0  # ADD and MODIFY share the value; DELETE = 2 and DELETEALL = 3 are not tracks


# --------------------------------------------------------------------------- frames table


@dataclass(frozen=True)
class FieldSeries:
    """One numeric field of one topic: ``value`` at each message's log time ``t_ns`` (a bool
    field is 1 or 0). ``error`` says why there are no values (no such topic, a path the
    message does not have, not a number); empty when the field was read."""

    t_ns: np.ndarray
    value: np.ndarray
    error: str = ""


def field_path(path: str) -> list[str | int]:
    """``twist.twist.linear.x`` / ``ranges[3]`` as attribute names and list indexes."""
    out: list[str | int] = []
    for part in path.split("."):
        name, *idx = part.split("[")
        out.append(name)
        out += [int(i.rstrip("]")) for i in idx]
    return out


def _field_value(msg: Any, steps: Sequence[str | int], path: str) -> float:
    """The number at ``steps`` in ``msg``; ValueError saying what is wrong."""
    v = msg
    for step in steps:
        if isinstance(step, int):
            try:
                v = v[step]
            except (IndexError, TypeError, KeyError) as err:
                raise ValueError(f"{path}: no item [{step}]") from err
        else:
            if not hasattr(v, step) or step.startswith("_"):
                have = ", ".join(k for k in getattr(v, "__dataclass_fields__", {})
                                 if not k.startswith("_"))
                raise ValueError(f"{path}: no field {step!r}" + (f" (fields: {have})"
                                                                 if have else ""))
            v = getattr(v, step)
    if isinstance(v, bool | np.bool_):
        return 1.0 if v else 0.0
    if isinstance(v, int | float | np.integer | np.floating):
        return float(v)
    raise ValueError(f"{path}: not a number ({type(v).__name__})")


@dataclass(frozen=True)
class Frames:
    """A run's recorded frames. Treat the tables as read-only: metrics never mutate them."""

    clock: pd.DataFrame
    gt_poses: pd.DataFrame
    odom: pd.DataFrame
    cmd_vel: pd.DataFrame
    tracks: pd.DataFrame
    track_frames: pd.DataFrame
    muted: pd.DataFrame
    topics: pd.DataFrame
    tf_static: pd.DataFrame
    tf: pd.DataFrame
    start_ns: int
    end_ns: int
    message_count: int
    world_frame: str = "world"
    fields: Mapping[tuple[str, str], FieldSeries] = dataclass_field(default_factory=dict)

    def gt(self, name: str) -> pd.DataFrame:
        """Ground-truth poses of one object, sorted by time."""
        g = self.gt_poses
        return g[g["name"] == name].sort_values("t_ns", kind="stable").reset_index(drop=True)

    @property
    def gt_names(self) -> tuple[str, ...]:
        return tuple(sorted(str(n) for n in self.gt_poses["name"].unique()))

    @property
    def duration_s(self) -> float:
        return (self.end_ns - self.start_ns) / 1e9


# --------------------------------------------------------------------------- CDR layout walk


class _LayoutError(Exception):
    """A message does not parse with the cursor (truncated, odd sizes): decode it slowly."""


_U32 = struct.Struct("<I")

# field name → (byte offset in the raw message, numpy dtype)
_Fields = dict[str, tuple[int, str]]
# one output row: numeric fields and constant strings
_Item = tuple[_Fields, dict[str, str]]


class _Cursor:
    """Walks one little-endian CDR message (or, ``ros1``, one ROS 1 message: no encapsulation,
    no alignment, strings without a terminating NUL, a ``seq`` first in each header), noting
    field offsets and layout bytes."""

    __slots__ = ("buf", "const", "pos", "ros1")

    def __init__(self, buf: bytes, ros1: bool = False) -> None:
        self.buf = buf
        self.ros1 = ros1
        if ros1:
            self.pos = 0
            self.const: list[tuple[int, int]] = []
            return
        if len(buf) < 4 or buf[0] != 0 or buf[1] != 1:
            raise _LayoutError("not little-endian CDR")
        self.pos = 4
        self.const = [(0, 2)]

    def _align(self, n: int) -> None:
        if not self.ros1:
            self.pos += (-(self.pos - 4)) % n

    def field(self, size: int) -> int:
        self._align(size)
        p = self.pos
        self.pos += size
        if self.pos > len(self.buf):
            raise _LayoutError("truncated")
        return p

    def count(self) -> int:
        p = self.field(4)
        self.const.append((p, p + 4))
        return int(_U32.unpack_from(self.buf, p)[0])

    def string(self) -> str:
        n = self.count()
        p = self.pos
        self.pos += n
        if self.ros1:
            if self.pos > len(self.buf):
                raise _LayoutError("bad string")
            if n:
                self.const.append((p, p + n))
            return self.buf[p:p + n].decode()
        if self.pos > len(self.buf) or n == 0 or self.buf[self.pos - 1] != 0:
            raise _LayoutError("bad string")
        self.const.append((p, p + n))
        return self.buf[p:p + n - 1].decode()

    def skip_seq(self, elem_size: int, align: int) -> None:
        n = self.count()
        if n:
            self._align(align)
            self.pos += n * elem_size
            if self.pos > len(self.buf):
                raise _LayoutError("truncated")

    def skip(self, size: int, align: int) -> None:
        self._align(align)
        self.pos += size
        if self.pos > len(self.buf):
            raise _LayoutError("truncated")

    def finish(self) -> None:
        if not 0 <= len(self.buf) - self.pos < (1 if self.ros1 else 8):
            raise _LayoutError("size mismatch")

    def header(self, f: _Fields, s: dict[str, str]) -> None:
        if self.ros1:
            self.field(4)  # seq
            f["sec"] = (self.field(4), "<u4")
        else:
            f["sec"] = (self.field(4), "<i4")
        f["nanosec"] = (self.field(4), "<u4")
        s["frame_id"] = self.string()


def _walk_clock(c: _Cursor) -> list[_Item]:
    f: _Fields = {"sec": (c.field(4), "<u4" if c.ros1 else "<i4"),
                  "nanosec": (c.field(4), "<u4")}
    return [(f, {})]


def _walk_bool(c: _Cursor) -> list[_Item]:
    return [({"data": (c.field(1), "u1")}, {})]


def _walk_twist(c: _Cursor) -> list[_Item]:
    f: _Fields = {}
    for k in ("vx", "vy", "vz", "wx", "wy", "wz"):
        f[k] = (c.field(8), "<f8")
    return [(f, {})]


def _walk_pose(c: _Cursor, f: _Fields) -> None:
    for k in ("x", "y", "z", "qx", "qy", "qz", "qw"):
        f[k] = (c.field(8), "<f8")


def _walk_odometry(c: _Cursor) -> list[_Item]:
    f: _Fields = {}
    s: dict[str, str] = {}
    c.header(f, s)
    s["child_frame_id"] = c.string()
    _walk_pose(c, f)
    c.skip(36 * 8, 8)
    for k in ("vx", "vy", "vz", "wx", "wy", "wz"):
        f[k] = (c.field(8), "<f8")
    c.skip(36 * 8, 8)
    return [(f, s)]


def _walk_tf(c: _Cursor) -> list[_Item]:
    items: list[_Item] = []
    for _ in range(c.count()):
        f: _Fields = {}
        s: dict[str, str] = {}
        c.header(f, s)
        s["child_frame_id"] = c.string()
        _walk_pose(c, f)
        items.append((f, s))
    return items


def _walk_marker_array(c: _Cursor) -> list[_Item]:
    items: list[_Item] = []
    for _ in range(c.count()):
        f: _Fields = {}
        s: dict[str, str] = {}
        c.header(f, s)
        s["ns"] = c.string()
        f["id"] = (c.field(4), "<i4")
        c.field(4)  # type
        f["action"] = (c.field(4), "<i4")
        _walk_pose(c, f)
        c.skip(3 * 8, 8)  # scale
        c.skip(4 * 4, 4)  # color
        c.skip(2 * 4, 4)  # lifetime
        c.field(1)  # frame_locked
        c.skip_seq(3 * 8, 8)  # points
        c.skip_seq(4 * 4, 4)  # colors
        if c.ros1:  # ROS 1's Marker ends here, without texture, uv and mesh-file fields
            c.string()  # text
            c.string()  # mesh_resource
            c.field(1)  # mesh_use_embedded_materials
            items.append((f, s))
            continue
        c.string()  # texture_resource
        c.field(4)  # texture.header.stamp
        c.field(4)
        c.string()  # texture.header.frame_id
        c.string()  # texture.format
        c.skip_seq(1, 1)  # texture.data
        c.skip_seq(2 * 4, 4)  # uv_coordinates
        c.string()  # text
        c.string()  # mesh_resource
        c.string()  # mesh_file.filename
        c.skip_seq(1, 1)  # mesh_file.data
        c.field(1)  # mesh_use_embedded_materials
        items.append((f, s))
    return items


_WALKERS: dict[str, Callable[[_Cursor], list[_Item]]] = {
    CLOCK: _walk_clock,
    BOOL: _walk_bool,
    TWIST: _walk_twist,
    ODOMETRY: _walk_odometry,
    TF_MESSAGE: _walk_tf,
    MARKER_ARRAY: _walk_marker_array,
}


# --------------------------------------------------------------------------- slow path


def _obj_header(h: Any, out: dict[str, Any]) -> None:
    out["sec"] = h.stamp.sec
    out["nanosec"] = h.stamp.nanosec
    out["frame_id"] = h.frame_id


def _obj_pose(p: Any, out: dict[str, Any]) -> None:
    out.update(x=p.position.x, y=p.position.y, z=p.position.z, qx=p.orientation.x,
               qy=p.orientation.y, qz=p.orientation.z, qw=p.orientation.w)


def _obj_twist(t: Any, out: dict[str, Any]) -> None:
    out.update(vx=t.linear.x, vy=t.linear.y, vz=t.linear.z,
               wx=t.angular.x, wy=t.angular.y, wz=t.angular.z)


def _obj_items(msg: Any, msgtype: str) -> list[dict[str, Any]]:
    out: dict[str, Any] = {}
    if msgtype == CLOCK:
        return [{"sec": msg.clock.sec, "nanosec": msg.clock.nanosec}]
    if msgtype == BOOL:
        return [{"data": int(msg.data)}]
    if msgtype == TWIST:
        _obj_twist(msg, out)
        return [out]
    if msgtype == ODOMETRY:
        _obj_header(msg.header, out)
        out["child_frame_id"] = msg.child_frame_id
        _obj_pose(msg.pose.pose, out)
        _obj_twist(msg.twist.twist, out)
        return [out]
    items = []
    if msgtype == TF_MESSAGE:
        for tf in msg.transforms:
            d: dict[str, Any] = {}
            _obj_header(tf.header, d)
            d["child_frame_id"] = tf.child_frame_id
            tr, rot = tf.transform.translation, tf.transform.rotation
            d.update(x=tr.x, y=tr.y, z=tr.z, qx=rot.x, qy=rot.y, qz=rot.z, qw=rot.w)
            items.append(d)
        return items
    for m in msg.markers:
        d = {}
        _obj_header(m.header, d)
        d.update(ns=m.ns, id=m.id, action=m.action)
        _obj_pose(m.pose, d)
        items.append(d)
    return items


# --------------------------------------------------------------------------- batch decoding

_MAX_TEMPLATES = 64
_INT_FIELDS = frozenset({"msg", "item", "sec", "nanosec", "id", "action", "data"})


def _fields_of(msgtype: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(numeric, string) field names each decoded item of ``msgtype`` has."""
    num = {
        CLOCK: ("sec", "nanosec"),
        BOOL: ("data",),
        TWIST: ("vx", "vy", "vz", "wx", "wy", "wz"),
        ODOMETRY: ("sec", "nanosec", "x", "y", "z", "qx", "qy", "qz", "qw",
                   "vx", "vy", "vz", "wx", "wy", "wz"),
        TF_MESSAGE: ("sec", "nanosec", "x", "y", "z", "qx", "qy", "qz", "qw"),
        MARKER_ARRAY: ("sec", "nanosec", "id", "action", "x", "y", "z", "qx", "qy", "qz",
                       "qw"),
    }[msgtype]
    strs = {
        ODOMETRY: ("frame_id", "child_frame_id"),
        TF_MESSAGE: ("frame_id", "child_frame_id"),
        MARKER_ARRAY: ("frame_id", "ns"),
    }.get(msgtype, ())
    return num, strs


def _gather(u8: np.ndarray, starts: np.ndarray, offset: int, dtype: str) -> np.ndarray:
    size = np.dtype(dtype).itemsize
    idx = starts[:, None] + (offset + np.arange(size))[None, :]
    return u8[idx].view(dtype).reshape(len(starts))


def _strided(u8: np.ndarray, n: int, length: int, offset: int, dtype: str) -> np.ndarray:
    """Field at ``offset`` of ``n`` back-to-back messages of ``length`` bytes each."""
    view = np.ndarray((n,), dtype=np.dtype(dtype), buffer=u8, offset=offset,
                      strides=(length,))
    return view.copy()


def decode_batch(raws: Sequence[bytes], msgtype: str, *, fast: bool = True,
                 encoding: Encoding = "cdr") -> dict[str, np.ndarray]:
    """Decode CDR messages (``encoding="ros1"``: ROS 1 messages of the same type's ROS 1
    counterpart) of one type into columns.

    Returns ``msg`` (index of the message each row came from), ``item`` (index of the row
    inside its message: transform or marker number), ``fast`` (whether the row was read by
    the vectorized path) plus the type's fields (see
    :data:`SUPPORTED_TYPES`; numbers as float64/int64, strings as object arrays). Rows are
    ordered by message, then item. ``fast=False`` decodes every message with rosbags.
    Raises :class:`BagError` for a message that cannot be decoded at all.
    """
    if msgtype not in _WALKERS:
        raise BagError(f"cannot decode message type {msgtype!r}")
    num, strs = _fields_of(msgtype)
    cols: dict[str, list[np.ndarray]] = {k: [] for k in ("msg", "item", "fast", *num, *strs)}
    n = len(raws)
    lengths = np.fromiter((len(r) for r in raws), dtype=np.int64, count=n)
    remaining = np.arange(n) if fast else np.zeros(0, dtype=np.int64)
    slow: list[int] = [] if fast else list(range(n))
    if fast and n:
        blob = np.frombuffer(b"".join(raws), dtype=np.uint8)
        starts_all = np.concatenate(([0], np.cumsum(lengths)[:-1]))
        templates = 0
        while remaining.size:
            t = int(remaining[0])
            if templates >= _MAX_TEMPLATES:
                slow.extend(int(i) for i in remaining)
                break
            templates += 1
            try:
                cur = _Cursor(raws[t], ros1=encoding == "ros1")
                items = _WALKERS[msgtype](cur)
                cur.finish()
            except (_LayoutError, UnicodeDecodeError):
                slow.append(t)
                remaining = remaining[1:]
                continue
            cand = remaining[lengths[remaining] == lengths[t]]
            starts = starts_all[cand]
            const_idx = np.concatenate([np.arange(a, b) for a, b in cur.const]
                                       or [np.zeros(0, dtype=np.int64)])
            same = (blob[starts[:, None] + const_idx[None, :]]
                    == blob[starts_all[t] + const_idx][None, :]).all(axis=1)
            rows, starts = cand[same], starts[same]
            remaining = np.setdiff1d(remaining, rows, assume_unique=True)
            uniform = rows.size == n and bool((lengths == lengths[t]).all())
            for j, (f, s) in enumerate(items):
                cols["msg"].append(rows)
                cols["item"].append(np.full(rows.size, j, dtype=np.int64))
                cols["fast"].append(np.ones(rows.size, dtype=np.int64))
                for k in num:
                    off, dt = f[k]
                    cols[k].append(_strided(blob, n, int(lengths[t]), off, dt) if uniform
                                   else _gather(blob, starts, off, dt))
                for k in strs:
                    cols[k].append(np.full(rows.size, s[k], dtype=object))
    if slow:
        recs: dict[str, list[Any]] = {k: [] for k in cols}
        for i in slow:
            try:
                msg = (deserialize_ros1(raws[i], msgtype) if encoding == "ros1"
                       else TYPESTORE.deserialize_cdr(raws[i], msgtype))
            except SerdeError as err:
                raise BagError(f"message {i} of type {msgtype}: {err}") from err
            for j, d in enumerate(_obj_items(msg, msgtype)):
                recs["msg"].append(i)
                recs["item"].append(j)
                recs["fast"].append(0)
                for k in (*num, *strs):
                    recs[k].append(d[k])
        for k, v in recs.items():
            cols[k].append(np.array(v, dtype=object if k in strs else None))
    out: dict[str, np.ndarray] = {}
    for k, parts in cols.items():
        dtype = (object if k in strs else bool if k == "fast"
                 else np.int64 if k in _INT_FIELDS else np.float64)
        out[k] = (np.concatenate([p.astype(dtype) for p in parts]) if parts
                  else np.zeros(0, dtype=dtype))
    order = np.lexsort((out["item"], out["msg"]))
    return {k: v[order] for k, v in out.items()}


# --------------------------------------------------------------------------- transforms


_Transform = tuple[np.ndarray, np.ndarray]  # translation (3,), rotation xyzw (4,)


def _chain(static: dict[str, tuple[str, _Transform]], world: str, frame: str
           ) -> _Transform | None:
    """Pose of ``frame`` in ``world`` from the static tree, or None when not connected."""
    t = np.zeros(3)
    q = np.array([0.0, 0.0, 0.0, 1.0])
    seen = set()
    cur = frame
    while cur != world:
        if cur in seen or cur not in static:
            return None
        seen.add(cur)
        parent, (pt, pq) = static[cur]
        t = pt + quat_xyzw_rotate_columns(pq, t)
        q = quat_xyzw_mul_columns(pq, q)
        cur = parent
    return t, q


# --------------------------------------------------------------------------- tables


def _stamp(cols: dict[str, np.ndarray]) -> np.ndarray:
    return cols["sec"].astype(np.int64) * 1_000_000_000 + cols["nanosec"].astype(np.int64)


def _empty(columns: dict[str, str]) -> pd.DataFrame:
    return pd.DataFrame({k: pd.Series(dtype=v) for k, v in columns.items()})


_GT_COLS = {"t_ns": "int64", "name": "category", "x": "float64", "y": "float64",
            "z": "float64", "yaw": "float64"}
_ODOM_COLS = {"t_ns": "int64", "topic": "category", "frame": "category", "x": "float64",
              "y": "float64", "yaw": "float64", "vx": "float64", "wz": "float64"}
_CMD_COLS = {"t_ns": "int64", "topic": "category", "vx": "float64", "wz": "float64"}
_TRACK_COLS = {"frame": "int64", "t_ns": "int64", "topic": "category", "cls": "category",
               "track_id": "int64", "x": "float64", "y": "float64"}
_TFRAME_COLS = {"frame": "int64", "t_ns": "int64", "log_ns": "int64", "topic": "category"}


def _concat(parts: list[pd.DataFrame], columns: dict[str, str]) -> pd.DataFrame:
    """One table from per-topic parts; the few-valued string columns become categoricals
    (fast to compare and group; they behave as strings otherwise)."""
    if not parts:
        return _empty(columns)
    df = pd.concat(parts, ignore_index=True)
    for k, dtype in columns.items():
        if dtype == "category":
            df[k] = pd.Categorical(df[k].to_numpy(dtype=object))
    return df


def _gt_table(name: str, cols: dict[str, np.ndarray]) -> pd.DataFrame:
    msg = cols["msg"]
    if msg.size == 0:
        return _empty(_GT_COLS)
    # per message: the transform whose child is the name, else the first one
    named = cols["child_frame_id"] == name
    has_named = np.zeros(int(msg.max()) + 1, dtype=bool)
    has_named[msg[named]] = True
    pick = np.where(has_named[msg], named, cols["item"] == 0)
    c = {k: v[pick] for k, v in cols.items()}
    return pd.DataFrame({
        "t_ns": _stamp(c), "name": np.full(c["msg"].size, name, dtype=object),
        "x": c["x"], "y": c["y"], "z": c["z"],
        "yaw": yaw_from_quat_xyzw_columns(c["qx"], c["qy"], c["qz"], c["qw"]),
    })


def _odom_table(topic: str, cols: dict[str, np.ndarray],
                static: dict[str, tuple[str, _Transform]], world: str) -> pd.DataFrame:
    n = cols["msg"].size
    pos = np.stack([cols["x"], cols["y"], cols["z"]], axis=1)
    quat = np.stack([cols["qx"], cols["qy"], cols["qz"], cols["qw"]], axis=1)
    frame = cols["frame_id"].copy()
    for fid in sorted(set(cols["frame_id"])):
        tf = _chain(static, world, str(fid))
        if tf is None:
            continue
        sel = cols["frame_id"] == fid
        pos[sel] = tf[0] + quat_xyzw_rotate_columns(tf[1], pos[sel])
        quat[sel] = quat_xyzw_mul_columns(tf[1], quat[sel])
        frame[sel] = world
    return pd.DataFrame({
        "t_ns": _stamp(cols), "topic": np.full(n, topic, dtype=object), "frame": frame,
        "x": pos[:, 0], "y": pos[:, 1],
        "yaw": yaw_from_quat_xyzw_columns(quat[:, 0], quat[:, 1], quat[:, 2], quat[:, 3]),
        "vx": cols["vx"], "wz": cols["wz"],
    })


def _track_tables(topic: str, cols: dict[str, np.ndarray], log_ns: np.ndarray,
                  first_frame: int) -> tuple[pd.DataFrame, pd.DataFrame]:
    n_msgs = log_ns.size
    is_track = cols["action"] == _MARKER_ADD
    stamp = _stamp(cols)
    msg = cols["msg"]
    # frame time: stamp of the first track when non-zero, else the log time
    t_frame = log_ns.copy()
    tr_msg, tr_stamp = msg[is_track], stamp[is_track]
    first = np.unique(tr_msg, return_index=True)
    ok = tr_stamp[first[1]] != 0
    t_frame[first[0][ok]] = tr_stamp[first[1]][ok]
    frames = pd.DataFrame({
        "frame": first_frame + np.arange(n_msgs), "t_ns": t_frame, "log_ns": log_ns,
        "topic": np.full(n_msgs, topic, dtype=object)})
    tracks = pd.DataFrame({
        "frame": first_frame + tr_msg, "t_ns": t_frame[tr_msg],
        "topic": np.full(tr_msg.size, topic, dtype=object), "cls": cols["ns"][is_track],
        "track_id": cols["id"][is_track], "x": cols["x"][is_track], "y": cols["y"][is_track]})
    return frames, tracks


_POSE = ("x", "y", "z", "qx", "qy", "qz", "qw")
_TF_COLS = {"t_ns": "int64", "log_ns": "int64", "topic": "category", "tree": "category",
            "static": "bool", "parent": "category", "child": "category",
            **dict.fromkeys(_POSE, "float64")}


def _tf_part(cols: dict[str, np.ndarray], log_ns: np.ndarray) -> dict[str, Any]:
    """One batch of a transform-tree topic as the tf table's columns (frames as categoricals:
    one byte a row)."""
    return {"t_ns": _stamp(cols), "log_ns": log_ns,
            "parent": pd.Categorical(cols["frame_id"]),
            "child": pd.Categorical(cols["child_frame_id"]),
            **{k: cols[k] for k in _POSE}}


def _tf_frame(topics: list[tuple[str, list[dict[str, Any]]]]) -> pd.DataFrame:
    """The ``tf`` table (``_TF_COLS``) from each transform-tree topic's batches, in topic
    order; built column by column, so at most one column is held twice (never the whole
    table: it grows with the run)."""
    parts = [(topic, part) for topic, batches in topics for part in batches]
    if not parts:
        return _empty(_TF_COLS)
    sizes = np.array([part["t_ns"].size for _, part in parts], dtype=np.int64)
    names = [topic for topic, _ in parts]

    def per_topic(values: list[Any]) -> pd.Categorical:
        cats = sorted(set(values))
        codes = np.repeat(np.array([cats.index(v) for v in values], dtype=np.int8), sizes)
        return pd.Categorical.from_codes(codes, cats)

    out: dict[str, Any] = {}
    for k in _TF_COLS:
        if k == "topic":
            out[k] = per_topic(names)
        elif k == "tree":
            out[k] = per_topic([tf_tree_of(t) for t in names])
        elif k == "static":
            out[k] = np.repeat(np.array([is_static_tf_topic(t) for t in names]),
                               sizes)
        elif k in ("parent", "child"):
            out[k] = union_categoricals([part.pop(k) for _, part in parts],
                                        sort_categories=True)
        else:
            out[k] = np.concatenate([part.pop(k) for _, part in parts])
    # copy=False: the columns become the table as they are; the default would stack the
    # float columns into one new block, holding the whole table twice while it is built
    return pd.DataFrame(out, copy=False)


_TfKey = tuple[Any, ...]  # a transform as a row: parent, stamp, pose


def _sent_rows(part: dict[str, Any], held: dict[str, _TfKey]) -> dict[str, Any]:
    """The rows of a tf batch (:func:`_tf_part`) of a topic whose messages each hold every
    static transform sent so far (:func:`~harness.recording.ros1bag.accumulates_static_tf`)
    that a message sends: a child frame's first transform, or one unlike the transform that
    child frame had before (``held``: child frame → its transform, across the batches)."""
    parent = np.asarray(part["parent"], dtype=object)
    child = np.asarray(part["child"], dtype=object)
    rows = zip(child.tolist(), parent.tolist(), part["t_ns"].tolist(),
               *(part[k].tolist() for k in _POSE), strict=True)
    keep = np.zeros(child.size, dtype=bool)
    for i, (name, *key) in enumerate(rows):
        row = tuple(key)
        if held.get(name) != row:
            held[name] = row
            keep[i] = True
    if keep.all():
        return part
    return {k: pd.Categorical(np.asarray(v, dtype=object)[keep]) if k in ("parent", "child")
            else v[keep] for k, v in part.items()}


#: Messages of one topic decoded at a time by :func:`load_frames`.
_DECODE_BATCH = 4096


def _decode_part(raws: Sequence[bytes], msgtype: str, fast: bool, first: int,
                 encoding: Encoding = "cdr") -> dict[str, np.ndarray]:
    """:func:`decode_batch` of the topic's messages ``first`` … ``first + len(raws) - 1``."""
    cols = decode_batch(raws, msgtype, fast=fast, encoding=encoding)
    if first:
        cols["msg"] = cols["msg"] + first
    return cols


def _join_parts(parts: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """One topic's decoded batches as one set of columns (rows still by message, item)."""
    if len(parts) == 1:
        return parts[0]
    return {k: np.concatenate([p.pop(k) for p in parts]) for k in list(parts[0])}


def load_frames(bag_dir: str | Path, *, marker_topics: Sequence[str] | None = None,
                muted_topic: str = "/safety/is_muted", clock_topic: str = "/clock",
                world_frame: str = "world", fast: bool = True,
                fields: Sequence[tuple[str, str]] = ()) -> Frames:
    """Read a rosbag2 directory (or a run directory holding ``bag/``, or a plain ``.mcap``
    file such as a baseline's reference recording, or a ROS 1 recording: a ``.bag`` file or
    a ``bag/`` directory holding one, or a ``ros1``-profile MCAP) into :class:`Frames`.

    ``marker_topics``: the ``MarkerArray`` topics that carry tracks; None takes every topic
    of that type. ``fields``: (topic, field path) of numeric fields to read as well
    (:attr:`Frames.fields`). Raises :class:`BagError` for a missing, truncated or
    undecodable bag.
    """
    p = Path(bag_dir)
    if (p / "bag" / "metadata.yaml").exists() or ros1_recording(p / "bag") is not None:
        p = p / "bag"
    if not p.is_file() and not (p / "metadata.yaml").exists() and ros1_recording(p) is None:
        raise BagError(f"{bag_dir}: metadata.yaml: missing (not a rosbag2 directory)")
    with open_indexed(p, shown=bag_dir) as reader:
        encoding: Encoding = reader.encoding
        conns = list(reader.connections)
        wanted: dict[int, str] = {}
        for c in conns:
            keep = (
                (c.topic == clock_topic and c.msgtype == CLOCK)
                or (c.topic == muted_topic and c.msgtype == BOOL)
                or (c.msgtype == TF_MESSAGE and (tf_tree_of(c.topic) is not None
                                                 or GT_TOPIC.match(c.topic) is not None))
                or c.msgtype in (ODOMETRY, TWIST)
                or (c.msgtype == MARKER_ARRAY
                    and (marker_topics is None or c.topic in marker_topics)))
            if keep:
                wanted[c.id] = c.topic
        # Memory stays flat in the bag's length: log times go into compact arrays and
        # the wanted payloads are decoded every _DECODE_BATCH messages, not kept.
        # the transform tree's topics go straight into the tf table's columns
        tree = {cid for cid, topic in wanted.items()
                if tf_tree_of(topic) is not None and GT_TOPIC.match(topic) is None}
        # ROS 1 static TF topics whose messages repeat the transforms sent before: child
        # frame -> its transform so far (see _sent_rows)
        held: dict[int, dict[str, _TfKey]] = {
            c.id: {} for c in conns if c.id in tree and encoding == "ros1"
            and accumulates_static_tf(c.topic, c.msgtype, c.latched)}
        # topic(...) fields: decoded message by message (few topics, any type)
        field_conns = {c.id: c for c in conns if any(c.topic == t for t, _ in fields)}
        field_rows: dict[tuple[str, str], tuple[array[int], array[float], list[str]]] = {
            f: (array("q"), array("d"), []) for f in fields}
        log: dict[int, array[int]] = {c.id: array("q") for c in conns}
        raws: dict[int, list[bytes]] = {cid: [] for cid in wanted}
        parts: dict[int, list[dict[str, Any]]] = {cid: [] for cid in wanted}
        types = {c.id: c.msgtype for c in conns}

        def flush(cid: int) -> None:
            batch, first = raws[cid], len(log[cid]) - len(raws[cid])
            cols = _decode_part(batch, types[cid], fast, first, encoding)
            if cid in tree:
                batch_log = np.frombuffer(log[cid][first:], dtype=np.int64)
                cols = _tf_part(cols, batch_log[cols["msg"] - first])
                if cid in held:
                    cols = _sent_rows(cols, held[cid])
            parts[cid].append(cols)
            raws[cid] = []

        for conn, t_ns, raw in reader.scan(set(wanted) | set(field_conns)):
            cid = conn.id
            log[cid].append(t_ns)
            if cid in field_conns:
                assert raw is not None
                _read_fields(reader, conn, t_ns, raw, field_rows)
            if cid in wanted:
                assert raw is not None
                raws[cid].append(raw)
                if len(raws[cid]) >= _DECODE_BATCH:
                    flush(cid)
        for cid in wanted:
            if raws[cid] or not parts[cid]:
                flush(cid)
        start_ns, end_ns = int(reader.start_time), int(reader.end_time)
    if start_ns > end_ns:  # empty bag: rosbags reports (max, 0)
        start_ns = end_ns = 0

    by_topic = {c.id: c for c in conns}
    topic_rows: dict[str, list[Any]] = {k: [] for k in
                                        ("name", "type", "count", "first_ns", "last_ns",
                                         "max_gap_ns")}
    log_arr: dict[int, np.ndarray] = {}
    for cid, stamps in log.items():
        arr = np.frombuffer(stamps, dtype=np.int64) if stamps else np.zeros(0, np.int64)
        log_arr[cid] = arr
        topic_rows["name"].append(by_topic[cid].topic)
        topic_rows["type"].append(by_topic[cid].msgtype)
        topic_rows["count"].append(arr.size)
        topic_rows["first_ns"].append(int(arr[0]) if arr.size else -1)
        topic_rows["last_ns"].append(int(arr[-1]) if arr.size else -1)
        topic_rows["max_gap_ns"].append(int(np.diff(arr).max()) if arr.size > 1 else 0)
    topics = pd.DataFrame(topic_rows).sort_values("name", kind="stable").reset_index(
        drop=True)

    order = sorted(wanted, key=lambda i: wanted[i])
    tf = _tf_frame([(wanted[cid], parts.pop(cid)) for cid in order if cid in tree])
    decoded = {cid: _join_parts(parts.pop(cid)) for cid in order if cid not in tree}
    tf_static = pd.DataFrame({k: tf.loc[tf["static"], k].to_numpy(
        dtype=object if k in ("parent", "child") else np.float64)
        for k in ("parent", "child", *_POSE)})
    static: dict[str, tuple[str, _Transform]] = {}
    for row in tf_static.itertuples(index=False):
        static[str(row.child)] = (str(row.parent), (
            np.array([row.x, row.y, row.z]), np.array([row.qx, row.qy, row.qz, row.qw])))

    clock = _empty({"t_ns": "int64", "log_ns": "int64"})
    muted = _empty({"t_ns": "int64", "value": "bool"})
    gt_parts: list[pd.DataFrame] = []
    odom_parts: list[pd.DataFrame] = []
    cmd_parts: list[pd.DataFrame] = []
    frame_parts: list[pd.DataFrame] = []
    track_parts: list[pd.DataFrame] = []
    n_frames = 0
    for cid, cols in decoded.items():
        topic, msgtype = wanted[cid], by_topic[cid].msgtype
        if msgtype == TF_MESSAGE and GT_TOPIC.match(topic) is None:
            continue
        lg = log_arr[cid]
        if msgtype == CLOCK:
            clock = pd.DataFrame({"t_ns": _stamp(cols), "log_ns": lg[cols["msg"]]})
        elif msgtype == BOOL:
            muted = pd.DataFrame({"t_ns": lg[cols["msg"]], "value": cols["data"] != 0})
        elif msgtype == TWIST:
            cmd_parts.append(pd.DataFrame({
                "t_ns": lg[cols["msg"]], "topic": np.full(lg.size, topic, dtype=object),
                "vx": cols["vx"], "wz": cols["wz"]}))
        elif msgtype == ODOMETRY:
            odom_parts.append(_odom_table(topic, cols, static, world_frame))
        elif msgtype == TF_MESSAGE:
            m = GT_TOPIC.match(topic)
            assert m is not None
            gt_parts.append(_gt_table(m.group("name"), cols))
        else:
            fr, tr = _track_tables(topic, cols, lg, n_frames)
            n_frames += len(fr)
            frame_parts.append(fr)
            track_parts.append(tr)

    return Frames(
        clock=clock,
        gt_poses=_concat(gt_parts, _GT_COLS),
        odom=_concat(odom_parts, _ODOM_COLS),
        cmd_vel=_concat(cmd_parts, _CMD_COLS),
        tracks=_concat(track_parts, _TRACK_COLS),
        track_frames=_concat(frame_parts, _TFRAME_COLS),
        muted=muted,
        topics=topics,
        tf_static=tf_static,
        tf=tf,
        start_ns=start_ns,
        end_ns=end_ns,
        message_count=int(topics["count"].sum()) if len(topics) else 0,
        world_frame=world_frame,
        fields=_field_series(field_rows, {c.topic for c in conns}),
    )


_FieldRows = dict[tuple[str, str], tuple["array[int]", "array[float]", list[str]]]


def _read_fields(reader: Any, conn: Any, t_ns: int, raw: bytes, rows: _FieldRows) -> None:
    """Append the asked-for fields of one message of ``conn`` (the first error of a field
    is kept, and the field reads no further)."""
    wanted = [(f, r) for f, r in rows.items() if f[0] == conn.topic and not r[2]]
    if not wanted:
        return
    try:
        msg = reader.decode(raw, conn)
    except DECODE_ERRORS as err:
        for _, r in wanted:
            r[2].append(f"cannot decode a {conn.msgtype} message: {err}")
        return
    for (_, path), (ts, vs, errs) in wanted:
        try:
            value = _field_value(msg, field_path(path), path)
        except ValueError as err:
            errs.append(f"{conn.msgtype} {err}")
            continue
        ts.append(t_ns)
        vs.append(value)


def _field_series(rows: _FieldRows, topics: set[str]) -> dict[tuple[str, str], FieldSeries]:
    out = {}
    for (topic, path), (ts, vs, errs) in rows.items():
        t = np.frombuffer(ts, dtype=np.int64) if ts else np.zeros(0, np.int64)
        v = np.frombuffer(vs, dtype=np.float64) if vs else np.zeros(0)
        error = errs[0] if errs else "" if t.size else \
            f"{topic}: no messages" if topic in topics else f"{topic}: not in the recording"
        order = np.argsort(t, kind="stable")
        out[(topic, path)] = FieldSeries(t[order], v[order], error)
    return out
