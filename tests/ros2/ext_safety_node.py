"""An external safety monitor in its own process (not srr code): on every
/perception/tracks message, /safety/is_muted = the forklift past the trailer tripwire (by its
odometry, placed in the world through the world → odom transform on /tf_static) and no
tracked person in the loading ROI; /safety/alarm = a person in the ROI.

    python ext_safety_node.py --ros-args -p use_sim_time:=true
"""

from __future__ import annotations

import math

import rclpy
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from std_msgs.msg import Bool
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

ROI = ((10.0, -3.0), (14.5, -3.0), (14.5, 3.0), (10.0, 3.0))
TRIPWIRE_X = 17.0  # a=(17, 3) → b=(17, -3), inside = left of a→b = +x


def inside(x: float, y: float, poly: tuple[tuple[float, float], ...]) -> bool:
    xs, ys = [p[0] for p in poly], [p[1] for p in poly]
    return min(xs) <= x <= max(xs) and min(ys) <= y <= max(ys)


class Monitor(Node):
    def __init__(self) -> None:
        super().__init__("ext_safety_monitor")
        self.origin: tuple[float, float, float] | None = None  # world → odom: x, y, yaw
        self.pose: tuple[float, float] | None = None
        self.muted = self.create_publisher(Bool, "/safety/is_muted", 100)
        self.alarm = self.create_publisher(Bool, "/safety/alarm", 100)
        self.create_subscription(Odometry, "/odom", self.on_odom, 100)
        latched = QoSProfile(depth=100, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.create_subscription(TFMessage, "/tf_static", self.on_tf_static, latched)
        self.create_subscription(MarkerArray, "/perception/tracks", self.on_tracks, 100)

    def on_tf_static(self, msg: TFMessage) -> None:
        for tf in msg.transforms:
            if tf.header.frame_id == "world" and tf.child_frame_id == "odom":
                t, q = tf.transform.translation, tf.transform.rotation
                yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y ** 2 + q.z ** 2))
                self.origin = (t.x, t.y, yaw)

    def on_odom(self, odom: Odometry) -> None:
        if self.origin is None:
            return
        p = odom.pose.pose.position
        x0, y0, yaw = self.origin
        self.pose = (x0 + math.cos(yaw) * p.x - math.sin(yaw) * p.y,
                     y0 + math.sin(yaw) * p.x + math.cos(yaw) * p.y)

    def on_tracks(self, tracks: MarkerArray) -> None:
        people = [(m.pose.position.x, m.pose.position.y) for m in tracks.markers
                  if m.action == 0 and m.ns == "person"]
        person = any(inside(x, y, ROI) for x, y in people)
        in_trailer = self.pose is not None and self.pose[0] > TRIPWIRE_X
        self.muted.publish(Bool(data=in_trailer and not person))
        self.alarm.publish(Bool(data=person))


def main() -> None:
    rclpy.init()
    node = Monitor()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
