"""ROS 1 output: the ROS 2 → ROS 1 conversion, the ROS 1 recorder (``.bag`` and MCAP), frames
read back from either exactly as from ROS 2, and the checks that decide and refuse an output
kind before a run.

Independent checks: ROS 1's own MD5 sums of the definitions, and genpy (vendored by
mcap-ros1-support) reading and re-serializing the bytes rosbags wrote.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from mcap_ros1._vendor.genpy import dynamic
from rosbags.rosbag1 import Reader as Rosbag1Reader
from rosbags.rosbag2 import Reader as Rosbag2Reader

from harness.bus import TRANSIENT_LOCAL, Envelope, Qos
from harness.cli import main
from harness.frames import (
    CLOCK,
    MARKER_ARRAY,
    ODOMETRY,
    TF_MESSAGE,
    TWIST,
    decode_batch,
    load_frames,
)
from harness.recording.ros1bag import Ros1Recorder
from harness.serde import messages as m
from harness.serde.messages import TYPESTORE
from harness.serde.ros1 import (
    Ros1Encoder,
    Ros1TypeError,
    deserialize_ros1,
    dropped_fields,
    msgdef,
    ros1_name,
    to_ros2,
)
from tests.conftest import ModuleTmp
from tests.metrics.synthbag import SynthSpec, write_synthetic_bag
from tests.metrics.test_frames import BOOL, random_messages

# ROS 1's own MD5 sums (rosmsg md5 on a Noetic install)
MD5 = {
    "tf2_msgs/msg/TFMessage": "94810edda583a504dfda3829e70d7eec",
    "rosgraph_msgs/msg/Clock": "a9c97c1d230cfc112e270351a944ee47",
    "nav_msgs/msg/Odometry": "cd5e73d190d741a2f92e81eda573aca7",
    "sensor_msgs/msg/Image": "060021388200f6f0f447d0fcd9c64743",
    "sensor_msgs/msg/CameraInfo": "c9a58c1b0b154e0e6da7578cb991d214",
    "sensor_msgs/msg/LaserScan": "90c7ef2dc6895d81024acba2ac42f369",
    "geometry_msgs/msg/Twist": "9f195f881246fdfa2798d1d3eebca84a",
    "std_msgs/msg/Bool": "8b94c1b53db61fb6aed406028ad6332a",
}


def test_definitions_have_ros1s_md5_sums() -> None:
    assert {t: msgdef(t)[1] for t in MD5} == MD5
    assert ros1_name("tf2_msgs/msg/TFMessage") == "tf2_msgs/TFMessage"
    assert ros1_name("sensor_msgs/msg/Image") == "sensor_msgs/Image"


def _samples() -> dict[str, Any]:
    rng = np.random.default_rng(3)
    img = m.make("sensor_msgs/msg/Image", header=m.header(7, "camera"), height=2, width=3,
                 encoding="rgb8", step=9, data=rng.integers(0, 255, 18).astype(np.uint8))
    info = m.make("sensor_msgs/msg/CameraInfo", header=m.header(7, "camera"), width=3,
                  height=2, distortion_model="plumb_bob", d=np.arange(5.0), k=np.arange(9.0),
                  r=np.eye(3).ravel(), p=np.arange(12.0))
    scan = m.make("sensor_msgs/msg/LaserScan", header=m.header(9, "laser"), angle_max=1.0,
                  ranges=np.array([1.0, np.inf, 2.5], dtype=np.float32),
                  intensities=np.zeros(3, dtype=np.float32))
    out = {"sensor_msgs/msg/Image": img, "sensor_msgs/msg/CameraInfo": info,
           "sensor_msgs/msg/LaserScan": scan}
    for t in (CLOCK, BOOL, TWIST, ODOMETRY, TF_MESSAGE):
        out[t] = random_messages(t, rng, 3)[2]
    return out


@pytest.mark.parametrize("msgtype", sorted(_samples()))
def test_ros1_round_trip_is_lossless(msgtype: str) -> None:
    """ROS 2 → ROS 1 bytes → ROS 2 gives the same CDR bytes (types ROS 1 carries whole)."""
    msg = _samples()[msgtype]
    raw = Ros1Encoder().encode("/t", msgtype, msg)
    back = to_ros2(deserialize_ros1(raw, msgtype), msgtype)
    assert bytes(TYPESTORE.serialize_cdr(back, msgtype)) == \
        bytes(TYPESTORE.serialize_cdr(msg, msgtype))


@pytest.mark.parametrize("msgtype", sorted(_samples()))
def test_genpy_reads_and_writes_the_same_bytes(msgtype: str) -> None:
    """genpy, from the definition text alone, parses the bytes and serializes them again
    identically; its MD5 sum of the text is the definition's."""
    text, md5 = msgdef(msgtype)
    name = ros1_name(msgtype)
    cls = dynamic.generate_dynamic(name, text)[name]
    raw = Ros1Encoder().encode("/t", msgtype, _samples()[msgtype])
    parsed = cls()
    parsed.deserialize(raw)
    buf = BytesIO()
    parsed.serialize(buf)
    assert buf.getvalue() == raw and cls._md5sum == md5


