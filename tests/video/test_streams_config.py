"""The ``rtsp:`` block and a camera's ``port`` / ``mount_path`` / ``record``: bad values are
one line naming the file and the field (exit 2) from ``srr validate`` and ``srr run``, before
anything listens or renders."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from harness import api
from harness.builders.camera_record import compressed_streams, fixed_camera, unrecorded_topics
from harness.cli import main
from harness.regression import config_differences
from harness.scenario import scenario_to_mapping

CAMS = """\
format_version: 1
name: t
duration: 1
cameras:
  - {name: cam_a, port: 8554, resolution: [64, 48], outputs: [rgb, depth]}
  - {name: cam_b, port: 8555, mount_path: /b/cam, resolution: [64, 48], outputs: []}
rtsp: {enabled: true}
"""


@pytest.mark.parametrize(
    ("edit", "field", "words"),
    [
        (("port: 8555, mount_path: /b/cam", "port: 8554, mount_path: /cam_a"),
         "cameras[1].port", "rtsp://127.0.0.1:8554/cam_a is also the stream of cameras[0] "
         "(cam_a)"),
        (("port: 8554", "port: 0"), "cameras[0].port", "must be >= 1"),
        (("/b/cam", "b/cam"), "cameras[1].mount_path", "must be '/' followed by"),
        (("/b/cam", "/b cam"), "cameras[1].mount_path", "must be '/' followed by"),
        (("[64, 48], outputs: []", "[63, 48], outputs: []"), "cameras[1].resolution",
         "needs an even width and height, got 63x48"),
        (("rtsp: {enabled: true}", "rtsp: {enabled: true, host: ''}"), "rtsp.host",
         "must not be empty"),
        (("rtsp: {enabled: true}", "rtsp: {enabled: true, h264: {encoder: vaapi}}"),
         "rtsp.h264.encoder", "expected one of 'x264', 'nvenc'"),
        (("rtsp: {enabled: true}", "rtsp: {enabled: true, fps: 0}"), "rtsp.fps",
         "must be > 0"),
        (("outputs: [rgb, depth]}", "outputs: [rgb], record: {depth: [png]}}"),
         "cameras[0].record.depth", "outputs has no 'depth'"),
        (("outputs: [rgb, depth]}", "outputs: [rgb], record: {rgb: [jpeg, png]}}"),
         "cameras[0].record.rgb", "jpeg and png both go to cam_a_rgb/compressed"),
        (("outputs: [rgb, depth]}", "outputs: [rgb], record: {rgb: [h264, h264]}}"),
         "cameras[0].record.rgb[1]", "'h264' is listed twice"),
        (("outputs: [rgb, depth]}", "outputs: [rgb], record: {rgb: [webp]}}"),
         "cameras[0].record.rgb[0]", "expected one of 'raw', 'h264', 'jpeg', 'png'"),
        (("outputs: [rgb, depth]}", "outputs: [rgb], record: {h264: {crf: 60}}}"),
         "cameras[0].record.h264.crf", "must be <= 51"),
        (("rtsp: {enabled: true}", "rtsp: {enabled: true, h264: {preset: turbo}}"),
         "rtsp.h264.preset", "x264 has no preset 'turbo' (presets: ultrafast,"),
        (("rtsp: {enabled: true}",
          "rtsp: {enabled: true, h264: {encoder: nvenc, preset: veryfast}}"),
         "rtsp.h264.preset", "nvenc has no preset 'veryfast' (presets: p1,"),
    ],
    ids=["same-url", "port-zero", "relative-mount", "mount-with-space", "odd-size",
         "empty-host", "unknown-encoder", "zero-fps", "depth-not-published",
         "jpeg-and-png", "twice", "unknown-format", "crf-range", "x264-preset",
         "nvenc-preset"],
)
def test_bad_stream_settings_are_one_line_exit_2(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str],
                                                 edit: tuple[str, str], field: str,
                                                 words: str) -> None:
    path = tmp_path / "scenario.yaml"
    text = CAMS.replace(*edit)
    assert text != CAMS
    path.write_text(text)
    for argv in (["validate", str(path)], ["run", str(path), "--out", str(tmp_path / "o")]):
        code = main(argv)
        err = capsys.readouterr().err.strip()
        assert code == 2, err
        assert len(err.splitlines()) == 1, err
        assert f"{path}: {field}: " in err and words in err, err
        assert not (tmp_path / "o").exists()


def test_enabled_without_a_port_is_refused(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text(CAMS.replace("port: 8554, ", "").replace("port: 8555, ", ""))
    assert main(["validate", str(path)]) == 2
    assert "rtsp.enabled: no enabled camera has a port" in capsys.readouterr().err


def test_validate_builds_the_graph_without_listening(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text(CAMS)
    assert main(["validate", str(path)]) == 0
    assert main(["graph", str(path), "--format", "json"]) == 0
    out = capsys.readouterr().out
    assert "/World/RTSPMultiGraph" in out and "RTSP_cam_b" in out
    # cam_b only streams: no camera graph of its own
    assert "/World/cam_b_CameraGraph" not in out and "/World/cam_a_CameraGraph" in out


def test_topics_of_a_record_block(tmp_path: Path) -> None:
    path = tmp_path / "scenario.yaml"
    path.write_text(CAMS.replace("outputs: [rgb, depth]}", "outputs: [rgb, depth], "
                                 "record: {rgb: [h264, jpeg], depth: [raw, png]}}"))
    sc = api.load(path)
    streams = compressed_streams(fixed_camera(sc, sc.cameras[0]))
    assert [(s.topic, s.raw_topic, s.msgtype) for s in streams] == [
        ("/cam_a_rgb/h264", "/cam_a_rgb", "foxglove_msgs/msg/CompressedVideo"),
        ("/cam_a_rgb/compressed", "/cam_a_rgb", "sensor_msgs/msg/CompressedImage"),
        ("/cam_a_depth/compressed", "/cam_a_depth", "sensor_msgs/msg/CompressedImage")]
    assert unrecorded_topics(sc) == {"/cam_a_rgb"}
    # how a camera is recorded and whether it streams do not make runs incomparable
    plain = api.load(path, overrides=["cameras.0.record.rgb=[raw]", "rtsp.enabled=false"])
    assert config_differences(scenario_to_mapping(plain), scenario_to_mapping(sc)) == []


def test_validate_warns_of_a_port_held_now(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket() as blocker:
        blocker.bind(("127.0.0.1", 0))
        blocker.listen()
        busy = blocker.getsockname()[1]
        path = tmp_path / "scenario.yaml"
        path.write_text(CAMS.replace("port: 8555", f"port: {busy}"))
        assert main(["validate", str(path)]) == 0
    err = capsys.readouterr().err
    assert (f"{path}: cameras[1].port: 127.0.0.1:{busy} cannot be bound now (Address already "
            "in use); a run would stop there") in err


def test_a_held_port_two_cameras_share_is_one_warning(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """Cameras on one port share a server (a mount path each): a port held by another
    program is said once, naming every camera that streams on it."""
    with socket.socket() as blocker:
        blocker.bind(("127.0.0.1", 0))
        blocker.listen()
        busy = blocker.getsockname()[1]
        path = tmp_path / "scenario.yaml"
        path.write_text(CAMS.replace("port: 8554", f"port: {busy}")
                        .replace("port: 8555", f"port: {busy}"))
        assert main(["validate", str(path)]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines() if "cannot be bound" in line]
    assert warnings == [f"srr validate: warning: {path}: cameras[0].port: 127.0.0.1:{busy} "
                        "cannot be bound now (Address already in use); a run would stop there "
                        "(the port of cameras[1] too)"], warnings


def test_validate_opens_the_encoders_it_will_need(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """NVENC opens only on an NVIDIA GPU with an encoder engine: elsewhere ``srr validate``
    says so in one line, before a run would fail at its first frame."""
    path = tmp_path / "scenario.yaml"
    path.write_text(CAMS.replace("outputs: [rgb, depth]}", "outputs: [rgb], record: "
                                 "{rgb: [h264], h264: {encoder: nvenc}}}"))
    code = main(["validate", str(path)])
    err = capsys.readouterr().err.strip()
    if code == 0:  # a machine with NVENC
        return
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"srr validate: {path}: cameras[0].record.h264: h264.encoder nvenc: "
                          "cannot open the nvenc h264 encoder (h264_nvenc): "), err
