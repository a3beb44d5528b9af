"""A robot-mounted camera's ``record`` block (seed 000's TurtleBot3 ``camera/color``): h264 and
depth PNG in the bag in the robot's namespace, read back with the independent mcap reader
and decoded with PyAV, compared with a raw run's frames; the raw topics published but not
recorded; the same bytes on a second run; a replay decoding them for a system under test
that reads the raw topics; bad values one line naming the file and field (exit 2)."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Any

import av
import numpy as np
import pytest
import yaml

from harness import api
from harness.builders.camera_record import compressed_streams, robot_camera, unrecorded_topics
from harness.cli import main
from harness.regression import config_differences
from harness.scenario import scenario_to_mapping
from harness.video import psnr
from tests.conftest import ModuleTmp
from tests.e2e.bagread import decoded

ROOT = Path(__file__).resolve().parents[2]
TURTLEBOT = ROOT / "scenarios" / "turtlebot3_room.yaml"
CAM = "robots.0.sensors.camera"
SHORT = ["duration=1", f"{CAM}.resolution=[64,48]", f"{CAM}.depth_topic=camera/depth"]
COMPRESSED = [f"{CAM}.record.rgb=[h264]", f"{CAM}.record.depth=[png]",
              f"{CAM}.record.h264.keyframe_interval=4"]
FRAMES = 10  # 1 s at 10 fps


@pytest.fixture(scope="module")
def scene(module_tmp: ModuleTmp) -> Path:
    """turtlebot3_room.yaml with a system under test that reads the camera's raw topics."""
    doc = yaml.safe_load(TURTLEBOT.read_text())
    doc["systems_under_test"].append({
        "name": "stats", "plugin": "tests.video.robot_plugins:ImageStats",
        "params": {"rgb": "camera/color", "depth": "camera/depth"}})
    path = module_tmp("robotcam") / "turtlebot3_stats.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def _run(scene: Path, out: Path, overrides: list[str]) -> api.RunResult:
    return api.run_scenario(api.load(scene, overrides=overrides), source=str(scene), out=out)


@pytest.fixture(scope="module")
def runs(scene: Path) -> dict[str, api.RunResult]:
    return {name: _run(scene, scene.parent / name, SHORT + extra)
            for name, extra in (("raw", []), ("a", COMPRESSED), ("b", COMPRESSED))}


def _by_topic(run_dir: Path) -> dict[str, list[tuple[int, str, Any]]]:
    out: dict[str, list[tuple[int, str, Any]]] = defaultdict(list)
    for topic, schema, t, msg in decoded(run_dir):
        out[topic].append((t, schema, msg))
    return out


@pytest.mark.slow
def test_h264_and_depth_png_decode_with_pyav_close_to_a_raw_run(
        runs: dict[str, api.RunResult]) -> None:
    raw_topics, topics = _by_topic(runs["raw"].run_dir), _by_topic(runs["a"].run_dir)
    raw = {t: np.frombuffer(bytes(m.data), np.uint8).reshape(m.height, m.width, 3)
           for t, _, m in raw_topics["/camera/color"]}
    video = topics["/camera/color/h264"]
    assert len(video) == len(raw) == FRAMES
    decoder = av.CodecContext.create("h264", "r")
    for t, schema, msg in video:
        assert schema == "foxglove_msgs/msg/CompressedVideo"
        assert msg.format == "h264" and msg.frame_id == "camera"
        (frame,) = decoder.decode(av.Packet(bytes(msg.data)))
        image = frame.to_ndarray(format="rgb24")
        assert image.shape == (48, 64, 3)
        assert psnr(image, raw[t]) >= 30.0, t
    depth = {t: np.frombuffer(bytes(m.data), "<f4").reshape(m.height, m.width)
             for t, _, m in raw_topics["/camera/depth"]}
    compressed = topics["/camera/depth/compressed"]
    assert len(compressed) == len(depth) == FRAMES
    for t, schema, msg in compressed:
        assert schema == "sensor_msgs/msg/CompressedImage"
        assert msg.format == "16UC1; png" and msg.header.frame_id == "camera"
        (frame,) = av.CodecContext.create("png", "r").decode(av.Packet(bytes(msg.data)))
        mm = frame.reformat(format="gray16le").to_ndarray()
        d = depth[t]
        hit = np.isfinite(d)
        assert hit.any()  # the room's floor and walls
        assert np.abs(mm[hit] / 1000.0 - d[hit]).max() <= 0.0005 + 1e-6
        assert not mm[~hit].any()


@pytest.mark.slow
def test_raw_topics_are_published_not_recorded(runs: dict[str, api.RunResult]) -> None:
    summary = runs["a"].summary
    assert "/camera/color" not in summary["topics"]
    assert "/camera/depth" not in summary["topics"]
    assert summary["unrecorded"] == {
        "/camera/color": {"type": "sensor_msgs/msg/Image", "published": FRAMES},
        "/camera/depth": {"type": "sensor_msgs/msg/Image", "published": FRAMES}}
    gates = {h["name"]: h["ok"] for h in summary["health"]}
    assert gates["recorded_equals_published"]
    assert gates["topic_rate:/camera/color/h264"]
    assert gates["topic_rate:/camera/depth/compressed"]
    # in the run the system under test read the rendered frames: the raw run's very values
    for topic in ("/image_stats/rgb", "/image_stats/depth"):
        assert summary["topics"][topic]["count"] == FRAMES
        assert summary["topics"][topic]["sha256"] == \
            runs["raw"].summary["topics"][topic]["sha256"]


