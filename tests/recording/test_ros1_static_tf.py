"""ROS 1 output's static TF: each message of a latched ``tf_static`` topic holds every static
transform sent on that topic so far (by child frame, the latest one, in the order the child
frames were first sent), as ROS 1's ``tf2_ros::StaticTransformBroadcaster`` sends them. So
the last message, the only one ``rosbag play`` latches for a subscriber that joins late,
holds the whole static tree.

The expected messages come from the ROS 2 recording of the same run (its messages as
published; their union so far, message by message). Every recording is read back with
readers independent of srr's: rosbags' for the ROS 2 bag and the ``.bag`` (types from the
file's own definitions), mcap's for the ROS 1 MCAP with rosbags deserializing from the
schema's own definition.
"""

from __future__ import annotations

import hashlib
import json
import struct
from collections import defaultdict
from itertools import pairwise
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Reader as Rosbag1Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from harness import api
from harness.bus import TRANSIENT_LOCAL, Envelope, Qos
from harness.cli import main
from harness.frames import load_frames
from harness.recording.ros1bag import Ros1Recorder
from harness.serde import messages as m
from harness.serde.ros1 import Ros1Encoder
from tests.conftest import SCENARIOS, ModuleTmp

TF = "tf2_msgs/msg/TFMessage"
# child frame → (parent, stamp, translation, rotation xyzw)
Sent = tuple[str, tuple[str, int, tuple[float, ...], tuple[float, ...]]]


class Topic:
    """One connection of a recording, read back: latched or not, each message's transforms
    (child frame and transform, in the message's order) and raw bytes, with log times."""

    def __init__(self) -> None:
        self.latched: bool | None = None
        self.msgs: list[list[Sent]] = []
        self.raw: list[tuple[int, bytes]] = []


def _sent(msg: Any) -> list[Sent]:
    out = []
    for t in msg.transforms:
        tr, rot, st = t.transform.translation, t.transform.rotation, t.header.stamp
        stamp = int(st.sec) * 1_000_000_000 + int(st.nanosec)
        out.append((str(t.child_frame_id), (str(t.header.frame_id), stamp,
                                            (tr.x, tr.y, tr.z), (rot.x, rot.y, rot.z, rot.w))))
    return out


def read_anyreader(path: Path) -> dict[str, Topic]:
    """The TF topics of a rosbag2 directory or a ``.bag``, with rosbags' AnyReader (types from
    the file's own definitions)."""
    topics: dict[str, Topic] = defaultdict(Topic)
    with AnyReader([path]) as reader:
        conns = [c for c in reader.connections if c.msgtype == TF]
        assert len({c.topic for c in conns}) == len(conns)  # one connection per topic
        for c in conns:
            ext = getattr(c, "ext", None)
            topics[c.topic].latched = bool(getattr(ext, "latching", 0))
        for c, t, raw in reader.messages(connections=conns):
            topics[c.topic].msgs.append(_sent(reader.deserialize(raw, c.msgtype)))
            topics[c.topic].raw.append((t, bytes(raw)))
    return dict(topics)


