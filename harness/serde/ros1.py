"""ROS 1 messages: the bus's ROS 2 messages as ROS 1 (Noetic) ones, and back.

The bus always carries ROS 2 Jazzy messages (:mod:`harness.serde.messages`). A run that records
ROS 1 converts each message here, once, as it is recorded:

* **Types** keep their package and name and lose ``/msg/`` in ROS 1 spelling
  (``sensor_msgs/msg/Image`` → ``sensor_msgs/Image``). ``/tf`` and ``/tf_static`` carry
  ``tf2_msgs/TFMessage``, as Isaac Sim's ROS 1 bridge publishes them (Noetic's
  ``tf/tfMessage`` has the same definition and is read back too). A type Noetic does not
  have (``geometry_msgs/VelocityStamped``, new in ROS 2; packages Noetic's set lacks) has no
  ROS 1 counterpart: :func:`ros1_type` refuses it, which the run does before its first tick.
* **Fields** are matched by name, then case-insensitively (``sensor_msgs/CameraInfo``'s
  ``D, K, R, P`` are ROS 2's ``d, k, r, p``). ROS 2 fields that ROS 1 lacks are dropped
  (:func:`dropped_fields` lists them: ``visualization_msgs/Marker``'s texture and mesh-file
  fields); ROS 1 fields that ROS 2 lacks are zero.
* **Stamps** are the same integer seconds and nanoseconds (``time`` in ROS 1).
* ``std_msgs/Header.seq``: a message whose top-level field ``header`` is a Header gets the
  topic's own counter, 0 for its first message and one more for each next, as a roscpp
  publisher numbers them; headers nested deeper (each transform of a ``TFMessage``, each
  marker of a ``MarkerArray``) keep 0, as publishers leave them.

Serialization and message definitions (with their MD5 sums) are rosbags' Noetic typestore's;
nothing here writes ROS 1 bytes by hand. :class:`Ros1Encoder` holds one run's counters.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.msg import denormalize_msgtype, normalize_msgtype
from rosbags.typesys.store import Typestore

from harness.errors import SrrError
from harness.serde.messages import TYPESTORE as ROS2_TYPESTORE

__all__ = [
    "Ros1Encoder",
    "Ros1TypeError",
    "deserialize_ros1",
    "dropped_fields",
    "msgdef",
    "ros1_name",
    "ros1_type",
    "ros1_typestore",
    "ros2_type",
    "to_ros1",
    "to_ros2",
]


class Ros1TypeError(SrrError):
    """A ROS 2 message type has no ROS 1 counterpart (or a field that cannot be carried);
    ``detail`` says which, to follow the type's name in a sentence."""

    def __init__(self, msgtype: str, detail: str) -> None:
        self.msgtype = msgtype
        self.detail = detail
        super().__init__(f"{msgtype} {detail}")


@functools.cache
def ros1_typestore() -> Typestore:
    """ROS 1 Noetic's message types (rosbags'), plus tf2_msgs and tf, which rosbags' Noetic
    store lacks: their ``TFMessage`` / ``tfMessage`` definitions, as in the ROS 1 packages.
    Made at its first use (0.1–0.2 s), not when srr is imported: most runs write no ROS 1."""
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register({
        **get_types_from_msg("geometry_msgs/TransformStamped[] transforms\n",
                             "tf2_msgs/msg/TFMessage"),
        **get_types_from_msg("geometry_msgs/TransformStamped[] transforms\n",
                             "tf/msg/tfMessage"),
    })
    return store

TF_ROS1 = "tf2_msgs/msg/TFMessage"
#: ROS 1 types read back as another ROS 2 type (same definition, another package).
_TO_ROS2 = {"tf/msg/tfMessage": "tf2_msgs/msg/TFMessage"}
_HEADER = "std_msgs/msg/Header"


def _norm(name: str) -> str:
    return normalize_msgtype(name) if "/msg/" not in name else name


_ROS1_OF: dict[str, str] = {}