def test_header_seq_counts_per_topic_and_nested_headers_keep_zero() -> None:
    enc = Ros1Encoder()
    odom = _samples()[ODOMETRY]
    tf = m.tf_message([m.transform_stamped(5, "a", "b", [0, 0, 0], [0, 0, 0, 1])] * 2)
    seqs = [deserialize_ros1(enc.encode(topic, ODOMETRY, odom), ODOMETRY).header.seq
            for topic in ("/odom", "/odom", "/other", "/odom")]
    assert seqs == [0, 1, 0, 2]
    for _ in range(3):
        raw = enc.encode("/tf", TF_MESSAGE, tf)
    assert [t.header.seq for t in deserialize_ros1(raw, TF_MESSAGE).transforms] == [0, 0]


def test_types_ros1_lacks() -> None:
    with pytest.raises(Ros1TypeError, match="VelocityStamped has no ROS 1 counterpart"):
        Ros1Encoder().encode("/v", "geometry_msgs/msg/VelocityStamped",
                             m.make("geometry_msgs/msg/VelocityStamped"))
    assert dropped_fields(MARKER_ARRAY) == tuple(
        f"visualization_msgs/msg/Marker.{f}"
        for f in ("mesh_file", "texture", "texture_resource", "uv_coordinates"))
    assert dropped_fields(ODOMETRY) == ()


@pytest.mark.parametrize("msgtype", [CLOCK, BOOL, TWIST, ODOMETRY, TF_MESSAGE, MARKER_ARRAY])
def test_frames_decode_ros1_as_cdr(msgtype: str) -> None:
    """The vectorized ROS 1 path, the one-by-one ROS 1 path and the CDR path give the same
    columns for the same messages (ROS 1's Marker lacks the fields the tables skip)."""
    msgs = random_messages(msgtype, np.random.default_rng(11), 60)
    enc = Ros1Encoder()
    ros1 = [enc.encode("/t", msgtype, x) for x in msgs]
    cdr = [bytes(TYPESTORE.serialize_cdr(x, msgtype)) for x in msgs]
    fast = decode_batch(ros1, msgtype, encoding="ros1")
    slow = decode_batch(ros1, msgtype, fast=False, encoding="ros1")
    ref = decode_batch(cdr, msgtype, fast=False)
    for k in ref.keys() - {"fast"}:
        assert fast[k].tolist() == slow[k].tolist() == ref[k].tolist(), k
    assert fast["fast"].mean() > (0.5 if msgtype == MARKER_ARRAY else 0.8)


def _as_ros1(ros2_bag: Path, bag_dir: Path, fmt: str, max_span_ns: int) -> dict[str, Any]:
    """Record a rosbag2 bag's messages again through the ROS 1 recorder."""
    from harness.recording.bagfile import ChunkPolicy

    rec = Ros1Recorder(bag_dir, "bag" if fmt == "bag" else "mcap",
                       chunks=ChunkPolicy(max_span_ns=max_span_ns))
    rec.open(lambda topic: TRANSIENT_LOCAL if topic == "/tf_static" else Qos())
    with Rosbag2Reader(ros2_bag) as reader:
        for i, (conn, t, raw) in enumerate(reader.messages()):
            rec.write(Envelope(conn.topic, conn.msgtype, t, i,
                               TYPESTORE.deserialize_cdr(raw, conn.msgtype)))
    return rec.close()


@pytest.fixture(scope="module")
def synth(module_tmp: ModuleTmp) -> Path:
    path = module_tmp("synth") / "bag"
    write_synthetic_bag(path, SynthSpec(duration_s=3.0, frame_prefix="forklift/"))
    return path


