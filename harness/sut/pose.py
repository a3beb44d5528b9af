"""Where a robot is in the world, as a system under test can know it: ``odom`` composed with
the static ``world → odom`` transform from ``/tf_static``. No ground truth involved."""

from __future__ import annotations

from typing import Any

import numpy as np

from harness.geometry import quat_mul, quat_rotate, quat_to_yaw, xyzw_to_wxyz
from harness.sut.base import SutContext

__all__ = ["OdomPose"]


class OdomPose:
    """Subscribes to ``odom_topic`` and ``tf_static_topic``; :meth:`pose` gives (x, y, yaw)."""

    def __init__(self, ctx: SutContext, odom_topic: str, tf_static_topic: str = "/tf_static",
                 world_frame: str = "world", odom_frame: str = "odom") -> None:
        self.world_frame = world_frame
        self.odom_frame = odom_frame
        self.odom: Any = None
        self.world_from_odom: tuple[np.ndarray, np.ndarray] | None = None
        ctx.subscribe(odom_topic, "nav_msgs/msg/Odometry", self._on_odom)
        ctx.subscribe(tf_static_topic, "tf2_msgs/msg/TFMessage", self._on_tf)

    def _on_odom(self, msg: Any) -> None:
        self.odom = msg

    def _on_tf(self, msg: Any) -> None:
        for tf in msg.transforms:
            if tf.header.frame_id == self.world_frame and tf.child_frame_id == self.odom_frame:
                t, r = tf.transform.translation, tf.transform.rotation
                self.world_from_odom = (np.array([t.x, t.y, t.z]),
                                        xyzw_to_wxyz([r.x, r.y, r.z, r.w]))

    def pose(self) -> tuple[float, float, float] | None:
        """Robot pose in the world frame, or None until odom and world → odom are known."""
        if self.odom is None or self.world_from_odom is None:
            return None
        p, q = self.odom.pose.pose.position, self.odom.pose.pose.orientation
        t0, q0 = self.world_from_odom
        pos = t0 + quat_rotate(q0, [p.x, p.y, p.z])
        yaw = quat_to_yaw(quat_mul(q0, xyzw_to_wxyz([q.x, q.y, q.z, q.w])))
        return float(pos[0]), float(pos[1]), yaw
