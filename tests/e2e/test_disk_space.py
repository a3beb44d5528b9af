"""Disk space: the bag-size estimate against real bags, refusing to start, and stopping a run
whose disk fills up (the free-space probe is injected; the real disk is never filled)."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

from harness import api, runmarker
from harness.cli import main
from harness.diskspace import MB, DiskGuard, estimate_bag_bytes, large_bag_notice
from harness.errors import DiskSpaceError

from .bagread import decoded, mcap_file

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


@pytest.mark.parametrize(("name", "duration"), [("forklift_warehouse", 2.0),
                                                ("camera_publishing", 1.0)])
@pytest.mark.slow
def test_estimate_is_within_its_stated_factor_of_a_real_bag(tmp_path: Path, name: str,
                                                            duration: float) -> None:
    sc = api.load(SCENARIOS / f"{name}.yaml", duration=duration)
    res = api.run_scenario(sc, source=str(SCENARIOS / f"{name}.yaml"), out=tmp_path / "r")
    actual = mcap_file(res.run_dir).stat().st_size
    ratio = estimate_bag_bytes(sc).total / actual
    # Errs high, by at most 1.6x: point clouds are counted as if every pixel were valid.
    assert 1.0 <= ratio <= 1.6, ratio


def test_estimate_scales_with_cameras_resolution_rate_and_duration() -> None:
    sc = api.load(SCENARIOS / "camera_publishing.yaml", duration=1.0)
    base = estimate_bag_bytes(sc).total
    longer = estimate_bag_bytes(api.load(SCENARIOS / "camera_publishing.yaml", duration=2.0))
    wider = estimate_bag_bytes(api.load(SCENARIOS / "camera_publishing.yaml", duration=1.0,
                                        overrides=["cameras.0.resolution=[512,256]"]))
    slower = estimate_bag_bytes(api.load(SCENARIOS / "camera_publishing.yaml", duration=1.0,
                                         overrides=["cameras.0.fps=15"]))
    assert longer.total == pytest.approx(2 * base, rel=0.01)
    assert wider.total == pytest.approx(2 * base, rel=0.02)
    assert slower.total == pytest.approx(base / 2, rel=0.05)
    parts = dict(estimate_bag_bytes(sc).parts)
    frames = 30  # 1 s at 30 Hz on the 60 Hz tick
    assert parts["floating_camera_rgb"] >= frames * 256 * 256 * 3
    assert parts["floating_camera_depth"] >= frames * 256 * 256 * 4


def test_refuses_to_start_without_room_for_the_estimate(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    out = tmp_path / "r"
    code = main(["run", str(SCENARIOS / "camera_publishing.yaml"), "--out", str(out), "-q",
                 "--duration", "3600", "--set", "cameras.0.resolution=[4096,4096]"])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert str(out) in err and "not enough free disk space" in err
    assert "floating_camera_pointcloud" in err and " MB free" in err
    assert not out.exists()  # nothing written, not even the run directory


def test_refusal_names_the_margin_from_the_command_line(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    out = tmp_path / "r"
    code = main(["run", str(SCENARIOS / "forklift_warehouse.yaml"), "--out", str(out), "-q",
                 "--min-free-mb", "1e8"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "recording.min_free_mb 100,000,000.0 MB" in err, err
    assert not out.exists()


@pytest.mark.slow
def test_low_disk_stops_the_run_at_a_tick_boundary_and_marks_it_invalid(tmp_path: Path) -> None:
    calls: list[Path] = []

    def probe(path: Path) -> int:  # plenty before the start, then the disk fills up
        calls.append(path)
        return 10**12 if len(calls) < 3 else 100 * MB

    sc = api.load(SCENARIOS / "forklift_warehouse.yaml", duration=5.0)
    res = api.run_scenario(sc, source=str(SCENARIOS / "forklift_warehouse.yaml"),
                           out=tmp_path / "r", free_space=probe)
    # Probes: before the start, after 1 s (fine), after 2 s (100 MB < 256 MB): stop there.
    assert len(calls) == 3 and all(p == res.run_dir for p in calls)
    assert res.verdict == "INVALID" and res.exit_code == 3
    s = res.summary
    assert s["ticks"] == 120 and s["simulated_s"] == 2.0 and not s["interrupted"]
    assert "fell to 100.0 MB" in s["stopped"] and "after 2 s of simulated time" in s["stopped"]
    gate = next(h for h in s["health"] if h["name"] == "disk_space")
    assert not gate["ok"] and any("disk_space" in r for r in s["reasons"])
    on_disk = json.loads((res.run_dir / "summary.json").read_text())
    assert on_disk["verdict"] == "INVALID"
    assert not (res.run_dir / runmarker.MARKER).exists()
    # The bag was closed cleanly: the independent reader reads all of it.
    counts = Counter(topic for topic, _, _, _ in decoded(res.run_dir))
    assert counts["/clock"] == 120 and counts["/odom"] == 120
    assert not list((res.run_dir / "bag").glob("*.damaged"))


def test_the_guard_probes_by_ticks_or_by_bytes_whichever_first() -> None:
    seen: list[int] = []

    def probe(path: Path) -> int:
        seen.append(1)
        return 10**9

    guard = DiskGuard(Path("."), 256 * MB, probe, every_ticks=60, every_bytes=16 * MB)
    assert [guard.poll(t, 0) for t in range(1, 60)] == [None] * 59 and not seen
    assert guard.poll(60, 0) is None and len(seen) == 1
    assert guard.poll(61, 16 * MB) is None and len(seen) == 2  # 16 MB written since
    assert guard.poll(62, 17 * MB) is None and len(seen) == 2
    low = DiskGuard(Path("/x"), 256 * MB, lambda p: 255 * MB, every_ticks=1)
    assert low.poll(1, 0) == ("free disk space at /x fell to 255.0 MB, below "
                              "recording.min_free_mb (256.0 MB)")


def test_api_refusal_is_a_disk_space_error(tmp_path: Path) -> None:
    sc = api.load(SCENARIOS / "forklift_warehouse.yaml", duration=1.0)
    with pytest.raises(DiskSpaceError, match="not enough free disk space"):
        api.run_scenario(sc, out=tmp_path / "r", free_space=lambda p: 10 * MB)
    assert not (tmp_path / "r").exists()


@pytest.mark.slow
def test_an_h264_camera_is_estimated_by_its_expected_size_not_its_raw_picture(
        tmp_path: Path) -> None:
    """An hour of a 1080p h264 camera was estimated at its raw 4:2:0 pictures (336 GB) and
    refused on any ordinary disk; it is a 32nd of the RGB pixels at the default crf, a fixed
    bitrate's own size with bitrate_kbps, the raw picture near lossless (crf below 18)."""
    path = SCENARIOS / "camera_publishing.yaml"

    def h264_part(*extra: str) -> int:
        sc = api.load(path, duration=3600.0, overrides=[
            "cameras.0.resolution=[1920,1080]", "cameras.0.record={rgb: [h264]}", *extra])
        return dict(estimate_bag_bytes(sc).parts)["floating_camera_rgb h264"]

    frames = 3600 * 30
    assert h264_part() == pytest.approx(frames * 1920 * 1080 * 3 / 32, rel=0.01)  # 21 GB
    notice = large_bag_notice(api.load(path, duration=3600.0, overrides=[
        "cameras.0.outputs=[rgb]", "cameras.0.resolution=[1920,1080]",
        "cameras.0.record={rgb: [h264]}"]))
    assert notice is not None and "h264" not in notice.split(";", 1)[1]  # it is h264 already
    assert h264_part("cameras.0.record.h264.bitrate_kbps=8000") == pytest.approx(
        frames * 2 * 8000 * 1000 / 8 / 30, rel=0.01)  # twice 8 Mbit/s
    assert h264_part("cameras.0.record.h264.crf=10") == pytest.approx(
        frames * 1920 * 1080 * 3 / 2, rel=0.01)
    # against a real recording: the moving dock scene's h264 stays under its estimate
    dock = SCENARIOS / "dock_worker_crossing.yaml"
    sc = api.load(dock, duration=6.0, overrides=["cameras.0.record={rgb: [h264]}"])
    res = api.run_scenario(sc, source=str(dock), out=tmp_path / "r", video=False)
    recorded = res.summary["topics"]["/dock_cam_left_rgb/h264"]["bytes"]
    assert recorded <= dict(estimate_bag_bytes(sc).parts)["dock_cam_left_rgb h264"]
