"""A raw ROS 2 tap in its own process (not srr code): subscribes to each TOPIC=TYPE as
serialized bytes (``/tf_static`` transient local, as a late joiner would) and writes OUT.json
when it is stopped: every message's bytes (hex) per topic, and the QoS its publishers offer.
It advertises ``/tap/ready`` once its subscriptions exist (a ``ready_topic``). On SIGINT it
first takes every message already delivered to it, then writes.

    python tap_node.py OUT.json /clock=rosgraph_msgs/msg/Clock ... --ros-args -p use_sim_time:=true
"""

from __future__ import annotations

import importlib
import json
import signal
import sys
from pathlib import Path
from typing import Any

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import Bool


def main() -> None:
    args = rclpy.utilities.remove_ros_args(sys.argv)
    out, specs = Path(args[1]), [a.split("=", 1) for a in args[2:]]
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop: list[int] = []
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    node = rclpy.create_node("srr_test_tap")
    got: dict[str, list[str]] = {t: [] for t, _ in specs}
    offered: dict[str, list[dict[str, Any]]] = {}

    def take(topic: str, raw: bytes) -> None:
        got[topic].append(bytes(raw).hex())
        if topic not in offered:  # the publishers' QoS, as discovery reports it
            offered[topic] = [{"durability": i.qos_profile.durability.name,
                               "reliability": i.qos_profile.reliability.name}
                              for i in node.get_publishers_info_by_topic(topic)]

    for topic, msgtype in specs:
        pkg, kind, name = msgtype.split("/")
        cls = getattr(importlib.import_module(f"{pkg}.{kind}"), name)
        durability = (DurabilityPolicy.TRANSIENT_LOCAL if topic == "/tf_static"
                      else DurabilityPolicy.VOLATILE)
        node.create_subscription(cls, topic, lambda raw, t=topic: take(t, raw),
                                 QoSProfile(depth=1000, durability=durability), raw=True)
    node.create_publisher(Bool, "/tap/ready", 1)
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    while not stop:
        executor.spin_once(timeout_sec=0.05)
    while True:  # what was delivered before the stop: every message srr sent (it waits for
        n = sum(map(len, got.values()))  # the acknowledgements before it stops us)
        executor.spin_once(timeout_sec=0.0)
        if sum(map(len, got.values())) == n:
            break
    out.write_text(json.dumps({"messages": got, "offered": offered}), encoding="utf-8")
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == "__main__":
    main()