def read_ros1_mcap(path: Path) -> dict[str, Topic]:
    """The TF topics of a ``ros1``-profile MCAP: mcap's reader, rosbags' ROS 1 deserializer
    with the type registered from the schema's own definition."""
    topics: dict[str, Topic] = defaultdict(Topic)
    store = get_typestore(Stores.EMPTY)
    with path.open("rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros1"
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema is None or schema.name != "tf2_msgs/TFMessage":
                continue
            assert (schema.encoding, channel.message_encoding) == ("ros1msg", "ros1")
            if TF not in store.types:
                store.register(get_types_from_msg(schema.data.decode(), TF))
            topic = topics[channel.topic]
            topic.latched = channel.metadata["latching"] == "true"
            topic.msgs.append(_sent(store.deserialize_ros1(message.data, TF)))
            topic.raw.append((message.log_time, bytes(message.data)))
    return dict(topics)


def unions(published: list[list[Sent]]) -> list[list[Sent]]:
    """What a static TF broadcaster sends after each published message: every transform so
    far, by child frame, the latest one, in the order the child frames were first sent."""
    held: dict[str, Any] = {}
    out = []
    for msg in published:
        for child, tf in msg:
            held[child] = tf
        out.append(list(held.items()))
    return out


def digest(raw: list[tuple[int, bytes]]) -> str:
    """A topic's digest as srr defines it: SHA-256 over each message's (log time, length,
    bytes) as recorded."""
    h = hashlib.sha256()
    for t, data in raw:
        h.update(struct.pack("<qI", t, len(data)) + data)
    return h.hexdigest()


# -- real runs: the static TF of a scene, recorded as ROS 2, ROS 1 MCAP and ROS 1 .bag

CASES = {
    # four static TF publishers on /tf_static: world → odom, the two link trees, the camera
    "turtlebot3_room": ("turtlebot3_room.yaml", ()),
    # two robots, one world → odom publisher each, on the one /tf_static
    "two_robots": ("two_forklifts.yaml", ()),
    # the robot's static tree on a namespaced topic, the camera's on /tf_static
    "namespaced": ("turtlebot3_room.yaml",
                   ("robots.turtlebot3.tf_tree.static_topic=/tb3/tf_static",)),
}
OUTPUTS = {"ros2": ("output.ros=2",), "mcap": ("output.ros=1",),
           "bag": ("output.ros=1", "output.format=bag", "recording.compression=lz4")}
READ = {"ros2": lambda run: read_anyreader(run / "bag"),
        "mcap": lambda run: read_ros1_mcap(run / "bag" / "bag.mcap"),
        "bag": lambda run: read_anyreader(run / "bag" / "bag.bag")}


@pytest.fixture(scope="module", params=list(CASES))
def runs(request: pytest.FixtureRequest, module_tmp: ModuleTmp) -> dict[str, Path]:
    """One scene's run (0.1 s: the static transforms go out on the first tick) in each
    output, by output."""
    scenario, sets = CASES[request.param]
    base = module_tmp(f"static-tf-{request.param}")
    out = {}
    for kind, kind_sets in OUTPUTS.items():
        run = base / kind
        args = ["run", str(SCENARIOS / scenario), "--out", str(run), "-q", "--no-video",
                "--duration", "0.1"]
        code = main([*args, *(a for s in (*sets, *kind_sets) for a in ("--set", s))])
        assert code in (0, 1), (kind, code)  # PASS, or without a baseline UNSCORED / MISMATCH
        out[kind] = run
    return out


@pytest.mark.slow
@pytest.mark.parametrize("fmt", ["mcap", "bag"])
def test_each_static_tf_message_holds_every_transform_so_far(runs: dict[str, Path],
                                                             fmt: str) -> None:
    ros2 = READ["ros2"](runs["ros2"])
    ros1 = READ[fmt](runs[fmt])
    static = sorted(t for t in ros2 if t.rsplit("/", 1)[-1] == "tf_static")
    assert static and sorted(t for t in ros1 if t.endswith("tf_static")) == static
    assert sum(len(ros2[t].msgs) for t in static) >= 2  # something to accumulate
    for topic in static:
        published, written = ros2[topic].msgs, ros1[topic].msgs
        assert ros1[topic].latched
        # message by message: the union of what was published up to it, latest per child
        assert written == unions(published), topic
        # the last message, the one rosbag play latches, holds the whole static tree
        assert {c for c, _ in written[-1]} == {c for msg in published for c, _ in msg}
        for before, after in pairwise(written):  # each message extends the one before
            assert [c for c, _ in after[:len(before)]] == [c for c, _ in before]
    recorded = _summary_topics(runs[fmt])
    for topic in static:  # the topic's digest is over the bytes written, as for any topic
        assert recorded[topic]["sha256"] == digest(ros1[topic].raw), topic
        assert recorded[topic]["count"] == len(ros2[topic].msgs)
    # dynamic TF is written as published
    for topic in set(ros2) - set(static):
        assert ros1[topic].msgs == ros2[topic].msgs and not ros1[topic].latched, topic
    # srr reads the ROS 1 recording into the same TF tables as the ROS 2 one: what scoring,
    # the tf_tree gate and reference recordings see does not depend on the format
    a, b = load_frames(runs["ros2"]), load_frames(runs[fmt])
    for name in ("tf", "tf_static", "odom"):
        pd.testing.assert_frame_equal(getattr(b, name), getattr(a, name), obj=name)


def _summary_topics(run: Path) -> dict[str, Any]:
    return dict(json.loads((run / "summary.json").read_text(encoding="utf-8"))["topics"])


@pytest.mark.slow
@pytest.mark.parametrize("runs", ["turtlebot3_room"], indirect=True)
@pytest.mark.parametrize("fmt", ["mcap", "bag"])
def test_a_replay_records_the_same_static_tf(runs: dict[str, Path], fmt: str,
                                             tmp_path: Path) -> None:
    """``srr replay`` of a ROS 1 run plays its accumulated messages to the systems under test
    and records them as they are: the same per-topic digests, the whole tree last."""
    replayed = api.replay(runs[fmt], out=tmp_path / "replay").summary
    original = _summary_topics(runs[fmt])
    assert {t: v["sha256"] for t, v in replayed["topics"].items()} == \
        {t: v["sha256"] for t, v in original.items()}
    again = READ[fmt](tmp_path / "replay")["/tf_static"].msgs
    ros2 = READ["ros2"](runs["ros2"])["/tf_static"].msgs
    assert again == unions(ros2) and len(again) == 4


# -- the recorder alone: what accumulates, and how


def _tf(ns: int, parent: str, child: str, x: float) -> Any:
    return m.transform_stamped(ns, parent, child, [x, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])


def test_the_union_by_child_frame_latest_wins_on_latched_tf_static_only(tmp_path: Path
                                                                       ) -> None:
    """A new transform for a child frame replaces the one before in its place; other latched
    TF topics (``staticPublisher`` on /tf), a volatile ``tf_static`` and /tf are written as
    published; a message that comes as ROS 1 bytes (a replayed recording) is written as it is
    and joins the union. srr reads the transforms back where each was sent."""
    qos = {"/tf_static": TRANSIENT_LOCAL, "/r/tf_static": TRANSIENT_LOCAL,
           "/tf": TRANSIENT_LOCAL, "/v/tf_static": Qos()}
    rec = Ros1Recorder(tmp_path / "bag", "bag")
    rec.open(lambda topic: qos[topic])
    published = [
        ("/tf_static", [_tf(0, "world", "odom", 1.0)]),
        ("/tf_static", [_tf(0, "base_link", "cam", 2.0), _tf(0, "base_link", "imu", 3.0)]),
        ("/r/tf_static", [_tf(0, "world", "r/odom", 4.0)]),
        ("/tf", [_tf(0, "odom", "base_link", 5.0)]),
        ("/tf", [_tf(0, "map", "odom", 6.0)]),
        ("/v/tf_static", [_tf(0, "a", "b", 7.0)]),
        ("/v/tf_static", [_tf(0, "a", "c", 8.0)]),
        ("/tf_static", [_tf(1_000_000_000, "world", "odom", 9.0)]),  # moved: replaces
    ]
    for i, (topic, transforms) in enumerate(published):
        rec.write(Envelope(topic, TF, 0 if i < 7 else 1_000_000_000, i,
                           m.tf_message(transforms)))
    # a replayed ROS 1 message: its bytes as recorded, holding its own union
    raw = Ros1Encoder().encode("/r/tf_static", TF, m.tf_message(
        [_tf(0, "world", "r/odom", 4.0), _tf(0, "r/base", "r/lidar", 10.0)]))
    rec.write(Envelope("/r/tf_static", TF, 1_000_000_000, 8, None, raw, encoding="ros1"))
    rec.write(Envelope("/r/tf_static", TF, 1_000_000_000, 9,
                       m.tf_message([_tf(0, "r/base", "r/imu", 11.0)])))
    rec.close()

    got = read_anyreader(tmp_path / "bag" / "bag.bag")
    x = {t: [[(c, tf[2][0]) for c, tf in msg] for msg in v.msgs] for t, v in got.items()}
    assert x["/tf_static"] == [[("odom", 1.0)], [("odom", 1.0), ("cam", 2.0), ("imu", 3.0)],
                               [("odom", 9.0), ("cam", 2.0), ("imu", 3.0)]]
    assert x["/r/tf_static"] == [[("r/odom", 4.0)], [("r/odom", 4.0), ("r/lidar", 10.0)],
                                 [("r/odom", 4.0), ("r/lidar", 10.0), ("r/imu", 11.0)]]
    assert x["/tf"] == [[("base_link", 5.0)], [("odom", 6.0)]]
    assert x["/v/tf_static"] == [[("b", 7.0)], [("c", 8.0)]]
    with Rosbag1Reader(tmp_path / "bag" / "bag.bag") as reader:
        assert {c.topic for c in reader.connections if c.ext.latching} == \
            {"/tf_static", "/r/tf_static", "/tf"}

    tf = load_frames(tmp_path / "bag" / "bag.bag").tf
    rows = {t: list(zip(g["child"].astype(str), g["x"], strict=True))
            for t, g in tf.groupby("topic", observed=True)}
    assert rows == {"/tf_static": [("odom", 1.0), ("cam", 2.0), ("imu", 3.0), ("odom", 9.0)],
                    "/r/tf_static": [("r/odom", 4.0), ("r/lidar", 10.0), ("r/imu", 11.0)],
                    "/tf": [("base_link", 5.0), ("odom", 6.0)],
                    "/v/tf_static": [("b", 7.0), ("c", 8.0)]}
