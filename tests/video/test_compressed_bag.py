"""Compressed camera images in the bag: foxglove_msgs/CompressedVideo (h264) and
sensor_msgs/CompressedImage (jpeg, png, 16-bit depth png), read back with the independent
mcap + mcap-ros2-support reader and decoded with PyAV's own decoders (not srr's), compared
with the raw frames recorded beside them; the same bytes on a second run; the systems under
test fed raw frames in the run and decoded ones in a replay."""

from __future__ import annotations

import json
import os
from collections import defaultdict
from pathlib import Path
from typing import Any

import av
import numpy as np
import pytest
from mcap.reader import make_reader

from harness import api
from harness.video import psnr, read_sim_time
from harness.video.sei import nal_units
from tests.conftest import ModuleTmp
from tests.e2e.bagread import decoded, mcap_file

pytestmark = pytest.mark.slow  # every test reads runs of the module's fixture

ROOT = Path(__file__).resolve().parents[2]
SCENE = Path(__file__).with_name("rtsp_two_cameras.yaml")
DOCK = ROOT / "scenarios" / "dock_nominal.yaml"
KEYFRAMES = 10
BOTH = ["rtsp.enabled=false", "duration=1.5",
        "cameras.0.outputs=[rgb,depth,camera_info]", "cameras.0.fps=30",
        "cameras.0.record.rgb=[raw,h264,jpeg]", "cameras.0.record.depth=[raw,png]",
        f"cameras.0.record.h264.keyframe_interval={KEYFRAMES}",
        "cameras.1.outputs=[rgb]", "cameras.1.fps=30", "cameras.1.record.rgb=[png]"]


def _run(tmp: Path, name: str, scenario: Path, overrides: list[str]) -> api.RunResult:
    sc = api.load(scenario, overrides=overrides)
    return api.run_scenario(sc, source=str(scenario), out=tmp / name)


@pytest.fixture(scope="module")
def runs(module_tmp: ModuleTmp) -> tuple[api.RunResult, api.RunResult]:
    tmp = module_tmp("compressed")
    return _run(tmp, "a", SCENE, BOTH), _run(tmp, "b", SCENE, BOTH)


def _by_topic(run_dir: Path) -> dict[str, list[tuple[int, str, Any]]]:
    out: dict[str, list[tuple[int, str, Any]]] = defaultdict(list)
    for topic, schema, t, msg in decoded(run_dir):
        out[topic].append((t, schema, msg))
    return out


def _rgb(msg: Any) -> np.ndarray:
    return np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.width, 3)


def test_h264_decodes_with_pyav_to_frames_close_to_the_raw_ones(runs: Any) -> None:
    topics = _by_topic(runs[0].run_dir)
    raw = {t: _rgb(m) for t, _, m in topics["/dock_cam_left_rgb"]}
    video = topics["/dock_cam_left_rgb/h264"]
    assert len(video) == len(raw) == 45  # 1.5 s at 30 Hz
    decoder = av.CodecContext.create("h264", "r")
    keys = []
    for k, (t, schema, msg) in enumerate(video):
        assert schema == "foxglove_msgs/msg/CompressedVideo"
        assert msg.format == "h264" and msg.frame_id == "dock_cam_left"
        assert msg.timestamp.sec * 10**9 + msg.timestamp.nanosec == t
        data = bytes(msg.data)
        assert data.startswith(b"\x00\x00\x00\x01")  # Annex B
        types = [data[head] & 0x1F for _, head, _ in nal_units(data)]
        if 5 in types:  # an IDR carries its SPS and PPS, as Foxglove needs
            keys.append(k)
            assert 7 in types and 8 in types
        sei = read_sim_time(data)
        assert sei is not None and (sei.time_ns, sei.index) == (t, k)
        frames = decoder.decode(av.Packet(data))
        assert len(frames) == 1  # one message, one frame, at once: no B-frames, no delay
        assert frames[0].pict_type != av.video.frame.PictureType.B
        assert psnr(frames[0].to_ndarray(format="rgb24"), raw[t]) >= 30.0
    assert keys == list(range(0, 45, KEYFRAMES))


def test_jpeg_png_and_depth_png_decode_with_pyav(runs: Any) -> None:
    topics = _by_topic(runs[0].run_dir)
    raw = {t: _rgb(m) for t, _, m in topics["/dock_cam_left_rgb"]}
    for t, schema, msg in topics["/dock_cam_left_rgb/compressed"]:
        assert schema == "sensor_msgs/msg/CompressedImage" and msg.format == "jpeg"
        (frame,) = av.CodecContext.create("mjpeg", "r").decode(av.Packet(bytes(msg.data)))
        assert psnr(frame.to_ndarray(format="rgb24"), raw[t]) >= 30.0
    depth = {t: np.frombuffer(bytes(m.data), "<f4").reshape(m.height, m.width)
             for t, _, m in topics["/dock_cam_left_depth"]}
    compressed = topics["/dock_cam_left_depth/compressed"]
    assert len(compressed) == len(depth) == 45
    for t, _, msg in compressed:
        assert msg.format == "16UC1; png"
        (frame,) = av.CodecContext.create("png", "r").decode(av.Packet(bytes(msg.data)))
        assert frame.format.name == "gray16be"
        mm = frame.reformat(format="gray16le").to_ndarray()
        d = depth[t]
        hit = np.isfinite(d)
        assert hit.any() and not hit.all()  # floor and walls, and sky beyond the door
        assert np.array_equal(mm[~hit], np.zeros((~hit).sum(), np.uint16))
        assert np.abs(mm[hit] / 1000.0 - d[hit]).max() <= 0.0005 + 1e-6
    # the right camera records only lossless png: pixel for pixel the rendered frame, though
    # its raw topic is not in the bag
    assert "/dock_cam_right_rgb" not in topics
    assert len(topics["/dock_cam_right_rgb/compressed"]) == 45


