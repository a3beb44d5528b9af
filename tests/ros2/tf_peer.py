"""A ROS 2 node in its own process that publishes or subscribes ``tf2_msgs/msg/TFMessage``
with real rclpy, for ``test_tf2_msgs.py``.

``python -m tests.ros2.tf_peer publish TOPIC typed|raw`` publishes :data:`TRANSFORMS` as one
TFMessage: ``typed`` builds it with rclpy's generated class, ``raw`` publishes the bytes
``harness.serde.messages`` serializes (as the recorder writes them). ``/tf`` is volatile and
republished every 50 ms; ``/tf_static`` is transient-local and published once, as
``tf2_ros.StaticTransformBroadcaster`` does. It prints ``ready`` after the first publication
and exits when its standard input closes (or after ``--timeout``), saying on standard output
whether it ever had a subscriber.

``python -m tests.ros2.tf_peer subscribe TOPIC OUT.json`` subscribes twice, raw and typed,
and writes the first message of each plus the publishers' endpoint info to ``OUT.json``.

The parent picks ``ROS_DOMAIN_ID``; discovery stays on this host.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import threading
import time
from pathlib import Path
from typing import Any

from harness.serde import messages

# (sec, nanosec, parent, child, translation, rotation xyzw). The frame names are chosen so
# the CDR has no padding (test_tf2_msgs checks it): Fast CDR leaves padding uninitialised,
# and without it every byte rclpy sends is a value byte, comparable with rosbags' output.
TRANSFORMS: list[tuple[int, int, str, str, list[float], list[float]]] = [
    (12, 500_000_000, "station", "robot1/odom", [1.5, -2.25, 0.0],
     [0.0, 0.0, 0.3826834323650898, 0.9238795325112867]),
    (12, 500_000_001, "robot1/odom", "robot1/base", [0.1, 1e-300, -7.0],
     [-0.0, 0.0, 0.0, 1.0]),
]
TYPENAME = "tf2_msgs/msg/TFMessage"


def rosbags_message() -> Any:
    return messages.tf_message([
        messages.transform_stamped(sec * 1_000_000_000 + nsec, parent, child, xyz, q)
        for sec, nsec, parent, child, xyz, q in TRANSFORMS])


def rosbags_bytes() -> bytes:
    return messages.serialize(rosbags_message(), TYPENAME)


def as_plain(msg: Any) -> list[dict[str, Any]]:
    """A TFMessage (rclpy's or rosbags') as plain values, floats as exact hex strings."""
    out = []
    for t in msg.transforms:
        tr, rot = t.transform.translation, t.transform.rotation
        out.append({
            "stamp": [t.header.stamp.sec, t.header.stamp.nanosec],
            "frame_id": t.header.frame_id, "child_frame_id": t.child_frame_id,
            "translation": [float(v).hex() for v in (tr.x, tr.y, tr.z)],
            "rotation": [float(v).hex() for v in (rot.x, rot.y, rot.z, rot.w)]})
    return out


def _qos(topic: str) -> Any:
    """tf2_ros's QoS: /tf_static latched (transient-local, depth 1), /tf volatile."""
    qos: Any = importlib.import_module("rclpy.qos")  # untyped
    if topic.endswith("tf_static"):
        return qos.QoSProfile(depth=1, reliability=qos.ReliabilityPolicy.RELIABLE,
                              durability=qos.DurabilityPolicy.TRANSIENT_LOCAL)
    return qos.QoSProfile(depth=100, reliability=qos.ReliabilityPolicy.RELIABLE,
                          durability=qos.DurabilityPolicy.VOLATILE)


def _typed_message() -> Any:
    from builtin_interfaces.msg import Time
    from geometry_msgs.msg import Quaternion, Transform, TransformStamped, Vector3
    from std_msgs.msg import Header
    from tf2_msgs.msg import TFMessage

    return TFMessage(transforms=[
        TransformStamped(header=Header(stamp=Time(sec=sec, nanosec=nsec), frame_id=parent),
                         child_frame_id=child,
                         transform=Transform(translation=Vector3(x=xyz[0], y=xyz[1], z=xyz[2]),
                                             rotation=Quaternion(x=q[0], y=q[1], z=q[2],
                                                                 w=q[3])))
        for sec, nsec, parent, child, xyz, q in TRANSFORMS])


