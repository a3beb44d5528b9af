"""ROS bridge nodes: publishers and subscribers on the srr bus.

Canonical names are ``srr.*``; the Isaac Sim spellings of the ROS 2 bridge (``isaacsim.ros2.bridge``
and the older ``omni.isaac.ros2_bridge``) and of the ROS 1 bridge (``omni.isaac.ros_bridge``) are
aliases, so a builder written for Isaac Sim ports by changing imports. Every message is stamped
from simulation time: ``inputs:timeStamp`` when connected (seconds, as Isaac's
ReadSimulationTime gives it), otherwise the tick's own time.

Publishers of messages with one shape (clock, odometry, TF) pack their bytes from values with
a :class:`~harness.serde.cdr.Packer` made for the frame ids they publish, and leave building the
message object to whoever reads it (:meth:`~harness.bus.Bus.publish_serialized`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import numpy as np

from harness.bus import TopicNameError, resolve_topic
from harness.bus.bus import Qos
from harness.bus.endpoints import Endpoint, TfEdge, is_static_tf_topic
from harness.geometry import quat_wxyz_conj, quat_wxyz_mul, quat_wxyz_rotate, wxyz_to_xyzw
from harness.graph import Attr, NodeType, register
from harness.graph.errors import GraphError
from harness.scenario.prims import frame_of
from harness.serde.cdr import Packer
from harness.serde.messages import (
    Pose,
    clock,
    clock_packer,
    odometry,
    odometry_packer,
    split_ns,
    tf_message_of,
    tf_packer,
)
from harness.sim.cameras import optical_quat
from harness.sim.prims import PrimKind

__all__ = [
    "BRIDGE_INPUTS",
    "EXEC_OUT",
    "PublishClock",
    "PublishOdometry",
    "PublishRawTransformTree",
    "PublishTransformTree",
    "SubscribeTwist",
    "aliases",
    "frame_pose",
]

STATIC_QOS = Qos(durability="transient_local", depth=100)


def aliases(name: str) -> tuple[str, ...]:
    """The Isaac Sim spellings of a bridge node: ROS 2 (new and old) and ROS 1."""
    return (
        f"isaacsim.ros2.bridge.ROS2{name}",
        f"omni.isaac.ros2_bridge.ROS2{name}",
        f"omni.isaac.ros_bridge.ROS1{name}",
    )


BRIDGE_INPUTS = (
    Attr("execIn", "execution"),
    Attr("context", "uint64", 0),
    Attr("nodeNamespace", "string", ""),
    Attr("qosProfile", "string", ""),
    Attr("queueSize", "uint64", 10),
)
EXEC_OUT = (Attr("execOut", "execution"),)


def topic_of(db: Any, field: str = "topicName") -> str:
    """The fully qualified topic of a bridge node, or a GraphError naming the node."""
    try:
        return resolve_topic(getattr(db.inputs, field), db.inputs.nodeNamespace)
    except TopicNameError as err:
        raise GraphError(f"{db.node_path}.inputs:{field}: {err}") from err


def stamp_of(db: Any, ctx: Any) -> int:
    """Stamp in ns: the connected ``timeStamp`` (seconds) or the tick's simulation time."""
    if db.is_connected("timeStamp"):
        return round(float(db.inputs.timeStamp) * 1e9)
    return int(ctx.time_ns)


class _Publisher(NodeType):
    """Base for publishing nodes: advertises once, on first compute."""

    kind = "action"
    msgtype = ""

    def initialize(self, db: Any, ctx: Any) -> None:
        self._pub = ctx.bus.advertise(topic_of(db), self.msgtype, self.qos(db))

    def qos(self, db: Any) -> Qos | None:
        return None

    def endpoints(self, value: Callable[[str], Any]) -> Sequence[Endpoint | TfEdge]:
        return (Endpoint("pub", str(value("topicName")), self.msgtype,
                         str(value("nodeNamespace"))),)


@register("srr.PublishClock", aliases=aliases("PublishClock"))
class PublishClock(_Publisher):
    inputs = (*BRIDGE_INPUTS, Attr("topicName", "string", "clock"),
              Attr("timeStamp", "double", 0.0))
    outputs = EXEC_OUT
    msgtype = "rosgraph_msgs/msg/Clock"

    def initialize(self, db: Any, ctx: Any) -> None:
        super().initialize(db, ctx)
        self._packer = clock_packer()

    def compute(self, db: Any, ctx: Any) -> bool:
        ns = stamp_of(db, ctx)
        self._pub.publish_serialized(self._packer.pack(*split_ns(ns)), partial(clock, ns))
        return True


