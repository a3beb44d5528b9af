"""ROS 2 Jazzy message types and small constructors, backed by the rosbags typestore.

Messages are the typestore's generated dataclasses, so what the bus carries is exactly what
is serialized to CDR. Every stamp comes from simulation time in integer nanoseconds.

:func:`serialize` writes the bytes of rosbags' CDR serializer through layouts compiled once
per type (:mod:`harness.serde.cdr`). Publishers whose messages keep one shape pack them from
values instead (:func:`clock_packer`, :func:`tf_packer`, :func:`odometry_packer`), without
building message objects; the ``*_of`` constructors make the same message as an object, for
whoever reads it.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from harness.serde.cdr import CDR_HEADER, Packer, Serializer
from harness.serde.pieces import Piece
from harness.validation import close_match

__all__ = [
    "TYPESTORE",
    "OdometryPose",
    "Pose",
    "UnknownMessageType",
    "clock",
    "clock_packer",
    "deserialize",
    "header",
    "make",
    "msg_type",
    "odometry",
    "odometry_packer",
    "odometry_pose",
    "quaternion_xyzw",
    "require_msgtype",
    "serialize",
    "split_ns",
    "tf_message",
    "tf_message_of",
    "tf_packer",
    "time_msg",
    "transform_stamped",
    "twist",
    "twist_packer",
]

TYPESTORE: Typestore = get_typestore(Stores.ROS2_JAZZY)

# Types Jazzy's common_interfaces lack, registered beside them. foxglove_msgs/CompressedVideo:
# the field order and types of the foxglove_msgs package (ros-jazzy-foxglove-msgs), which
# Foxglove's video decoding reads.
_EXTRA_TYPES = {
    "foxglove_msgs/msg/CompressedVideo": """\
# One frame of a compressed video stream.
builtin_interfaces/Time timestamp
# Optical frame of the camera that took it.
string frame_id
# Exactly one frame: for h264, Annex B access units; a keyframe carries its SPS and PPS.
uint8[] data
# Codec: h264, h265, vp9 or av1.
string format
""",
}
for _name, _text in _EXTRA_TYPES.items():
    if _name not in TYPESTORE.types:
        TYPESTORE.register(get_types_from_msg(_text, _name))

# Vectors and quaternions come in as plain sequences or as numpy arrays.
_FloatVec = Sequence[float] | npt.NDArray[np.float64]


def msg_type(name: str) -> Any:
    """The message class for ``pkg/msg/Name`` (``pkg/Name`` is accepted too)."""
    if "/msg/" not in name and name.count("/") == 1:
        pkg, short = name.split("/")
        name = f"{pkg}/msg/{short}"
    try:
        return TYPESTORE.types[name]
    except KeyError:
        raise KeyError(f"unknown ROS 2 message type {name!r}") from None


class UnknownMessageType(ValueError):
    """A message type name the typestore does not know (what srr can neither serialize nor
    record); its message suggests the closest known name."""


def require_msgtype(name: str) -> str:
    """``name`` when it is a message type the typestore knows (``pkg/msg/Name``, as the bus
    and the recording spell it); else :class:`UnknownMessageType`, its message suggesting
    the closest known name (``did you mean 'geometry_msgs/msg/Twist'?``)."""
    if isinstance(name, str) and name in TYPESTORE.fielddefs:
        return name
    near = close_match(name, TYPESTORE.fielddefs) if isinstance(name, str) else None
    if isinstance(name, str) and not near and "/msg/" not in name and name.count("/") == 1:
        full = name.replace("/", "/msg/")  # pkg/Name, as ROS 1 and rosidl spell it
        near = full if full in TYPESTORE.fielddefs else None
    hint = f"; did you mean {near!r}?" if near else " (expected pkg/msg/Name)"
    raise UnknownMessageType(f"unknown message type {name!r}{hint}")


_NUMPY_DTYPES = {
    "bool": np.bool_, "int8": np.int8, "uint8": np.uint8, "byte": np.uint8, "char": np.uint8,
    "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
    "int64": np.int64, "uint64": np.uint64, "float32": np.float32, "float64": np.float64,
}


def _zero(node: Any) -> Any:
    kind, detail = node
    name = getattr(kind, "name", str(kind))
    if name == "BASE":
        base = detail[0]
        if base == "string":
            return ""
        if base == "bool":
            return False
        return 0.0 if base.startswith("float") else 0
    if name == "NAME":
        return make(detail)
    sub, count = detail
    sub_name = getattr(sub[0], "name", str(sub[0]))
    if sub_name == "BASE" and sub[1][0] in _NUMPY_DTYPES:
        return np.zeros(count if name == "ARRAY" else 0, dtype=_NUMPY_DTYPES[sub[1][0]])
    if name == "ARRAY":
        return [_zero(sub) for _ in range(count)]
    return []


def make(typename: str, **fields: Any) -> Any:
    """A message of ``typename`` with ``fields`` set and every other field zero / empty,
    recursively (the rosbags dataclasses have no defaults)."""
    cls = msg_type(typename)
    _, defs = TYPESTORE.fielddefs[cls.__msgtype__]
    values = {name: fields.pop(name) if name in fields else _zero(node) for name, node in defs}
    if fields:
        raise TypeError(f"{typename} has no field(s) {', '.join(sorted(fields))}")
    return cls(**values)


def _rosbags_serialize(msg: Any, typename: str) -> bytes:
    return bytes(TYPESTORE.serialize_cdr(msg, typename))


_SERIALIZER = Serializer(TYPESTORE, _rosbags_serialize)


def serialize(msg: Any, typename: str) -> bytes:
    """``msg`` as CDR bytes: exactly rosbags' ``serialize_cdr`` (little-endian)."""
    return _SERIALIZER(msg, typename)