@pytest.mark.slow
def test_two_runs_give_identical_digests(runs: dict[str, api.RunResult]) -> None:
    a, b = runs["a"].summary, runs["b"].summary
    assert a["topics"].keys() == b["topics"].keys()
    for topic in a["topics"]:
        assert a["topics"][topic]["sha256"] == b["topics"][topic]["sha256"], topic
    assert a["digest"] == b["digest"]
    # how the camera is recorded changes nothing else
    raw = runs["raw"].summary["topics"]
    for topic in ("/odom", "/scan", "/tf", "/camera/camera_info"):
        assert a["topics"][topic]["sha256"] == raw[topic]["sha256"], topic


@pytest.mark.slow
def test_replay_decodes_the_compressed_topics_for_a_raw_reader(
        runs: dict[str, api.RunResult], tmp_path: Path) -> None:
    rep = api.replay(runs["a"].run_dir, out=tmp_path / "replay")
    assert not rep.summary["warnings"], rep.summary["warnings"]
    replayed, recorded = _by_topic(rep.run_dir), _by_topic(runs["raw"].run_dir)
    for topic, tolerance in (("/image_stats/rgb", 2.0), ("/image_stats/depth", 0.0005)):
        got = [list(m.data) for _, _, m in replayed[topic]]
        want = [list(m.data) for _, _, m in recorded[topic]]
        assert len(got) == len(want) == FRAMES
        for (t, mean), (t0, mean0) in zip(got, want, strict=True):
            assert t == t0  # decoded at the recorded stamps
            assert abs(mean - mean0) <= tolerance, (topic, t, mean, mean0)


def test_topics_in_the_robots_namespace() -> None:
    sc = api.load(TURTLEBOT, overrides=[*SHORT, *COMPRESSED, "robots.0.namespace=tb",
                                        f"{CAM}.record.rgb=[raw,h264,jpeg]"])
    cam = robot_camera(sc, sc.robots[0])
    assert cam is not None
    assert [(s.topic, s.raw_topic, s.msgtype) for s in compressed_streams(cam)] == [
        ("/tb/camera/color/h264", "/tb/camera/color", "foxglove_msgs/msg/CompressedVideo"),
        ("/tb/camera/color/compressed", "/tb/camera/color", "sensor_msgs/msg/CompressedImage"),
        ("/tb/camera/depth/compressed", "/tb/camera/depth", "sensor_msgs/msg/CompressedImage")]
    assert unrecorded_topics(sc) == {"/tb/camera/depth"}
    # how a robot's camera is recorded does not make runs incomparable
    plain = api.load(TURTLEBOT, overrides=[*SHORT, "robots.0.namespace=tb"])
    assert config_differences(scenario_to_mapping(plain), scenario_to_mapping(sc)) == []


@pytest.mark.parametrize(
    ("overrides", "field", "words"),
    [
        ([f"{CAM}.record.rgb=[webp]"], f"{CAM}.record.rgb[0]",
         "expected one of 'raw', 'h264', 'jpeg', 'png'"),
        ([f"{CAM}.record.depth=[png]"], f"{CAM}.record.depth",
         f"records png of the depth stream, but {CAM.replace('.0.', '[0].')}.depth_topic "
         "is not set"),
        ([f"{CAM}.record.rgb=[jpeg,png]"], f"{CAM}.record.rgb",
         "jpeg and png both go to camera/color/compressed: choose one"),
        ([f"{CAM}.record.rgb=[h264]", f"{CAM}.resolution=[63,48]"], f"{CAM}.resolution",
         "needs an even width and height, got 63x48"),
        ([f"{CAM}.record.h264.preset=turbo", f"{CAM}.record.rgb=[h264]"],
         f"{CAM}.record.h264.preset", "x264 has no preset 'turbo'"),
        ([f"{CAM}.record.jpeg_qscale=1"], f"{CAM}.record.jpeg_qscale", "must be >= 2"),
        ([f"{CAM}.graph=false", f"{CAM}.record.rgb=[h264]"], f"{CAM}.record",
         "has no effect with graph: false"),
    ],
    ids=["unknown-format", "no-depth-topic", "jpeg-and-png", "odd-size", "preset",
         "qscale", "no-graph"],
)
def test_bad_record_values_are_one_line_exit_2(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str],
                                               overrides: list[str], field: str,
                                               words: str) -> None:
    path = tmp_path / "scenario.yaml"
    sc = api.load(TURTLEBOT)
    path.write_text(yaml.safe_dump(scenario_to_mapping(sc), sort_keys=False))
    field = field.replace("robots.0.", "robots[0].")
    sets = [a for o in overrides for a in ("--set", o)]
    for argv in (["validate", str(path), *sets],
                 ["run", str(path), *sets, "--out", str(tmp_path / "o")]):
        code = main(argv)
        err = capsys.readouterr().err.strip()
        assert code == 2, err
        assert len(err.splitlines()) == 1, err
        assert field in err and words in err, err
        assert not (tmp_path / "o").exists()
