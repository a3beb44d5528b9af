"""ROS 2 Jazzy message types and small constructors, backed by the rosbags typestore.

Messages are the typestore's generated dataclasses, so what the bus carries is exactly what
is serialized to CDR. Every stamp comes from simulation time in integer nanoseconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

__all__ = [
    "TYPESTORE",
    "clock",
    "deserialize",
    "header",
    "make",
    "msg_type",
    "odometry",
    "serialize",
    "tf_message",
    "time_msg",
    "transform_stamped",
    "twist",
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


def serialize(msg: Any, typename: str) -> bytes:
    return bytes(TYPESTORE.serialize_cdr(msg, typename))


def deserialize(data: bytes, typename: str) -> Any:
    return TYPESTORE.deserialize_cdr(data, typename)


def time_msg(ns: int) -> Any:
    sec, nanosec = divmod(int(ns), 1_000_000_000)
    return msg_type("builtin_interfaces/msg/Time")(sec=sec, nanosec=nanosec)


def header(ns: int, frame_id: str) -> Any:
    return msg_type("std_msgs/msg/Header")(stamp=time_msg(ns), frame_id=frame_id)


def clock(ns: int) -> Any:
    return msg_type("rosgraph_msgs/msg/Clock")(clock=time_msg(ns))


def _vec3(v: _FloatVec) -> Any:
    return msg_type("geometry_msgs/msg/Vector3")(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _quat_xyzw(q: _FloatVec) -> Any:
    return msg_type("geometry_msgs/msg/Quaternion")(
        x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))


def twist(linear: Sequence[float], angular: Sequence[float]) -> Any:
    return msg_type("geometry_msgs/msg/Twist")(linear=_vec3(linear), angular=_vec3(angular))


def transform_stamped(ns: int, parent: str, child: str, translation: _FloatVec,
                      rotation_xyzw: _FloatVec) -> Any:
    tf = msg_type("geometry_msgs/msg/Transform")(
        translation=_vec3(translation), rotation=_quat_xyzw(rotation_xyzw))
    return msg_type("geometry_msgs/msg/TransformStamped")(
        header=header(ns, parent), child_frame_id=child, transform=tf)


def tf_message(transforms: Sequence[Any]) -> Any:
    return msg_type("tf2_msgs/msg/TFMessage")(transforms=list(transforms))


def odometry(ns: int, odom_frame: str, child_frame: str, position: Sequence[float],
             orientation_xyzw: Sequence[float], linear: Sequence[float],
             angular: Sequence[float]) -> Any:
    point = msg_type("geometry_msgs/msg/Point")(
        x=float(position[0]), y=float(position[1]), z=float(position[2]))
    pose = msg_type("geometry_msgs/msg/Pose")(position=point,
                                               orientation=_quat_xyzw(orientation_xyzw))
    cov = np.zeros(36, dtype=np.float64)
    return msg_type("nav_msgs/msg/Odometry")(
        header=header(ns, odom_frame),
        child_frame_id=child_frame,
        pose=msg_type("geometry_msgs/msg/PoseWithCovariance")(pose=pose, covariance=cov),
        twist=msg_type("geometry_msgs/msg/TwistWithCovariance")(
            twist=twist(linear, angular), covariance=cov.copy()),
    )