def serialize_pieces(msg: Any, typename: str) -> tuple[Piece, ...]:
    """The bytes of :func:`serialize` in pieces, large numeric arrays (an image's pixels) as
    views of the message's own arrays instead of copies (see
    :meth:`harness.serde.cdr.Serializer.pieces`)."""
    return _SERIALIZER.pieces(msg, typename)


def deserialize(data: bytes, typename: str) -> Any:
    return TYPESTORE.deserialize_cdr(data, typename)


_Time = msg_type("builtin_interfaces/msg/Time")
_Header = msg_type("std_msgs/msg/Header")
_Clock = msg_type("rosgraph_msgs/msg/Clock")
_Vector3 = msg_type("geometry_msgs/msg/Vector3")
_Quaternion = msg_type("geometry_msgs/msg/Quaternion")
_Point = msg_type("geometry_msgs/msg/Point")
_Pose = msg_type("geometry_msgs/msg/Pose")
_Twist = msg_type("geometry_msgs/msg/Twist")
_Transform = msg_type("geometry_msgs/msg/Transform")
_TransformStamped = msg_type("geometry_msgs/msg/TransformStamped")
_TFMessage = msg_type("tf2_msgs/msg/TFMessage")
_PoseWithCovariance = msg_type("geometry_msgs/msg/PoseWithCovariance")
_TwistWithCovariance = msg_type("geometry_msgs/msg/TwistWithCovariance")
_Odometry = msg_type("nav_msgs/msg/Odometry")


def split_ns(ns: int) -> tuple[int, int]:
    """``(sec, nanosec)`` of a time in nanoseconds, as ``builtin_interfaces/Time`` holds it."""
    return divmod(int(ns), 1_000_000_000)


def time_msg(ns: int) -> Any:
    sec, nanosec = divmod(int(ns), 1_000_000_000)
    return _Time(sec=sec, nanosec=nanosec)


def header(ns: int, frame_id: str) -> Any:
    return _Header(stamp=time_msg(ns), frame_id=frame_id)


def clock(ns: int) -> Any:
    return _Clock(clock=time_msg(ns))


def _vec3(v: _FloatVec) -> Any:
    return _Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def quaternion_xyzw(q: _FloatVec) -> Any:
    """A ``geometry_msgs/Quaternion`` of the (x, y, z, w) quaternion ``q`` (harness.geometry
    converts from MuJoCo's (w, x, y, z))."""
    return _Quaternion(x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))


def twist(linear: Sequence[float], angular: Sequence[float]) -> Any:
    return _Twist(linear=_vec3(linear), angular=_vec3(angular))


def transform_stamped(ns: int, parent: str, child: str, translation: _FloatVec,
                      rotation_xyzw: _FloatVec) -> Any:
    tf = _Transform(translation=_vec3(translation), rotation=quaternion_xyzw(rotation_xyzw))
    return _TransformStamped(header=header(ns, parent), child_frame_id=child, transform=tf)


def tf_message(transforms: Sequence[Any]) -> Any:
    return _TFMessage(transforms=list(transforms))


class Pose(NamedTuple):
    """One transform of a TF message: parent and child frame, translation, rotation (x, y,
    z, w)."""

    parent: str
    child: str
    translation: _FloatVec
    rotation_xyzw: _FloatVec


def tf_message_of(ns: int, poses: Sequence[Pose]) -> Any:
    """A TF message of ``poses``, all stamped ``ns``."""
    return tf_message([transform_stamped(ns, *pose) for pose in poses])