@pytest.mark.parametrize("fmt", ["bag", "mcap"])
def test_ros1_recording_reads_back_as_the_same_frames(synth: Path, tmp_path: Path,
                                                      fmt: str) -> None:
    """Scoring's tables from the ROS 1 recording (``.bag`` or ``ros1`` MCAP, in a run's
    ``bag/`` directory or given as the file) equal those from the ROS 2 original."""
    stats = _as_ros1(synth, tmp_path / "bag", fmt, max_span_ns=1_000_000_000)
    assert stats["/odom"].msgtype == "nav_msgs/Odometry" and stats["/clock"].count == 180
    ref = load_frames(synth)
    for got in (load_frames(tmp_path), load_frames(tmp_path / "bag" / f"bag.{fmt}")):
        for name in ("clock", "gt_poses", "odom", "cmd_vel", "tracks", "track_frames",
                     "muted", "topics", "tf_static", "tf"):
            pd.testing.assert_frame_equal(getattr(got, name), getattr(ref, name), obj=name)
        assert (got.start_ns, got.end_ns, got.message_count) == \
            (ref.start_ns, ref.end_ns, ref.message_count)
    if fmt == "bag":  # chunks close at chunk_s of simulated time, as in ROS 2 bags
        with Rosbag1Reader(tmp_path / "bag" / "bag.bag") as reader:
            assert len(reader.chunk_infos) >= 3
            latched = {c.topic for c in reader.connections if c.ext.latching}
            assert latched == {"/tf_static"}


# -- deciding the output kind, and refusing what cannot be recorded as ROS 1 ----------------

CLOCKS = """format_version: 1
name: ros1_clock
duration: 0.1
clock: {enabled: false}
graphs:
  - {name: Ros1Clock, builder: "tests.recording.ros1_plugins:ros1_clock"}
  - {name: Ros2Clock, builder: "tests.recording.ros1_plugins:ros2_clock", enabled: false}
"""


@dataclass(frozen=True)
class Done:
    returncode: int
    stdout: str
    stderr: str


@pytest.fixture
def srr(capsys: pytest.CaptureFixture[str]) -> Callable[..., Done]:
    """The CLI, in process."""
    def run(*args: str) -> Done:
        code = main(list(args))
        out, err = capsys.readouterr()
        return Done(code, out, err)
    return run


@pytest.fixture
def clocks(tmp_path: Path) -> Path:
    path = tmp_path / "clocks.yaml"
    path.write_text(CLOCKS, encoding="utf-8")
    return path


@pytest.mark.parametrize(("sets", "expected"), [
    (["graphs.Ros2Clock.enabled=true"],  # the whole graph: said of the file; the rest, --set
     "FILE: graphs[1]: mixes ROS 1 and ROS 2 bridge nodes (/World/Ros1ClockGraph/PublishClock is "
     "omni.isaac.ros_bridge.ROS1PublishClock, /World/Ros2ClockGraph/PublishClock is "
     "isaacsim.ros2.bridge.ROS2PublishClock)"),
    (["systems_under_test=[{name: v, plugin: 'tests.recording.ros1_plugins:Velocity'}]"],
     "--set: systems_under_test[0]: systems_under_test[0] (v) publishes /velocity as "
     "geometry_msgs/msg/VelocityStamped, which has no ROS 1 counterpart"),
    (["output.ros=true"], "--set: output.ros: expected one of 1, 2, got True"),
    (["output.ros=2", "output.format=bag"], "--set: output.format: bag is a ROS 1 bag"),
    (["output.format=bag", "recording.compression=zstd"], "--set: recording.compression: a ROS 1 "
     "bag compresses its chunks with lz4"),
    (["output.ros=1", "ros2.enabled=true"], "--set: ros2.enabled: the live ROS 2 bridge needs "
     "ROS 2 output"),
])
@pytest.mark.parametrize("command", ["validate", "run"])
def test_bad_output_is_one_line_exit_2(srr: Callable[..., Done], clocks: Path, tmp_path: Path,
                                       command: str, sets: list[str], expected: str) -> None:
    extra = ["--out", str(tmp_path / "out")] if command == "run" else []
    done = srr(command, str(clocks), *(a for s in sets for a in ("--set", s)), *extra)
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert f"srr {command}: {expected.replace('FILE', str(clocks))}" in done.stderr
    assert not (tmp_path / "out").exists()