def ros1_type(ros2: str) -> str:
    """The ROS 1 type (rosbags' normalized spelling, ``pkg/msg/Name``) a ROS 2 type is
    recorded as; :class:`Ros1TypeError` when Noetic has none."""
    found = _ROS1_OF.get(ros2)
    if found is not None:
        return found
    name = _norm(ros2)
    if name not in ros1_typestore().fielddefs:
        raise Ros1TypeError(ros2, "has no ROS 1 counterpart (ROS Noetic has no message type "
                            "by that name)")
    if name not in ROS2_TYPESTORE.fielddefs:
        raise Ros1TypeError(ros2, "is not a ROS 2 message type")
    _converter(ROS2_TYPESTORE, ros1_typestore(), name, name)  # every field can be carried
    _ROS1_OF[ros2] = name
    return name


def ros2_type(ros1: str) -> str:
    """The ROS 2 type a recorded ROS 1 type is read back as (``tf/tfMessage`` →
    ``tf2_msgs/msg/TFMessage``); the same name otherwise."""
    name = _norm(ros1)
    return _TO_ROS2.get(name, name)


def ros1_name(ros2: str) -> str:
    """ROS 1 spelling of the type a ROS 2 type is recorded as: ``sensor_msgs/Image``."""
    return str(denormalize_msgtype(ros1_type(ros2)))


def msgdef(ros1: str) -> tuple[str, str]:
    """The ROS 1 message definition (the type's ``.msg`` text followed by its dependencies,
    as rosbag and the MCAP ``ros1msg`` schema encoding carry it) and its MD5 sum."""
    text, md5 = ros1_typestore().generate_msgdef(_norm(ros1), ros_version=1)
    return str(text), str(md5)


# --------------------------------------------------------------------------- conversion

Convert = Callable[[Any, int], Any]  # (message, header seq) -> message of the other store
_CACHE: dict[tuple[int, str, str], Convert] = {}
_DROPPED: dict[tuple[int, str, str], tuple[str, ...]] = {}
_STRING = frozenset({"string", "wstring"})


def _kind(node: Any) -> str:
    return str(getattr(node[0], "name", node[0]))


def _zero(store: Typestore, node: Any) -> Any:
    kind, detail = node
    if kind == Nodetype.BASE:
        base = detail[0]
        return "" if base in _STRING else False if base == "bool" else \
            0.0 if base.startswith("float") else 0
    if kind == Nodetype.NAME:
        _, fields = store.fielddefs[detail]
        return store.types[detail](**{n: _zero(store, f) for n, f in fields})
    sub, count = detail
    if kind == Nodetype.ARRAY:
        return [_zero(store, sub) for _ in range(count)]
    return []


def _compatible(src: Any, dst: Any) -> bool:
    """Whether a field's value carries over as it is (or element by element)."""
    ks, kd = _kind(src), _kind(dst)
    if ks != kd:
        return False
    if ks == "BASE":
        return (src[1][0] in _STRING) == (dst[1][0] in _STRING)
    if ks == "NAME":
        return True
    (sub_s, n_s), (sub_d, n_d) = src[1], dst[1]
    return (ks != "ARRAY" or n_s == n_d) and _compatible(sub_s, sub_d)


def _element(src_store: Typestore, dst_store: Typestore, src: Any, dst: Any) -> Convert | None:
    """Converter for one value of node ``src`` into node ``dst``; None when it passes as is."""
    kind = _kind(dst)
    if kind == "BASE":
        return None
    if kind == "NAME":
        return _converter(src_store, dst_store, src[1], dst[1])
    inner = _element(src_store, dst_store, src[1][0], dst[1][0])
    if inner is None:
        return None
    return lambda v, _seq: [inner(x, 0) for x in v]