@register("srr.SubscribeTwist", aliases=aliases("SubscribeTwist"))
class SubscribeTwist(NodeType):
    """Fires ``execOut`` on the tick a new Twist has arrived, with its velocities as outputs."""

    kind = "action"
    inputs = (*BRIDGE_INPUTS, Attr("topicName", "string", "cmd_vel"))
    outputs = (
        *EXEC_OUT,
        Attr("linearVelocity", "double[3]", (0.0, 0.0, 0.0)),
        Attr("angularVelocity", "double[3]", (0.0, 0.0, 0.0)),
    )

    def initialize(self, db: Any, ctx: Any) -> None:
        self._pending: list[Any] = []
        ctx.bus.subscribe(topic_of(db), "geometry_msgs/msg/Twist", self._pending.append)

    def endpoints(self, value: Callable[[str], Any]) -> Sequence[Endpoint | TfEdge]:
        return (Endpoint("sub", str(value("topicName")), "geometry_msgs/msg/Twist",
                         str(value("nodeNamespace")), required=True),)

    def compute(self, db: Any, ctx: Any) -> bool:
        if not self._pending:
            return False
        msg = self._pending[-1]
        self._pending.clear()
        db.outputs.linearVelocity = (msg.linear.x, msg.linear.y, msg.linear.z)
        db.outputs.angularVelocity = (msg.angular.x, msg.angular.y, msg.angular.z)
        return True


@register("srr.PublishOdometry", aliases=aliases("PublishOdometry"))
class PublishOdometry(_Publisher):
    inputs = (
        *BRIDGE_INPUTS,
        Attr("topicName", "string", "odom"),
        Attr("timeStamp", "double", 0.0),
        Attr("chassisFrameId", "string", "base_link"),
        Attr("odomFrameId", "string", "odom"),
        Attr("position", "double[3]", (0.0, 0.0, 0.0)),
        Attr("orientation", "quatd[4]", (0.0, 0.0, 0.0, 1.0)),
        Attr("linearVelocity", "double[3]", (0.0, 0.0, 0.0)),
        Attr("angularVelocity", "double[3]", (0.0, 0.0, 0.0)),
        Attr("robotFront", "double[3]", (1.0, 0.0, 0.0)),
    )
    outputs = EXEC_OUT
    msgtype = "nav_msgs/msg/Odometry"

    def initialize(self, db: Any, ctx: Any) -> None:
        super().initialize(db, ctx)
        self._frames: tuple[str, str] | None = None

    def compute(self, db: Any, ctx: Any) -> bool:
        i = db.inputs
        frames = (i.odomFrameId, i.chassisFrameId)
        if frames != self._frames:
            self._frames, self._packer = frames, odometry_packer(*frames)
        ns = stamp_of(db, ctx)
        pos, ori, lin, ang = i.position, i.orientation, i.linearVelocity, i.angularVelocity
        raw = self._packer.pack(*split_ns(ns), *pos, *ori, *lin, *ang)
        self._pub.publish_serialized(raw, partial(odometry, ns, *frames, pos, ori, lin, ang))
        return True