def publish(topic: str, mode: str, timeout: float) -> int:
    import rclpy
    from rclpy.event_handler import PublisherEventCallbacks
    from rclpy.executors import SingleThreadedExecutor
    from tf2_msgs.msg import TFMessage

    rclpy.init()
    node: Any = rclpy.create_node("srr_tf_publisher")
    # every match counts, also one whose subscriber took the latched message and left
    # between two looks at the subscription count
    matches = [0]

    def on_matched(status: Any) -> None:
        matches[0] = max(matches[0], int(status.total_count))

    pub = node.create_publisher(TFMessage, topic, _qos(topic),
                                event_callbacks=PublisherEventCallbacks(matched=on_matched))
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    msg = _typed_message() if mode == "typed" else rosbags_bytes()
    latched = topic.endswith("tf_static")
    pub.publish(msg)
    print("ready", flush=True)
    stop = threading.Event()

    def wait_for_eof() -> None:
        sys.stdin.read()
        stop.set()

    threading.Thread(target=wait_for_eof, daemon=True).start()
    deadline, seen = time.monotonic() + timeout, False
    while time.monotonic() < deadline and not stop.is_set():
        executor.spin_once(timeout_sec=0.05)
        seen = seen or pub.get_subscription_count() > 0 or matches[0] > 0
        if not latched:
            pub.publish(msg)
    for _ in range(10):  # events already on their way
        executor.spin_once(timeout_sec=0.02)
    seen = seen or matches[0] > 0
    print("had a subscriber" if seen else "never had a subscriber", flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


def subscribe(topic: str, out: Path, timeout: float) -> int:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from tf2_msgs.msg import TFMessage

    rclpy.init()
    node: Any = rclpy.create_node("srr_tf_subscriber")
    got: dict[str, Any] = {}

    def on_raw(data: bytes) -> None:
        got.setdefault("raw", bytes(data).hex())

    def on_typed(msg: Any) -> None:
        got.setdefault("typed", as_plain(msg))

    node.create_subscription(TFMessage, topic, on_raw, _qos(topic), raw=True)
    node.create_subscription(TFMessage, topic, on_typed, _qos(topic))
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not {"raw", "typed"} <= got.keys():
        executor.spin_once(timeout_sec=0.05)
    # the node name comes with ROS's own discovery topic, possibly after the data
    deadline = time.monotonic() + 10.0
    while True:
        infos = node.get_publishers_info_by_topic(topic)
        known = all(i.node_name != "_NODE_NAME_UNKNOWN_" for i in infos)
        if (infos and known) or time.monotonic() > deadline:
            break
        executor.spin_once(timeout_sec=0.05)
    got["publishers"] = [
        {"node": info.node_name, "type": info.topic_type, "hash": str(info.topic_type_hash)}
        for info in infos]
    out.write_text(json.dumps(got, indent=1), encoding="utf-8")
    node.destroy_node()
    rclpy.shutdown()
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    sub = p.add_subparsers(dest="role", required=True)
    pp = sub.add_parser("publish")
    pp.add_argument("topic")
    pp.add_argument("mode", choices=["typed", "raw"])
    ss = sub.add_parser("subscribe")
    ss.add_argument("topic")
    ss.add_argument("out", type=Path)
    for parser in (pp, ss):
        parser.add_argument("--timeout", type=float, default=30.0)
    args = p.parse_args(argv)
    from harness.ros2.tf2_msgs import ensure_tf2_msgs

    if not ensure_tf2_msgs(build=False):  # the test built it; this process only finds it
        print("tf2_msgs is not built", file=sys.stderr)
        return 3
    if args.role == "publish":
        return publish(args.topic, args.mode, args.timeout)
    return subscribe(args.topic, args.out, args.timeout)


if __name__ == "__main__":
    sys.exit(main())