def _converter(src_store: Typestore, dst_store: Typestore, src_type: str,
               dst_type: str) -> Convert:
    """A function building a ``dst_type`` message of ``dst_store`` from a ``src_type``
    message of ``src_store`` (compiled once per pair of types)."""
    key = (id(dst_store), src_type, dst_type)
    found = _CACHE.get(key)
    if found is not None:
        return found
    src_fields = dict(src_store.fielddefs[src_type][1])
    by_lower = {n.lower(): n for n in src_fields}
    cls = dst_store.types[dst_type]
    plan: list[tuple[str, str | None, Convert | None, Any]] = []
    used: set[str] = set()
    for name, node in dst_store.fielddefs[dst_type][1]:
        src_name = name if name in src_fields else by_lower.get(name.lower())
        if src_name is None:
            plan.append((name, None, None, node))
            continue
        if not _compatible(src_fields[src_name], node):
            raise Ros1TypeError(src_type, f"cannot be carried: its field {src_name} does "
                                f"not fit {dst_type}.{name}")
        used.add(src_name)
        plan.append((name, src_name, _element(src_store, dst_store, src_fields[src_name],
                                              node), node))
    _DROPPED[key] = tuple(n for n in src_fields if n not in used)
    is_header = dst_type == _HEADER
    top_header = any(n == "header" and s == "header" and _kind(node) == "NAME"
                     and node[1] == _HEADER for n, s, _, node in plan)

    def convert(msg: Any, seq: int) -> Any:
        values: dict[str, Any] = {}
        for name, src_name, sub, node in plan:
            if src_name is None:
                values[name] = seq if is_header and name == "seq" else _zero(dst_store, node)
                continue
            value = getattr(msg, src_name)
            if sub is not None:
                value = sub(value, seq if top_header and name == "header" else 0)
            values[name] = value
        return cls(**values)

    _CACHE[key] = convert
    return convert


def dropped_fields(ros2: str) -> tuple[str, ...]:
    """Fields of ROS 2 type ``ros2``, and of the types inside it, that ROS 1 does not have,
    as ``pkg/msg/Type.field`` (sorted)."""
    out: set[str] = set()
    seen: set[str] = set()
    ros1 = ros1_typestore()

    def walk(name: str) -> None:
        if name in seen:
            return
        seen.add(name)
        _converter(ROS2_TYPESTORE, ros1, name, name)
        dropped = set(_DROPPED[(id(ros1), name, name)])
        out.update(f"{name}.{f}" for f in dropped)
        for field, node in ROS2_TYPESTORE.fielddefs[name][1]:
            if field in dropped:
                continue
            inner: Any = node
            while _kind(inner) in ("ARRAY", "SEQUENCE"):
                inner = inner[1][0]
            if _kind(inner) == "NAME":
                walk(str(inner[1]))

    walk(ros1_type(ros2))
    return tuple(sorted(out))


def to_ros1(msg: Any, ros2: str, seq: int = 0) -> Any:
    """The ROS 1 message for ROS 2 message ``msg`` of type ``ros2``; ``seq`` goes into its
    top-level ``header`` (if it has one)."""
    name = _norm(ros2)
    return _converter(ROS2_TYPESTORE, ros1_typestore(), name, ros1_type(name))(msg, seq)


def to_ros2(msg: Any, ros1: str) -> Any:
    """The ROS 2 message for ROS 1 message ``msg`` of type ``ros1`` (header ``seq``
    dropped, fields ROS 1 lacks zero)."""
    src = _norm(ros1)
    return _converter(ros1_typestore(), ROS2_TYPESTORE, src, ros2_type(src))(msg, 0)


def deserialize_ros1(data: bytes, ros1: str) -> Any:
    """A ROS 1 message of type ``ros1`` from its serialized bytes (rosbags' Noetic store)."""
    return ros1_typestore().deserialize_ros1(data, _norm(ros1))


class Ros1Encoder:
    """One run's ROS 2 → ROS 1 serialization: the header ``seq`` counter of every topic."""

    def __init__(self) -> None:
        self._seq: dict[str, int] = {}

    def encode(self, topic: str, ros2: str, msg: Any) -> bytes:
        """ROS 1 bytes of ``msg`` (type ``ros2``) published on ``topic``."""
        seq = self._seq.get(topic, 0)
        self._seq[topic] = seq + 1
        name = ros1_type(ros2)
        return bytes(ros1_typestore().serialize_ros1(to_ros1(msg, ros2, seq & 0xFFFFFFFF), name))