class _TfPublisher(_Publisher):
    """TF publishers: ``staticPublisher`` (or a ``tf_static`` topic) latches and publishes
    only when the transforms change, like a ROS static broadcaster."""

    msgtype = "tf2_msgs/msg/TFMessage"

    def is_static(self, db: Any) -> bool:
        return bool(db.inputs.staticPublisher) or topic_of(db).endswith("tf_static")

    def qos(self, db: Any) -> Qos | None:
        self._static = self.is_static(db)  # fixed once the publisher exists
        self._last_key: tuple[Any, ...] | None = None
        self._packers: dict[tuple[tuple[str, str], ...], Packer] = {}
        self._frames: tuple[str, str] | None = None
        self._one: Packer | None = None
        return STATIC_QOS if self._static else None

    def unchanged(self, key: tuple[Any, ...]) -> bool:
        """For a static publisher: True when ``key`` (what the transforms depend on) is what
        was published last, so there is nothing to send; remembers ``key`` otherwise."""
        if not self._static:
            return False
        if self._last_key == key:
            return True
        self._last_key = key
        return False

    def emit(self, ns: int, poses: list[Pose]) -> None:
        """Publish one TF message of ``poses`` stamped ``ns``."""
        sec, nanosec = split_ns(ns)
        if len(poses) == 1:  # the usual case, without the generators
            pose = poses[0]
            frames: tuple[tuple[str, str], ...] = ((pose.parent, pose.child),)
            values: tuple[Any, ...] = (sec, nanosec, *pose.translation, *pose.rotation_xyzw)
        else:
            frames = tuple((pose.parent, pose.child) for pose in poses)
            values = tuple(value for pose in poses for value in (
                sec, nanosec, *pose.translation, *pose.rotation_xyzw))
        raw = self._packer_of(frames).pack(*values)
        self._pub.publish_serialized(raw, partial(tf_message_of, ns, poses))

    def _packer_of(self, frames: tuple[tuple[str, str], ...]) -> Packer:
        packer = self._packers.get(frames)
        if packer is None:
            packer = self._packers[frames] = tf_packer(frames)
        return packer

    def edges(self, value: Callable[[str], Any]) -> list[TfEdge]:
        """The transforms this node publishes, as TF edges (see :meth:`endpoints`)."""
        raise NotImplementedError

    def endpoints(self, value: Callable[[str], Any]) -> Sequence[Endpoint | TfEdge]:
        return (*super().endpoints(value), *self.edges(value))

    @staticmethod
    def edge_topic(value: Callable[[str], Any]) -> tuple[str, bool]:
        """The resolved topic and whether its edges are static for tf2: published on a
        ``tf_static`` topic (``staticPublisher`` on ``/tf`` only latches the publisher)."""
        topic = resolve_topic(str(value("topicName")), str(value("nodeNamespace")))
        return topic, is_static_tf_topic(topic)


@register("srr.PublishRawTransformTree", aliases=aliases("PublishRawTransformTree"))
class PublishRawTransformTree(_TfPublisher):
    """One transform from explicit values. ``rotation`` is a quatd in Isaac's IJKR order
    (x, y, z, w)."""

    inputs = (
        *BRIDGE_INPUTS,
        Attr("topicName", "string", "tf"),
        Attr("timeStamp", "double", 0.0),
        Attr("parentFrameId", "string", "odom"),
        Attr("childFrameId", "string", "base_link"),
        Attr("translation", "double[3]", (0.0, 0.0, 0.0)),
        Attr("rotation", "quatd[4]", (0.0, 0.0, 0.0, 1.0)),
        Attr("staticPublisher", "bool", False),
    )
    outputs = EXEC_OUT

    def compute(self, db: Any, ctx: Any) -> bool:
        i = db.inputs
        tr, rot = tuple(i.translation), tuple(i.rotation)
        parent, child = i.parentFrameId, i.childFrameId
        if self._static and self.unchanged((parent, child, tr, rot)):
            return True
        ns = stamp_of(db, ctx)
        frames = (parent, child)
        packer = self._one  # one transform: its packer kept, without emit's lookups
        if packer is None or frames != self._frames:
            self._frames, packer = frames, self._packer_of((frames,))
            self._one = packer
        raw = packer.pack(*divmod(ns, 1_000_000_000), *tr, *rot)
        self._pub.publish_serialized(raw, partial(_one_transform, ns, parent, child, tr, rot))
        return True

    def edges(self, value: Callable[[str], Any]) -> list[TfEdge]:
        topic, static = self.edge_topic(value)
        return [TfEdge(str(value("parentFrameId")), str(value("childFrameId")), static, topic)]


def frame_pose(world: Any, prim: str) -> tuple[np.ndarray, np.ndarray]:
    """World pose (position, wxyz) of ``prim``'s TF frame. Like Isaac's transform-tree
    publishers, a camera prim's frame is its ROS optical frame (+Z forward, +X right, +Y down)."""
    pos, quat = world.prim_pose(prim)
    if world.prim_ref(prim).kind is PrimKind.CAMERA:
        quat = optical_quat(quat)
    return np.asarray(pos, dtype=np.float64), np.asarray(quat, dtype=np.float64)


def relative_pose(world: Any, parent: str | None, child: str) -> tuple[np.ndarray, np.ndarray]:
    """Pose of ``child``'s frame in ``parent``'s (or the world), as (translation, wxyz)."""
    pos, quat = frame_pose(world, child)
    if not parent:
        return pos, quat
    ppos, pquat = frame_pose(world, parent)
    inv = quat_wxyz_conj(pquat)
    return quat_wxyz_rotate(inv, np.asarray(pos) - np.asarray(ppos)), quat_wxyz_mul(inv, quat)