def test_the_run_is_healthy_and_says_what_it_did_not_record(runs: Any) -> None:
    summary = runs[0].summary
    gates = {h["name"]: h["ok"] for h in summary["health"]}
    assert gates["recorded_equals_published"]
    assert gates["topic_rate:/dock_cam_left_rgb/h264"]
    assert gates["topic_rate:/dock_cam_right_rgb/compressed"]
    assert "topic_rate:/dock_cam_right_rgb" not in gates
    assert summary["unrecorded"] == {"/dock_cam_right_rgb": {
        "type": "sensor_msgs/msg/Image", "published": 45}}


def test_two_runs_give_identical_digests_with_the_cpu_encoder(runs: Any) -> None:
    a, b = (r.summary["topics"] for r in runs)
    assert a.keys() == b.keys()
    for topic in ("/dock_cam_left_rgb/h264", "/dock_cam_left_rgb/compressed",
                  "/dock_cam_left_depth/compressed", "/dock_cam_right_rgb/compressed"):
        assert a[topic]["sha256"] == b[topic]["sha256"], topic
    assert runs[0].summary["digest"] == runs[1].summary["digest"]


def test_compressed_only_dock_run_feeds_perception_raw_and_replays_decoded(
        tmp_path: Path) -> None:
    compressed = ["duration=3", "cameras.0.record.rgb=[h264]", "cameras.1.record.rgb=[h264]",
                  "cameras.0.record.depth=[png]", "cameras.1.record.depth=[png]"]
    raw = _run(tmp_path, "raw", DOCK, ["duration=3"])
    small = _run(tmp_path, "small", DOCK, compressed)
    tracks = "/perception/tracks"
    # in the run the tracker read the raw depth images: the very same tracks
    assert small.summary["topics"][tracks]["sha256"] == raw.summary["topics"][tracks]["sha256"]
    assert "/dock_cam_left_depth" not in small.summary["topics"]
    # the report's camera keyframes come from the compressed topics (h264 decoded from the
    # keyframe before the moment)
    html = (small.run_dir / "report.html").read_text()
    assert 'alt="/dock_cam_left_rgb/h264 at ' in html
    assert 'alt="/dock_cam_right_rgb/h264 at ' in html
    raw_bytes = sum(t["bytes"] for t in raw.summary["topics"].values())
    small_bytes = sum(t["bytes"] for t in small.summary["topics"].values())
    assert small_bytes * 5 < raw_bytes
    # a replay decodes the depth png back to 32FC1 for the tracker: millimetre depth, so the
    # tracks are close to the recorded ones, not necessarily equal
    rep = api.replay(small.run_dir, out=tmp_path / "replay")
    assert not rep.summary["warnings"], rep.summary["warnings"]
    assert rep.summary["topics"][tracks]["count"] == raw.summary["topics"][tracks]["count"]
    m = {x["name"]: x["value"] for x in rep.summary["metrics"]}
    m0 = {x["name"]: x["value"] for x in raw.summary["metrics"]}
    assert m["perception.recall"] == m0["perception.recall"]
    assert abs(m["perception.position_error.mean"] - m0["perception.position_error.mean"]) \
        < 0.005
    assert json.loads((rep.run_dir / "summary.json").read_text())["unrecorded"] == {
        "/dock_cam_left_depth": {"type": "sensor_msgs/msg/Image", "published": 15},
        "/dock_cam_right_depth": {"type": "sensor_msgs/msg/Image", "published": 15}}


@pytest.mark.ros2
def test_compressed_images_read_back_with_rclpy(runs: Any) -> None:
    """sensor_msgs/CompressedImage as recorded is what the real rclpy (ROS 2 Jazzy) reads."""
    if os.environ.get("SRR_REQUIRE_ROS2") != "1":
        pytest.importorskip("rclpy", reason="needs the ros2 extra")
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import CompressedImage

    topics = ("/dock_cam_left_rgb/compressed", "/dock_cam_left_depth/compressed")
    n = 0
    with mcap_file(runs[0].run_dir).open("rb") as f:
        for _schema, channel, message in make_reader(f).iter_messages(topics=list(topics)):
            msg = deserialize_message(message.data, CompressedImage)
            assert msg.format == ("jpeg" if "rgb" in channel.topic else "16UC1; png")
            assert msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec == message.log_time
            assert bytes(msg.data)[:4] in (b"\xff\xd8\xff\xdb", b"\x89PNG")
            n += 1
    assert n == 90
