"""Where a robot is in the world, as a system under test can know it: ``odom`` composed with
the static transforms from the world frame to the odometry's frame (``/tf_static``). No ground
truth involved."""

from __future__ import annotations

from typing import Any

import numpy as np

from harness.bus import Envelope, resolved
from harness.geometry import (
    quat_wxyz_mul,
    quat_wxyz_mul_floats,
    quat_wxyz_rotate,
    quat_wxyz_rotate_floats,
    xyzw_to_wxyz,
    yaw_from_quat_wxyz,
)
from harness.serde.messages import OdometryPose, odometry_pose
from harness.sut.base import SutContext

__all__ = ["OdomPose"]

_Transform = tuple[np.ndarray, np.ndarray]  # translation, rotation (w, x, y, z)


class OdomPose:
    """Subscribes to ``odom_topic`` and ``tf_static_topic``; :meth:`pose` gives (x, y, yaw).

    The odometry is placed in ``world_frame`` through the static chain from the world frame to
    ``odom_frame`` — by default the frame the odometry messages name in their header, so a
    robot whose frames carry a prefix (``forklift_b/odom``) needs no configuration, as with a
    tf2 lookup."""

    def __init__(self, ctx: SutContext, odom_topic: str, tf_static_topic: str = "/tf_static",
                 world_frame: str = "world", odom_frame: str = "") -> None:
        self.world_frame = world_frame
        self.odom_frame = odom_frame
        self._odom: Envelope | None = None
        self._static: dict[str, tuple[str, _Transform]] = {}
        self._chain: tuple[str, _Transform | None] | None = None
        # the latest envelope only: a message is built when pose() reads it, not per message
        ctx.subscribe_envelopes(odom_topic, "nav_msgs/msg/Odometry", self._on_odom)
        ctx.subscribe(tf_static_topic, "tf2_msgs/msg/TFMessage", self._on_tf)

    def _on_odom(self, env: Envelope) -> None:
        self._odom = env

    @property
    def odom(self) -> Any:
        """The latest odometry message, or None before the first."""
        return None if self._odom is None else resolved(self._odom.msg)

    def _on_tf(self, msg: Any) -> None:
        for tf in msg.transforms:
            t, r = tf.transform.translation, tf.transform.rotation
            self._static[tf.child_frame_id] = (tf.header.frame_id, (
                np.array([t.x, t.y, t.z]), xyzw_to_wxyz([r.x, r.y, r.z, r.w])))
        self._chain = None

    def world_from(self, frame: str) -> _Transform | None:
        """Pose of ``frame`` in the world frame from the static transforms, or None."""
        if self._chain is not None and self._chain[0] == frame:
            return self._chain[1]
        t, q = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])
        cur, seen, found = frame, set(), True
        while cur != self.world_frame:
            if cur in seen or cur not in self._static:
                found = False
                break
            seen.add(cur)
            parent, (pt, pq) = self._static[cur]
            t, q = pt + quat_wxyz_rotate(pq, t), quat_wxyz_mul(pq, q)
            cur = parent
        result = (t, q) if found else None
        self._chain = (frame, result)
        return result

    def pose(self) -> tuple[float, float, float] | None:
        """Robot pose in the world frame, or None until odom and its static chain are known."""
        read = self._odom_pose()
        if read is None:
            return None
        frame_id, (px, py, pz), (qx, qy, qz, qw) = read
        chain = self.world_from(self.odom_frame or frame_id)
        if chain is None:
            return None
        # Python floats: the arithmetic of quat_wxyz_rotate / quat_wxyz_mul on arrays, term for
        # term (see harness.geometry), without building arrays.
        t0, q0 = chain
        tx, ty, _ = t0.tolist()
        q0f = q0.tolist()
        rx, ry, _ = quat_wxyz_rotate_floats(q0f, (px, py, pz))
        q_odom = (float(qw), float(qx), float(qy), float(qz))
        yaw = yaw_from_quat_wxyz(quat_wxyz_mul_floats(q0f, q_odom))
        return tx + rx, ty + ry, yaw

    def _odom_pose(self) -> OdometryPose | None:
        """The latest odometry's frame id, position and orientation (x, y, z, w), or None
        before the first: read from its CDR bytes when it came with them (the graphs'
        publisher packs it; no message object is built), else from the message."""
        env = self._odom
        if env is None:
            return None
        if env.raw is not None and env.encoding == "cdr":
            read = odometry_pose(env.raw)
            if read is not None:
                return read
        odom = resolved(env.msg)
        p, q = odom.pose.pose.position, odom.pose.pose.orientation
        return odom.header.frame_id, (p.x, p.y, p.z), (q.x, q.y, q.z, q.w)