@register("srr.PublishTransformTree", aliases=aliases("PublishTransformTree"))
class PublishTransformTree(_TfPublisher):
    """Transforms of ``targetPrims`` relative to ``parentPrim`` (default: the world frame).
    Camera prims stand for their ROS optical frames (see :func:`frame_pose`).

    Frames are named after the prims (their last path component) with ``frameIdPrefix`` in
    front (an srr input, like robot_state_publisher's ``frame_prefix``; empty in Isaac), so
    several robots built from one model publish distinct frames. ``worldFrameId`` is never
    prefixed.

    A target that is a robot's articulation root (its root link's prim, or the robot prim)
    stands for the whole robot, as in Isaac Sim: the root relative to ``parentPrim`` and
    every other link relative to its parent link, each named after its link. A target equal
    to ``parentPrim`` publishes no transform of its own (so ``parentPrim`` = ``targetPrims``
    = the root publishes only the links, leaving the root's pose to odometry)."""

    inputs = (
        *BRIDGE_INPUTS,
        Attr("topicName", "string", "tf"),
        Attr("timeStamp", "double", 0.0),
        Attr("parentPrim", "target", ()),
        Attr("targetPrims", "target", ()),
        Attr("staticPublisher", "bool", False),
        Attr("worldFrameId", "string", "world"),
        Attr("frameIdPrefix", "string", ""),
    )
    outputs = EXEC_OUT

    @staticmethod
    def frames(value: Callable[[str], Any]) -> tuple[str, list[tuple[str, str]]]:
        """The parent frame and (target prim, frame) pairs the node publishes."""
        prefix = str(value("frameIdPrefix"))
        parents = _paths(value("parentPrim"))
        parent = prefix + frame_of(parents[0]) if parents else str(value("worldFrameId"))
        return parent, [(p, prefix + frame_of(p)) for p in _paths(value("targetPrims"))
                        if not parents or p != parents[0]]

    @staticmethod
    def link_frames(value: Callable[[str], Any],
                    world: Any) -> list[tuple[str, str, str, str]]:
        """(parent prim, child prim, parent frame, child frame) of the links of every target
        that is an articulation root in ``world``."""
        prefix = str(value("frameIdPrefix"))
        out = []
        for target in _paths(value("targetPrims")):
            for p, c in world.articulation_links(target) or ():
                out.append((p, c, prefix + frame_of(p), prefix + frame_of(c)))
        return out

    def edges(self, value: Callable[[str], Any]) -> list[TfEdge]:
        topic, static = self.edge_topic(value)
        parent, children = self.frames(value)
        return [TfEdge(parent, child, static, topic, "parentPrim", "targetPrims")
                for _, child in children]

    def world_edges(self, value: Callable[[str], Any], world: Any) -> list[TfEdge]:
        topic, static = self.edge_topic(value)
        return [TfEdge(pf, cf, static, topic, "targetPrims", "targetPrims")
                for _, _, pf, cf in self.link_frames(value, world)]

    def initialize(self, db: Any, ctx: Any) -> None:
        super().initialize(db, ctx)
        for prim in (*_paths(db.inputs.parentPrim), *_paths(db.inputs.targetPrims)):
            if not ctx.world.has_prim(prim):
                raise GraphError(f"{db.node_path}: prim {prim!r} does not exist")

    def compute(self, db: Any, ctx: Any) -> bool:
        parents = _paths(db.inputs.parentPrim)
        parent = parents[0] if parents else None

        def value(name: str) -> Any:
            return getattr(db.inputs, name)

        parent_frame, targets = self.frames(value)
        poses = []
        for prim, frame in targets:
            t, q = relative_pose(ctx.world, parent, prim)
            poses.append((parent_frame, frame, t, wxyz_to_xyzw(q)))
        for p, c, pf, cf in self.link_frames(value, ctx.world):
            t, q = relative_pose(ctx.world, p, c)
            poses.append((pf, cf, t, wxyz_to_xyzw(q)))
        key = tuple((pf, cf, tuple(np.round(t, 9)), tuple(np.round(xyzw, 9)))
                    for pf, cf, t, xyzw in poses)
        if self.unchanged(key):
            return True
        self.emit(stamp_of(db, ctx), [Pose(*pose) for pose in poses])
        return True


def _one_transform(ns: int, parent: str, child: str, translation: tuple[float, ...],
                   rotation_xyzw: tuple[float, ...]) -> Any:
    return tf_message_of(ns, [Pose(parent, child, translation, rotation_xyzw)])


def _paths(value: Sequence[Any] | str | None) -> list[str]:
    if not value:
        return []
    if isinstance(value, str):
        return [value]
    return [str(v) for v in value]
