"""An external ROS 2 node in its own process (not srr code): on every odometry message it
publishes a cmd_vel computed from that message alone — forward speed ramping with the
odometry's stamp, turning while y < 0 — so a lockstep run is deterministic.

    python ext_cmd_node.py [--silent-after SEC] [--exit-after SEC] --ros-args -p use_sim_time:=true
"""

from __future__ import annotations

import os
import sys

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.node import Node


class Commander(Node):
    def __init__(self, silent_after: float | None, exit_after: float | None) -> None:
        super().__init__("ext_commander")
        self.silent_after = silent_after
        self.exit_after = exit_after
        self.pub = self.create_publisher(Twist, "/cmd_vel", 100)
        self.create_subscription(Odometry, "/odom", self.on_odom, 100)

    def on_odom(self, odom: Odometry) -> None:
        t = odom.header.stamp.sec + odom.header.stamp.nanosec * 1e-9
        if self.silent_after is not None and t >= self.silent_after:
            return  # a node that stops publishing
        if self.exit_after is not None and t >= self.exit_after:
            os._exit(5)  # a node that dies
        cmd = Twist()
        cmd.linear.x = min(1.2, 0.3 + 0.5 * t)
        cmd.angular.z = 0.25 if odom.pose.pose.position.y < 0.0 else 0.0
        self.pub.publish(cmd)


def main() -> None:
    args = rclpy.utilities.remove_ros_args(sys.argv)
    silent = float(args[args.index("--silent-after") + 1]) if "--silent-after" in args else None
    dies = float(args[args.index("--exit-after") + 1]) if "--exit-after" in args else None
    rclpy.init()
    node = Commander(silent, dies)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
