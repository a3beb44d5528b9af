"""CDR from compiled layouts and packers is byte for byte rosbags' serializer: random messages
of every ROS 2 Jazzy type, every message of a real run, the packers of the publishers, and the
same errors where a value does not fit."""

from __future__ import annotations

import random
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.interfaces import Nodetype

from harness import api
from harness.serde.cdr import Serializer
from harness.serde.messages import (
    TYPESTORE,
    Pose,
    clock,
    clock_packer,
    msg_type,
    odometry,
    odometry_packer,
    odometry_pose,
    serialize,
    split_ns,
    tf_message_of,
    tf_packer,
    twist,
    twist_packer,
)
from tests.conftest import SCENARIOS


def rosbags(msg: Any, msgtype: str) -> bytes:
    return bytes(TYPESTORE.serialize_cdr(msg, msgtype))


_INTS = {"int8": (-2**7, 2**7 - 1), "byte": (-2**7, 2**7 - 1), "uint8": (0, 2**8 - 1),
         "char": (0, 2**8 - 1), "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1),
         "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
         "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1)}
_DTYPES = {"bool": np.bool_, "byte": np.int8, "char": np.uint8, "int8": np.int8,
           "uint8": np.uint8, "int16": np.int16, "uint16": np.uint16, "int32": np.int32,
           "uint32": np.uint32, "int64": np.int64, "uint64": np.uint64,
           "float32": np.float32, "float64": np.float64}
_TEXT = ["", "a", "odom", "base_link", "forklift/base_footprint", "é", "日本語", "x" * 13]


def _number(rng: random.Random, base: str) -> Any:
    if base == "bool":
        return rng.random() < 0.5
    if base in _INTS:
        lo, hi = _INTS[base]
        return rng.choice([lo, hi, 0, rng.randint(lo, hi)])
    if base == "float32":
        return rng.choice([0.0, -0.0, 1.5, rng.uniform(-1e6, 1e6)])
    return rng.choice([0.0, -0.0, float("inf"), 1e-310, rng.uniform(-1e9, 1e9)])


def _array(rng: random.Random, base: str, count: int) -> np.ndarray:
    dtype = _DTYPES[base]
    if base == "bool":
        return np.array([rng.random() < 0.5 for _ in range(count)], dtype=dtype)
    if base in _INTS:
        lo, hi = _INTS[base]
        return np.array([rng.randint(lo, hi) for _ in range(count)], dtype=dtype)
    return np.array([rng.uniform(-1e3, 1e3) for _ in range(count)], dtype=dtype)


def random_message(rng: random.Random, msgtype: str, depth: int = 0) -> Any:
    """A message of ``msgtype`` with random values, strings and sequence lengths."""
    _, fields = TYPESTORE.fielddefs[msgtype]
    values: dict[str, Any] = {}
    for name, (kind, detail) in fields:
        if kind == Nodetype.BASE:
            base = detail[0]
            values[name] = rng.choice(_TEXT) if base == "string" else _number(rng, base)
        elif kind == Nodetype.NAME:
            values[name] = random_message(rng, detail, depth + 1)
        elif kind == Nodetype.ARRAY:
            (_, sub), count = detail
            values[name] = _array(rng, sub[0], count)
        else:
            (sub_kind, sub), _ = detail
            n = rng.randint(0, 3 if depth < 2 else 1)
            if sub_kind == Nodetype.NAME:
                values[name] = [random_message(rng, sub, depth + 1) for _ in range(n)]
            elif sub[0] == "string":
                values[name] = [rng.choice(_TEXT) for _ in range(n)]
            else:
                values[name] = _array(rng, sub[0], n)
    return msg_type(msgtype)(**values)


@pytest.mark.parametrize("msgtype", sorted(TYPESTORE.fielddefs))
def test_every_type_serializes_as_rosbags_does(msgtype: str) -> None:
    layouts = Serializer(TYPESTORE, rosbags)
    layout = layouts.layout(msgtype)
    assert layout is not None, f"{msgtype} has no compiled layout"
    rng = random.Random(msgtype)
    for _ in range(20):
        msg = random_message(rng, msgtype)
        expected = rosbags(msg, msgtype)
        assert layout.serialize(msg) == expected  # the layout itself, no fallback
        assert b"".join(layout.serialize_pieces(msg)) == expected


def test_large_arrays_stay_the_messages_own_buffers() -> None:
    """In pieces, a large numeric array is a read-only view of the message's array (not a
    copy) and the fields after it are laid out as if it had been copied: an image, a point
    cloud (a bool after its data), a scan (a float array after a float array of odd
    length)."""
    from harness.serde.messages import make, serialize_pieces
    from harness.serde.pieces import LARGE as LARGE_ARRAY

    rng = np.random.default_rng(7)
    image = make("sensor_msgs/msg/Image", height=130, width=131, encoding="32FC1", step=524,
                 data=rng.integers(0, 255, 130 * 524, dtype=np.uint8))
    cloud = make("sensor_msgs/msg/PointCloud2", height=1, width=7000, point_step=12,
                 row_step=84000, is_dense=True,
                 data=rng.integers(0, 255, 84000, dtype=np.uint8))
    scan = make("sensor_msgs/msg/LaserScan", range_max=9.5,
                ranges=rng.random(LARGE_ARRAY // 4 + 3, dtype=np.float32),
                intensities=rng.random(5, dtype=np.float32))
    for msg, array in ((image, image.data), (cloud, cloud.data), (scan, scan.ranges)):
        msgtype = msg.__msgtype__
        pieces = serialize_pieces(msg, msgtype)
        assert b"".join(pieces) == rosbags(msg, msgtype), msgtype
        large = [p for p in pieces if len(p) >= LARGE_ARRAY]
        assert len(large) == 1, msgtype
        assert isinstance(large[0], memoryview) and large[0].readonly
        assert np.shares_memory(np.frombuffer(large[0], dtype=np.uint8), array), msgtype
    small = make("sensor_msgs/msg/Image", height=2, width=2, encoding="mono8", step=2,
                 data=np.arange(4, dtype=np.uint8))
    assert serialize_pieces(small, "sensor_msgs/msg/Image") == (
        rosbags(small, "sensor_msgs/msg/Image"),)


@pytest.mark.slow
def test_every_message_of_a_real_run(tmp_path: Path) -> None:
    """Each recorded message, decoded and serialized again, gives the recorded bytes."""
    from rosbags.highlevel import AnyReader

    path = SCENARIOS / "forklift_warehouse.yaml"
    res = api.run_scenario(api.load(path, duration=2.0), source=str(path), out=tmp_path / "r")
    seen: set[str] = set()
    with AnyReader([res.run_dir / "bag"], default_typestore=TYPESTORE) as reader:
        for conn, _, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            assert serialize(msg, conn.msgtype) == bytes(raw), conn.topic
            seen.add(conn.msgtype)
    assert {"nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage", "rosgraph_msgs/msg/Clock",
            "geometry_msgs/msg/Twist"} <= seen


def test_values_that_do_not_fit_get_rosbags_answer() -> None:
    """A list where rosbags wants an array, a wrong dtype, a float for an int: the compiled
    path hands the message over and the result is rosbags' own, bytes or error."""
    same_size = odometry(5, "odom", "base_link", (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0),
                         (0.1, 0.0, 0.0), (0.0, 0.0, 0.2))
    same_size.pose.covariance = np.arange(36, dtype=np.int64)  # rosbags copies the raw bits
    assert serialize(same_size, "nav_msgs/msg/Odometry") == rosbags(same_size,
                                                                    "nav_msgs/msg/Odometry")
    for broken in ("list", "short", "float32"):
        msg = odometry(5, "odom", "base_link", (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0),
                       (0.1, 0.0, 0.0), (0.0, 0.0, 0.2))
        msg.pose.covariance = {"list": [0.0] * 36, "short": np.zeros(35),
                               "float32": np.zeros(36, dtype=np.float32)}[broken]
        with pytest.raises(Exception) as ours:
            serialize(msg, "nav_msgs/msg/Odometry")
        with pytest.raises(Exception) as theirs:
            rosbags(msg, "nav_msgs/msg/Odometry")
        assert type(ours.value) is type(theirs.value) and str(ours.value) == str(theirs.value)
    stamp = clock(0)
    stamp.clock.sec = 1.5  # not an int
    with pytest.raises(Exception) as ours:
        serialize(stamp, "rosgraph_msgs/msg/Clock")
    with pytest.raises(Exception) as theirs:
        rosbags(stamp, "rosgraph_msgs/msg/Clock")
    assert type(ours.value) is type(theirs.value)


@pytest.mark.parametrize("seed", range(5))
def test_packers_give_the_bytes_of_the_messages_they_stand_for(seed: int) -> None:
    rng = random.Random(seed)
    for _ in range(50):
        ns = rng.choice([0, 1, 999_999_999, 1_000_000_000, rng.randint(0, 2**40)])
        sec, nanosec = split_ns(ns)
        assert clock_packer().pack(sec, nanosec) == rosbags(clock(ns),
                                                            "rosgraph_msgs/msg/Clock")

        frames = [(rng.choice(_TEXT), rng.choice(_TEXT)) for _ in range(rng.randint(0, 4))]
        poses = [Pose(parent, child, tuple(_number(rng, "float64") for _ in range(3)),
                      tuple(rng.uniform(-1, 1) for _ in range(4))) for parent, child in frames]
        values = [v for p in poses for v in (sec, nanosec, *p.translation, *p.rotation_xyzw)]
        assert tf_packer(frames).pack(*values) == rosbags(tf_message_of(ns, poses),
                                                          "tf2_msgs/msg/TFMessage")

        odom_frame, child = rng.choice(_TEXT), rng.choice(_TEXT)
        pos, lin, ang = ([rng.uniform(-50, 50) for _ in range(3)] for _ in range(3))
        ori = [rng.uniform(-1, 1) for _ in range(4)]
        raw = odometry_packer(odom_frame, child).pack(sec, nanosec, *pos, *ori, *lin, *ang)
        assert raw == rosbags(odometry(ns, odom_frame, child, pos, ori, lin, ang),
                              "nav_msgs/msg/Odometry")

        assert twist_packer().pack(*lin, *ang) == rosbags(twist(lin, ang),
                                                          "geometry_msgs/msg/Twist")


def test_a_packer_refuses_what_it_does_not_lay_out() -> None:
    with pytest.raises(ValueError, match="no number field"):
        tf_packer([("a", "b")]).__class__(TYPESTORE, "rosgraph_msgs/msg/Clock", clock(0),
                                           ("clock.frame_id",))
    with pytest.raises(ValueError, match="2 values expected"):
        clock_packer().pack(1)


@pytest.mark.parametrize("frames", [("odom", "base_link"), ("", ""), ("o", "b"),
                                    ("forklift_b/odom", "forklift_b/base_link"),
                                    ("ödom", "bäse"), ("abc", "abcdefg"), ("abcd", "")])
def test_odometry_pose_reads_the_messages_own_values(frames: tuple[str, str]) -> None:
    """The frame id, position and orientation read from an Odometry's CDR bytes are the
    message's, bit for bit, whatever the frame ids' lengths do to the alignment; from
    rosbags' bytes and from the publisher's packer alike."""
    rng = random.Random(len(frames[0]) * 31 + len(frames[1]))
    for _ in range(50):
        values = [rng.choice([rng.uniform(-1e3, 1e3), -0.0, 1e-310, float("inf")])
                  for _ in range(13)]
        pos, ori, lin, ang = values[:3], values[3:7], values[7:10], values[10:]
        ns = rng.randint(0, 10**12)
        msg = odometry(ns, *frames, pos, ori, lin, ang)
        packed = odometry_packer(*frames).pack(*split_ns(ns), *pos, *ori, *lin, *ang)
        for raw in (rosbags(msg, "nav_msgs/msg/Odometry"), packed):
            got = odometry_pose(raw)
            assert got is not None
            frame_id, position, orientation = got
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            assert frame_id == msg.header.frame_id
            assert [v.hex() for v in position] == [v.hex() for v in (p.x, p.y, p.z)]
            assert [v.hex() for v in orientation] == [v.hex() for v in (q.x, q.y, q.z, q.w)]


def test_odometry_pose_of_other_bytes_is_none() -> None:
    """Bytes that are not little-endian CDR (big-endian CDR, a ROS 1 message) are not read."""
    raw = rosbags(odometry(1, "odom", "base", (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0),
                           (0.0,) * 3, (0.0,) * 3), "nav_msgs/msg/Odometry")
    assert odometry_pose(b"\x00\x00\x00\x00" + raw[4:]) is None
    assert odometry_pose(b"") is None