def test_inferred_ros1_refuses_the_live_views(srr: Callable[..., Done], clocks: Path,
                                              tmp_path: Path) -> None:
    """The live ROS 2 bridge and the Foxglove view speak ROS 2: refused, with the reason."""
    from harness.engine import Simulation
    from harness.errors import ScenarioError
    from harness.output import decide_output
    from harness.scenario import load_scenario

    sc = load_scenario(clocks, [("ros2.enabled", True)])
    sim = Simulation(sc, source=str(clocks))  # without the bridge plug-in: only the decision
    try:
        with pytest.raises(ScenarioError, match=r"ros2\.enabled: the live ROS 2 bridge needs "
                           r"ROS 2 output, and this run records ROS 1 \(graphs\[0\] builds"):
            decide_output(sc, sim.stage, sim.custom_graphs, str(clocks))
    finally:
        sim.close()
    done = srr("run", str(clocks), "--foxglove", "--out", str(tmp_path / "out"))
    assert done.returncode == 2 and "--foxglove: the live view serves ROS 2 messages, and " \
        "this run records ROS 1" in done.stderr and not (tmp_path / "out").exists()


@pytest.mark.parametrize(("sets", "ros", "file"), [
    ([], 1, "bag.mcap"), (["output.format=bag", "recording.compression=lz4"], 1, "bag.bag"),
    (["output.ros=2"], 2, None),
    (["graphs.Ros1Clock.enabled=false", "graphs.Ros2Clock.enabled=true"], 2, None),
])
@pytest.mark.slow
def test_output_kind_and_inspect(srr: Callable[..., Done], clocks: Path, tmp_path: Path,
                                 sets: list[str], ros: int, file: str | None) -> None:
    """ROS 1 node names record ROS 1 unless output says otherwise; ``srr inspect`` lists
    either."""
    out = tmp_path / "run"
    done = srr("run", str(clocks), "-q", "--out", str(out),
               *(a for s in sets for a in ("--set", s)))
    assert done.returncode == 1, done.stderr  # UNSCORED
    names = sorted(p.name for p in (out / "bag").iterdir())
    assert names == ([file] if file else ["bag.mcap", "metadata.yaml"])
    shown = srr("inspect", str(out))
    assert shown.returncode == 0, shown.stderr
    clock_type = "rosgraph_msgs/Clock" if ros == 1 else "rosgraph_msgs/msg/Clock"
    assert clock_type in shown.stdout and "6" in shown.stdout
    if not sets:  # a replay records what the recording is
        done = srr("replay", str(out), "--set", "output.ros=2", "--out", str(tmp_path / "r"))
        assert done.returncode == 2 and "--set: output: a replay records what the " \
            "recording is" in done.stderr and not (tmp_path / "r").exists()
        done = srr("replay", str(out), "--foxglove", "--out", str(tmp_path / "r"))
        assert done.returncode == 2 and "--foxglove: the live view serves ROS 2 messages, " \
            "and the recording" in done.stderr and not (tmp_path / "r").exists()


def test_a_foreign_bag_with_tf_tfmessage(tmp_path: Path) -> None:
    """A ROS 1 bag written elsewhere, with the older ``tf/tfMessage`` on /tf, reads into the
    same TF table (the type is read as tf2_msgs/msg/TFMessage)."""
    from rosbags.rosbag1 import Writer

    from harness.serde.ros1 import ros1_typestore

    tf = m.tf_message([m.transform_stamped(2_000_000_000, "odom", "base_link", [1, 2, 0],
                                           [0, 0, 0, 1])])
    raw = Ros1Encoder().encode("/tf", TF_MESSAGE, tf)
    with Writer(tmp_path / "x.bag") as bag:
        conn = bag.add_connection("/tf", "tf/msg/tfMessage", typestore=ros1_typestore())
        for k in range(3):
            bag.write(conn, k * 1_000_000_000, raw)
    frames = load_frames(tmp_path / "x.bag")
    assert frames.topics[["name", "type", "count"]].values.tolist() == [
        ["/tf", TF_MESSAGE, 3]]
    assert frames.tf[["parent", "child", "x", "y"]].values.tolist() == \
        [["odom", "base_link", 1.0, 2.0]] * 3
    assert (frames.tf["t_ns"] == 2_000_000_000).all()


def test_fields_ros1_drops_are_warned(srr: Callable[..., Done], clocks: Path) -> None:
    done = srr("validate", str(clocks), "--set",
               "systems_under_test=[{name: t, plugin: 'tests.e2e.replay_plugins:BlindTracker'}]")
    assert done.returncode == 0, done.stderr
    assert ("srr validate: warning: ROS 1 output: visualization_msgs/msg/MarkerArray "
            "(/perception/tracks) is recorded without mesh_file, texture, texture_resource, "
            "uv_coordinates (ROS 1 has no such fields)") in done.stderr
