"""Reading bags into frames: both decoding paths agree, tables hold the known values."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer

from harness.frames import (
    CLOCK,
    MARKER_ARRAY,
    ODOMETRY,
    TF_MESSAGE,
    TWIST,
    decode_batch,
    load_frames,
)
from harness.recording.errors import BagError
from harness.serde.messages import (
    TYPESTORE,
    clock,
    header,
    msg_type,
    odometry,
    tf_message,
    transform_stamped,
    twist,
)
from tests.conftest import SCENARIOS, ModuleTmp
from tests.metrics.synthbag import ODOM_ORIGIN, SynthSpec, forklift_xy, write_synthetic_bag

BOOL = "std_msgs/msg/Bool"


def marker(rng: np.random.Generator, k: int) -> Any:
    """A marker with every variable-length field filled at random."""
    def s(n: int) -> str:
        return "".join(rng.choice(list("abcdefghij_/"), n))

    def arr(n: int) -> np.ndarray:
        return rng.integers(0, 255, n).astype(np.uint8)

    point = msg_type("geometry_msgs/msg/Point")
    color = msg_type("std_msgs/msg/ColorRGBA")
    return msg_type("visualization_msgs/msg/Marker")(
        header=header(int(rng.integers(0, 10**12)), s(int(rng.integers(0, 9)))),
        ns=s(int(rng.integers(0, 12))), id=int(rng.integers(-5, 1000)), type=2,
        action=int(rng.choice([0, 0, 0, 2, 3])),
        pose=msg_type("geometry_msgs/msg/Pose")(
            position=point(x=float(rng.normal()), y=float(rng.normal()), z=float(k)),
            orientation=msg_type("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0)),
        scale=msg_type("geometry_msgs/msg/Vector3")(x=1.0, y=1.0, z=1.0),
        color=color(r=0.1, g=0.2, b=0.3, a=1.0),
        lifetime=msg_type("builtin_interfaces/msg/Duration")(sec=1, nanosec=2),
        frame_locked=bool(rng.integers(2)),
        points=[point(x=1.0, y=2.0, z=3.0)] * int(rng.integers(0, 3)),
        colors=[color(r=1.0, g=0.0, b=0.0, a=1.0)] * int(rng.integers(0, 3)),
        texture_resource=s(int(rng.integers(0, 4))),
        texture=msg_type("sensor_msgs/msg/CompressedImage")(
            header=header(0, s(int(rng.integers(0, 3)))), format=s(int(rng.integers(0, 3))),
            data=arr(int(rng.integers(0, 7)))),
        uv_coordinates=[msg_type("visualization_msgs/msg/UVCoordinate")(u=0.5, v=0.5)]
        * int(rng.integers(0, 3)),
        text=s(int(rng.integers(0, 5))), mesh_resource=s(int(rng.integers(0, 3))),
        mesh_file=msg_type("visualization_msgs/msg/MeshFile")(
            filename=s(int(rng.integers(0, 3))), data=arr(int(rng.integers(0, 5)))),
        mesh_use_embedded_materials=bool(rng.integers(2)))


def random_messages(msgtype: str, rng: np.random.Generator, n: int) -> list[Any]:
    out = []
    for i in range(n):
        stamp = int(rng.integers(0, 10**12))
        # a few layouts repeat (fast path), some are unique (new templates)
        frame = ["odom", "odom", "forklift/odom", "a" * int(rng.integers(1, 9))][i % 4]
        q = (0.0, 0.0, float(np.sin(i)), float(np.cos(i)))
        if msgtype == CLOCK:
            out.append(clock(stamp))
        elif msgtype == BOOL:
            out.append(msg_type(BOOL)(data=bool(i % 3)))
        elif msgtype == TWIST:
            out.append(twist(rng.normal(size=3), rng.normal(size=3)))
        elif msgtype == ODOMETRY:
            out.append(odometry(stamp, frame, "base_link", rng.normal(size=3), q,
                                rng.normal(size=3), rng.normal(size=3)))
        elif msgtype == TF_MESSAGE:
            out.append(tf_message([transform_stamped(stamp, "world", f"{frame}{j}",
                                                     rng.normal(size=3), q)
                                   for j in range(i % 3)]))
        else:
            out.append(msg_type(MARKER_ARRAY)(
                markers=[marker(rng, k) for k in range(int(rng.integers(0, 4)))]))
    return out


@pytest.mark.parametrize("msgtype", [CLOCK, BOOL, TWIST, ODOMETRY, TF_MESSAGE, MARKER_ARRAY])
def test_fast_decoding_equals_rosbags(msgtype: str) -> None:
    rng = np.random.default_rng(7)
    msgs = random_messages(msgtype, rng, 60)
    raws = [bytes(TYPESTORE.serialize_cdr(m, msgtype)) for m in msgs]
    raws[5] = bytes(TYPESTORE.serialize_cdr(msgs[5], msgtype, little_endian=False))
    fast = decode_batch(raws, msgtype)
    slow = decode_batch(raws, msgtype, fast=False)
    assert fast.keys() == slow.keys()
    for k in fast.keys() - {"fast"}:
        assert fast[k].tolist() == slow[k].tolist(), k
    assert fast["msg"].size > 0 and not slow["fast"].any()
    # the big-endian message is decoded by rosbags, the repeated layouts by the fast path
    assert not fast["fast"][fast["msg"] == 5].any()
    assert fast["fast"].mean() > (0.5 if msgtype == MARKER_ARRAY else 0.8)


def test_decoding_reads_the_known_values() -> None:
    msgs = [odometry(1_500_000_000, "odom", "base_link", (1.0, 2.0, 3.0),
                     (0.0, 0.0, math.sin(0.25), math.cos(0.25)), (0.5, 0.0, 0.0),
                     (0.0, 0.0, -0.1))]
    cols = decode_batch([bytes(TYPESTORE.serialize_cdr(m, ODOMETRY)) for m in msgs], ODOMETRY)
    assert (cols["sec"][0], cols["nanosec"][0]) == (1, 500_000_000)
    assert cols["frame_id"][0] == "odom" and cols["child_frame_id"][0] == "base_link"
    assert (cols["x"][0], cols["y"][0], cols["vx"][0], cols["wz"][0]) == (1.0, 2.0, 0.5, -0.1)


def test_column_types_do_not_depend_on_the_path() -> None:
    rng = np.random.default_rng(1)
    full = msg_type(MARKER_ARRAY)(markers=[marker(rng, 0)])
    empty = msg_type(MARKER_ARRAY)(markers=[])
    raws = [bytes(TYPESTORE.serialize_cdr(full, MARKER_ARRAY)),
            bytes(TYPESTORE.serialize_cdr(empty, MARKER_ARRAY, little_endian=False))]
    cols = decode_batch(raws, MARKER_ARRAY)
    assert cols["fast"].tolist() == [True]  # the empty big-endian array gives no row
    assert cols["id"].dtype == np.int64 and cols["sec"].dtype == np.int64
    assert cols["x"].dtype == np.float64 and cols["ns"].dtype == object


def test_corrupt_message_is_a_bag_error() -> None:
    good = bytes(TYPESTORE.serialize_cdr(clock(5), CLOCK))
    with pytest.raises(BagError, match="rosgraph_msgs/msg/Clock"):
        decode_batch([good, good[:6]], CLOCK)


@pytest.fixture(scope="module")
def synth(module_tmp: ModuleTmp) -> tuple[Path, int]:
    path = module_tmp("synth") / "bag"
    n = write_synthetic_bag(path, SynthSpec(duration_s=3.0, frame_prefix="forklift/"))
    return path, n


def test_synthetic_bag_both_paths_identical(synth: tuple[Path, int]) -> None:
    fast, slow = load_frames(synth[0]), load_frames(synth[0], fast=False)
    for name in ("clock", "gt_poses", "odom", "cmd_vel", "tracks", "track_frames", "muted",
                 "topics", "tf_static"):
        pd.testing.assert_frame_equal(getattr(fast, name), getattr(slow, name), obj=name)


def test_synthetic_bag_tables(synth: tuple[Path, int]) -> None:
    f = load_frames(synth[0])
    assert f.message_count == synth[1] and f.topics["count"].sum() == synth[1]
    assert len(f.clock) == 180 and (np.diff(f.clock["t_ns"]) > 0).all()
    assert f.gt_names == ("character_0", "character_1", "character_2", "character_3",
                          "forklift")
    # odometry, published in "forklift/odom", lands on the ground truth in the world frame
    assert set(f.odom["frame"]) == {"world"} and set(f.odom["topic"]) == {"/odom"}
    fork = f.gt("forklift")
    assert np.allclose(f.odom["x"], fork["x"]) and np.allclose(f.odom["y"], fork["y"])
    t = f.odom["t_ns"].to_numpy() / 1e9
    assert np.allclose(f.odom["x"], [forklift_xy(s)[0] for s in t])
    assert f.tf_static.iloc[0]["child"] == "forklift/odom"
    assert f.tf_static.iloc[0]["x"] == ODOM_ORIGIN[0]
    # 30 Hz tracker: a DELETEALL plus the persons of each frame; DELETEALL is not a track
    assert len(f.track_frames) == 90
    assert set(f.tracks["cls"]) == {"person"} and f.tracks["frame"].max() < 90
    assert len(f.cmd_vel) == 60 and (f.cmd_vel["vx"] == 1.5).all()
    assert len(f.muted) == 60 and f.muted["value"].dtype == bool


def test_the_tf_table_holds_its_columns_once_while_it_is_built() -> None:
    """The transform tree is the largest table a run's scoring reads (every body, every tick):
    it grows with the run's length, so building it must not hold the whole table twice (the
    decoded batches are released column by column as the table takes them)."""
    import tracemalloc

    from harness.frames import _POSE, _tf_frame

    def part(n: int) -> dict[str, Any]:
        rng = np.random.default_rng(n)
        return {"t_ns": np.arange(n, dtype=np.int64), "log_ns": np.arange(n, dtype=np.int64),
                "parent": pd.Categorical(np.full(n, "world", dtype=object)),
                "child": pd.Categorical(np.array(["a", "b"] * (n // 2), dtype=object)),
                **{k: rng.random(n) for k in _POSE}}

    topics = [("/tf", [part(50_000), part(50_000)]), ("/tf_static", [part(2)])]
    tracemalloc.start()
    try:
        table = _tf_frame(topics)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    size = table.memory_usage(deep=True).sum()
    assert len(table) == 100_002 and size > 7 * 100_002 * 8
    assert peak < 1.25 * size, (peak, size)


def write_bag(path: Path, msgs: list[tuple[str, str, int, Any]]) -> None:
    w = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    w.open()
    conns: dict[str, Any] = {}
    for topic, msgtype, t, msg in msgs:
        if topic not in conns:
            conns[topic] = w.add_connection(topic, msgtype, typestore=TYPESTORE)
        w.write(conns[topic], t, bytes(TYPESTORE.serialize_cdr(msg, msgtype)))
    w.close()


def test_empty_tracker_frames_multi_transform_gt_and_marker_topics(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    ma = msg_type(MARKER_ARRAY)
    m1 = marker(rng, 0)
    m2 = marker(rng, 1)
    deleteall = marker(rng, 2)
    for m, ns, action, tid in ((m1, "person", 0, 4), (m2, "forklift", 0, 9),
                               (deleteall, "", 3, 0)):
        m.ns, m.action, m.id = ns, action, tid
    m1.header = header(0, "world")  # zero stamp: the frame takes the log time
    tf = TF_MESSAGE
    write_bag(tmp_path / "bag", [
        ("/tracks", MARKER_ARRAY, 100, ma(markers=[deleteall, m1, m2])),
        ("/tracks", MARKER_ARRAY, 200, ma(markers=[deleteall])),
        ("/tracks", MARKER_ARRAY, 300, ma(markers=[])),
        ("/debug_markers", MARKER_ARRAY, 300, ma(markers=[m2])),
        ("/gt/forklift/tf", tf, 100, tf_message([
            transform_stamped(100, "world", "forklift/fork", (9.0, 9.0, 0.0), (0, 0, 0, 1)),
            transform_stamped(100, "world", "forklift", (1.0, 2.0, 0.0),
                              (0.0, 0.0, 1.0, 0.0))])),
        ("/gt/character_0/tf", tf, 100, tf_message([
            transform_stamped(100, "world", "someone", (3.0, 4.0, 0.0), (0, 0, 0, 1))])),
    ])
    f = load_frames(tmp_path / "bag", marker_topics=["/tracks"])
    assert f.track_frames["t_ns"].tolist() == [100, 200, 300]
    assert f.tracks[["frame", "cls", "track_id"]].values.tolist() == [[0, "person", 4],
                                                                       [0, "forklift", 9]]
    assert f.tracks["t_ns"].tolist() == [100, 100]
    fork = f.gt("forklift").iloc[0]
    assert (fork["x"], fork["y"]) == (1.0, 2.0) and fork["yaw"] == pytest.approx(math.pi)
    assert f.gt("character_0").iloc[0]["x"] == 3.0  # no child named so: the first transform
    every = load_frames(tmp_path / "bag")
    assert sorted(set(every.track_frames["topic"])) == ["/debug_markers", "/tracks"]


def test_bad_bags_raise_bag_error(tmp_path: Path, synth: tuple[Path, int]) -> None:
    with pytest.raises(BagError, match="not a rosbag2 directory"):
        load_frames(tmp_path / "nowhere")
    broken = tmp_path / "broken"
    broken.mkdir()
    for p in synth[0].iterdir():
        data = p.read_bytes()
        (broken / p.name).write_bytes(data[: len(data) // 2] if p.suffix == ".mcap" else data)
    with pytest.raises(BagError):
        load_frames(broken)


@pytest.mark.slow
def test_frames_of_a_recorded_forklift_run(tmp_path: Path) -> None:
    from harness import api  # builds the MuJoCo world: imported only by this test

    sc = api.load(SCENARIOS / "forklift_warehouse.yaml", duration=3.0)
    run = api.run_scenario(sc, out=tmp_path / "run")
    f = load_frames(run.run_dir)
    counts = {t: v["count"] for t, v in run.summary["topics"].items()}
    assert dict(zip(f.topics["name"], f.topics["count"], strict=True)) == counts
    assert len(f.odom) == counts["/odom"] == 180 and len(f.clock) == 180
    first = f.odom.iloc[0]
    assert first["frame"] == "world"
    assert (first["x"], first["y"]) == pytest.approx((-12.0, -3.0), abs=1e-9)  # the spawn
    assert f.odom["x"].iloc[-1] > -12.0 + 0.5  # drove forward (+X) in the world
    assert abs(first["yaw"]) < 1e-9  # forward heading along +X
    assert len(f.cmd_vel) == counts["/cmd_vel"] and (f.cmd_vel["vx"] > 0).any()
    assert (np.diff(f.clock["t_ns"]) > 0).all() and f.clock["t_ns"].iloc[0] == 0


@pytest.mark.slow
def test_every_metric_on_a_synthetic_bag(tmp_path: Path) -> None:
    """Bag → frames → metrics: the synthetic world's known answers come out."""
    from harness.metrics import (
        OutputSpec,
        Tripwire,
        control_metrics,
        health_gates,
        perception_metrics,
        safety_metrics,
    )
    from tests.metrics.synthbag import ROI, TRIPWIRE

    write_synthetic_bag(tmp_path / "bag", SynthSpec(duration_s=20.0))
    f = load_frames(tmp_path / "bag")
    r = {m.name: m for m in (
        control_metrics(f, robot="forklift", route=[(3.0, 0.0), (21.0, 0.0)])
        + perception_metrics(f)
        + safety_metrics(f, tripwire=Tripwire(*TRIPWIRE, inside="right"), roi=ROI))}
    # forklift inside the trailer 8-16 s, nobody in the ROI then; the monitor lags 0.25 s
    # and publishes at 20 Hz, so each edge is followed 0.25 s to 0.30 s later
    for edge in ("mute", "unmute"):
        assert 0.25 <= r[f"safety.{edge}_lag.max"].value <= 0.30
        assert r[f"safety.{edge}_lag.p50"].value == r[f"safety.{edge}_lag.max"].value
    assert r["safety.mute_never_engaged"].value == 0
    assert r["safety.match_rate"].verdict == "PASS"
    assert r["control.odom_drift.max"].value == pytest.approx(0.0, abs=1e-9)
    assert r["control.goal_reached"].value == 1.0
    assert r["control.time_to_goal"].value == pytest.approx(11.67, abs=0.02)
    assert r["control.cross_track_error.max"].value == pytest.approx(0.0, abs=1e-9)
    assert r["perception.position_error.mean"].value == pytest.approx(0.0627, abs=0.01)
    assert 0.9 < r["perception.recall"].value < 0.99  # 5 % of detections dropped
    # one id per worker for the whole 20 s: no switch, and IDF1 is the detection F1
    assert r["perception.id_switches"].value == 0
    assert r["perception.idf1"].value == pytest.approx(r["perception.f1"].value)
    gates = health_gates(f, expected_hz={"/clock": 60, "/perception/tracks": 30},
                         gt_expected=list(f.gt_names), robots={"forklift": "/odom"},
                         outputs={"/cmd_vel": OutputSpec(first_within_s=0.1,
                                                         max_silence_s=0.1)})
    assert all(g.ok for g in gates), gates
