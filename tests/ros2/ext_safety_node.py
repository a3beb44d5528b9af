"""An external safety monitor in its own process (not srr code): on every
/perception/tracks message, /safety/is_muted = the forklift past the trailer tripwire (by its
odometry, placed in the world through the world → odom transform on /tf_static) and no
tracked person in the loading ROI; /safety/alarm = a person in the ROI.

Its outputs depend on its inputs only, not on the order topics arrive in: a tracks message
is paired with the odometry of the same stamp (the tracks wait until it is there), as
message_filters' exact-time synchroniser would.

    python ext_safety_node.py [--mute-after N] [--exit-after SEC] [--work-ms MS] \
        --ros-args -p use_sim_time:=true

``--mute-after N``: a slower reaction — mute only once the condition has held for N
consecutive tracks messages. ``--exit-after SEC``: the process dies at the first odometry
message stamped at or after SEC (a node that crashes mid-run). ``--work-ms MS``: each answer
takes MS more milliseconds of wall-clock time (a heavier stack; the outputs are the same).
"""

from __future__ import annotations

import math
import os
import sys
import time

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
    def __init__(self, mute_after: int = 1, exit_after: float | None = None,
                 work_s: float = 0.0) -> None:
        super().__init__("ext_safety_monitor")
        self.work_s = work_s
        self.mute_after = mute_after
        self.exit_after = exit_after
        self.held = 0  # consecutive tracks messages with the mute condition true
        self.origin: tuple[float, float, float] | None = None  # world → odom: x, y, yaw
        self.odom: dict[int, tuple[float, float]] = {}  # stamp → odometry x, y
        self.waiting: list[tuple[int, MarkerArray]] = []  # tracks without their odometry yet
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
        self.flush()

    def on_odom(self, odom: Odometry) -> None:
        stamp = odom.header.stamp.sec * 1_000_000_000 + odom.header.stamp.nanosec
        if self.exit_after is not None and stamp >= self.exit_after * 1e9:
            os._exit(7)  # a node that dies
        p = odom.pose.pose.position
        self.odom[stamp] = (p.x, p.y)
        self.flush()

    def on_tracks(self, tracks: MarkerArray) -> None:
        if tracks.markers:  # the first one (DELETEALL) carries the stamp
            s = tracks.markers[0].header.stamp
            self.waiting.append((s.sec * 1_000_000_000 + s.nanosec, tracks))
            self.flush()

    def flush(self) -> None:
        """Answer every tracks message whose odometry (and the odom origin) is there, in
        order; one whose odometry was lost (a later one came instead) is never answered."""
        while self.waiting and self.origin is not None:
            stamp, tracks = self.waiting[0]
            if stamp not in self.odom:
                if not self.odom or max(self.odom) < stamp:
                    return  # its odometry is still to come
                self.waiting.pop(0)  # lost: skipped, as an exact-time synchroniser does
                continue
            self.waiting.pop(0)
            self.answer(self.odom[stamp], tracks)
            self.odom = {t: xy for t, xy in self.odom.items() if t >= stamp}

    def answer(self, odom: tuple[float, float], tracks: MarkerArray) -> None:
        assert self.origin is not None
        if self.work_s:
            time.sleep(self.work_s)
        x0, _y0, yaw = self.origin
        x = x0 + math.cos(yaw) * odom[0] - math.sin(yaw) * odom[1]
        people = [(m.pose.position.x, m.pose.position.y) for m in tracks.markers
                  if m.action == 0 and m.ns == "person"]
        person = any(inside(px, py, ROI) for px, py in people)
        in_trailer = x > TRIPWIRE_X
        self.held = self.held + 1 if in_trailer and not person else 0
        self.muted.publish(Bool(data=self.held >= self.mute_after))
        self.alarm.publish(Bool(data=person))


def main() -> None:
    args = rclpy.utilities.remove_ros_args(sys.argv)
    after = int(args[args.index("--mute-after") + 1]) if "--mute-after" in args else 1
    dies = float(args[args.index("--exit-after") + 1]) if "--exit-after" in args else None
    work = float(args[args.index("--work-ms") + 1]) / 1e3 if "--work-ms" in args else 0.0
    rclpy.init()
    node = Monitor(after, dies, work)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
