"""The comparator the rclpy conformance test relies on (runs without rclpy)."""

from __future__ import annotations

import array
import struct

import numpy as np

from harness.serde.messages import TYPESTORE, msg_type, odometry
from tests.conformance.values import message_fields, value_diff

ODOM = "nav_msgs/msg/Odometry"
MARK_X = 1234.5678


def _odom_bytes() -> bytes:
    msg = odometry(2_000_000_000, "odom", "base_link", [MARK_X, -2.0, 0.0],
                   [0.0, 0.0, 0.0, 1.0], [1.5, 0.0, 0.0], [0.0, 0.0, 0.25])
    return bytes(TYPESTORE.serialize_cdr(msg, ODOM))


def test_field_names_come_from_the_definition_not_the_dataclass() -> None:
    # rosbags' dataclasses also carry the constants (ARROW, ...) and __msgtype__ as fields
    marker = msg_type("visualization_msgs/msg/Marker")
    fields = message_fields(object.__new__(marker))
    assert fields is not None and fields[:4] == ["header", "ns", "id", "type"]
    assert "ARROW" not in fields and "__msgtype__" not in fields
    assert message_fields(TYPESTORE.deserialize_cdr(_odom_bytes(), ODOM)) == [
        "header", "child_frame_id", "pose", "twist"]
    assert message_fields(1.0) is None and message_fields([1, 2]) is None


def test_identical_decodes_have_no_difference() -> None:
    raw = _odom_bytes()
    assert value_diff(TYPESTORE.deserialize_cdr(raw, ODOM),
                      TYPESTORE.deserialize_cdr(raw, ODOM)) == []


def test_one_corrupted_byte_in_a_numeric_field_is_named() -> None:
    raw = bytearray(_odom_bytes())
    at = raw.find(struct.pack("<d", MARK_X))
    assert at > 0
    good = TYPESTORE.deserialize_cdr(bytes(raw), ODOM)
    raw[at + 4] ^= 0x01  # the middle of the double: a small change of value
    bad = TYPESTORE.deserialize_cdr(bytes(raw), ODOM)
    diff = value_diff(bad, good)
    assert len(diff) == 1 and diff[0].startswith("pose.pose.position.x:"), diff


def test_padding_bytes_are_not_compared() -> None:
    raw = bytearray(_odom_bytes())
    at = raw.find(struct.pack("<d", MARK_X))
    assert raw[at - 6:at] == bytes(6)  # alignment after "base_link\0"
    good = TYPESTORE.deserialize_cdr(bytes(raw), ODOM)
    raw[at - 6:at] = b"\x55" * 6
    assert value_diff(TYPESTORE.deserialize_cdr(bytes(raw), ODOM), good) == []


def test_floats_compare_bit_for_bit() -> None:
    vec = msg_type("geometry_msgs/msg/Vector3")
    assert value_diff(vec(x=0.0, y=1.0, z=2.0), vec(x=-0.0, y=1.0, z=2.0)) == [
        "x: 0.0 != -0.0"]
    assert value_diff(vec(x=float("nan"), y=1.0, z=2.0), vec(x=float("nan"), y=1.0, z=2.0)) == []
    assert value_diff(vec(x=1.0, y=1.0, z=2.0), vec(x=1.0 + 2**-52, y=1.0, z=2.0)) != []


def test_arrays_in_any_representation() -> None:
    a = np.array([1.0, 2.5, -0.0])
    assert value_diff(a, array.array("d", [1.0, 2.5, -0.0])) == []
    assert value_diff(a, array.array("d", [1.0, 2.5, 0.0]))[0].startswith("[2]:")
    assert value_diff(a, np.array([1.0, 2.5])) == [": shape (3,) != (2,)"]
    assert value_diff(np.array([1.5], np.float32), array.array("f", [1.5])) == []
    assert value_diff(np.array([1.5], np.float32), np.array([1], np.int32)) != []
    # ROS byte/octet: signed in rosbags, bytes in rclpy
    assert value_diff(np.array([-1, 2], np.int8), [b"\xff", b"\x02"]) == []
    assert value_diff(np.array([-1, 2], np.int8), [b"\xfe", b"\x02"]) != []
    assert value_diff(np.frombuffer(b"\x01\x02", np.uint8), array.array("B", [1, 2])) == []
    assert value_diff(np.zeros(0), []) == []


def test_sequences_of_messages_and_strings() -> None:
    point = msg_type("geometry_msgs/msg/Point")
    assert value_diff([point(x=1.0, y=2.0, z=3.0)], [point(x=1.0, y=2.0, z=3.0)]) == []
    assert value_diff([point(x=1.0, y=2.0, z=3.0)], [point(x=1.0, y=2.0, z=4.0)]) == [
        "[0].z: 3.0 != 4.0"]
    assert value_diff(["a", "b"], ["a", "c"]) == ["[1]: 'b' != 'c'"]
    assert value_diff(["a"], ["a", "b"]) == [": length 1 != 2"]


def test_scalars_of_different_kinds_differ() -> None:
    assert value_diff(1, 1.0) != []
    assert value_diff(True, 1) != []
    assert value_diff(b"\xff", -1) == []  # byte scalar: rclpy bytes, rosbags signed int
    assert value_diff("odom", "odom ") != []


def test_different_message_types_differ() -> None:
    vec = msg_type("geometry_msgs/msg/Vector3")
    quat = msg_type("geometry_msgs/msg/Quaternion")
    diff = value_diff(vec(x=0.0, y=0.0, z=0.0), quat(x=0.0, y=0.0, z=0.0, w=1.0))
    assert diff and "fields" in diff[0]