def odometry(ns: int, odom_frame: str, child_frame: str, position: Sequence[float],
             orientation_xyzw: Sequence[float], linear: Sequence[float],
             angular: Sequence[float]) -> Any:
    point = _Point(x=float(position[0]), y=float(position[1]), z=float(position[2]))
    pose = _Pose(position=point, orientation=quaternion_xyzw(orientation_xyzw))
    cov = np.zeros(36, dtype=np.float64)
    return _Odometry(
        header=header(ns, odom_frame),
        child_frame_id=child_frame,
        pose=_PoseWithCovariance(pose=pose, covariance=cov),
        twist=_TwistWithCovariance(twist=twist(linear, angular), covariance=cov.copy()),
    )


_U32 = struct.Struct("<I")
_POSE = struct.Struct("<7d")
#: What :func:`odometry_pose` reads: the header's frame id, position (x, y, z), orientation
#: (x, y, z, w).
OdometryPose = tuple[str, tuple[float, float, float], tuple[float, float, float, float]]


def odometry_pose(raw: bytes) -> OdometryPose | None:
    """The frame id, position and orientation of a ``nav_msgs/Odometry`` in (little-endian)
    CDR, read at their offsets instead of deserializing the whole message (a subscriber that
    only needs the pose, 20 times a second). The values are the message's own: each double is
    unpacked as it was packed. None when ``raw`` is not little-endian CDR (read the message
    object instead).

    The layout, offsets counted from the end of the 4-byte encapsulation header: the stamp (two
    32-bit integers), ``header.frame_id`` and ``child_frame_id`` (each a 32-bit length that
    counts a trailing NUL, then the bytes; the second aligned to 4), then the pose's seven
    doubles aligned to 8."""
    if raw[:4] != CDR_HEADER:
        return None
    at = 4 + 8
    (size,) = _U32.unpack_from(raw, at)
    frame_id = raw[at + 4:at + 3 + size].decode()
    at += 4 + size
    at += -(at - 4) % 4
    (size,) = _U32.unpack_from(raw, at)
    at += 4 + size
    at += -(at - 4) % 8
    x, y, z, qx, qy, qz, qw = _POSE.unpack_from(raw, at)
    return frame_id, (x, y, z), (qx, qy, qz, qw)


# -- packers: the same messages, from values ------------------------------------------------

_STAMP = ("stamp.sec", "stamp.nanosec")
_TRANSLATION = tuple(f"translation.{c}" for c in "xyz")
_ROTATION = tuple(f"rotation.{c}" for c in "xyzw")


def clock_packer() -> Packer:
    """``rosgraph_msgs/Clock`` from ``(sec, nanosec)`` (see :func:`split_ns`)."""
    return Packer(TYPESTORE, "rosgraph_msgs/msg/Clock", clock(0),
                  ("clock.sec", "clock.nanosec"))


def tf_packer(frames: Sequence[tuple[str, str]]) -> Packer:
    """``tf2_msgs/TFMessage`` of one transform per ``(parent, child)`` of ``frames``, from the
    values ``sec, nanosec, tx, ty, tz, qx, qy, qz, qw`` of each transform in turn (as
    :func:`tf_message_of` would build it)."""
    template = tf_message_of(0, [Pose(parent, child, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
                                 for parent, child in frames])
    variables = tuple(
        f"transforms[{i}].{path}"
        for i in range(len(frames))
        for path in (*(f"header.{p}" for p in _STAMP),
                     *(f"transform.{p}" for p in (*_TRANSLATION, *_ROTATION)))
    )
    return Packer(TYPESTORE, "tf2_msgs/msg/TFMessage", template, variables)


def twist_packer() -> Packer:
    """``geometry_msgs/Twist`` from its linear and then angular velocity (x, y, z each), as
    :func:`twist` builds it."""
    return Packer(TYPESTORE, "geometry_msgs/msg/Twist", twist((0.0,) * 3, (0.0,) * 3),
                  tuple(f"{part}.{c}" for part in ("linear", "angular") for c in "xyz"))


def odometry_packer(odom_frame: str, child_frame: str) -> Packer:
    """``nav_msgs/Odometry`` from ``sec, nanosec``, position (3), orientation (x, y, z, w),
    linear and angular velocity (3 each), zero covariances (as :func:`odometry` builds it)."""
    template = odometry(0, odom_frame, child_frame, (0.0,) * 3, (0.0, 0.0, 0.0, 1.0),
                        (0.0,) * 3, (0.0,) * 3)
    variables = (
        *(f"header.{p}" for p in _STAMP),
        *(f"pose.pose.position.{c}" for c in "xyz"),
        *(f"pose.pose.orientation.{c}" for c in "xyzw"),
        *(f"twist.twist.linear.{c}" for c in "xyz"),
        *(f"twist.twist.angular.{c}" for c in "xyz"),
    )
    return Packer(TYPESTORE, "nav_msgs/msg/Odometry", template, variables)
