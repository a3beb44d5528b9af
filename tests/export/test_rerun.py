"""``srr export RUN_DIR --rerun FILE.rrd``: real runs (the dock with its two cameras recorded
raw, as h264, JPEG and depth PNG; a lidar robot) exported and read back with Rerun's own
reader (``rerun.chunk.RrdReader``): the entities, each one's rows on ``sim_time`` against the
bag as an independent reader (mcap + mcap-ros2-support) reads it, and values at given times;
bad input is one line, exit 2, and leaves no file."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness import api
from harness.cli import main
from tests.conftest import SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded, mcap_file

pytestmark = pytest.mark.slow

CAMERAS = ["--set", "cameras.dock_cam_left.record.rgb=[raw,h264]",
           "--set", "cameras.dock_cam_right.record.rgb=[jpeg]",
           "--set", "cameras.dock_cam_right.record.depth=[png]"]


def _run(tmp: Path, scenario: str, duration: str, *extra: str) -> Path:
    out = tmp / scenario
    code = main(["run", str(SCENARIOS / f"{scenario}.yaml"), "--duration", duration,
                 "--out", str(out), "-q", *extra])
    assert code in (0, 1), code  # judged (a short run is of another configuration)
    return out


@pytest.fixture(scope="module")
def dock(module_tmp: ModuleTmp) -> Path:
    return _run(module_tmp("export"), "dock_nominal", "2", *CAMERAS)


@pytest.fixture(scope="module")
def lidar(module_tmp: ModuleTmp) -> Path:
    return _run(module_tmp("export"), "diffbot_urdf", "1")


def _reader(rrd: Path) -> Any:
    """Rerun's own reader of ``rrd``, imported on first use, not at collection: the SDK takes
    0.7 s to import, which every pytest process (each xdist worker) would pay for nothing."""
    rerun_chunk = pytest.importorskip("rerun.chunk")
    return rerun_chunk.RrdReader(rrd)


def _read(rrd: Path) -> tuple[dict[str, int], dict[str, list[Any]]]:
    """Rows on sim_time per entity (static rows apart, as ``entity#static``) and each
    entity's record batches, as Rerun reads the file."""
    store = _reader(rrd).stream().collect()
    rows: Counter[str] = Counter()
    batches: dict[str, list[Any]] = {}
    for ch in store.stream():
        path = ch.entity_path
        if ch.is_static:
            rows[f"{path}#static"] += ch.num_rows
        else:
            assert ch.timeline_names == ["sim_time"], (path, ch.timeline_names)
            rows[path] += ch.num_rows
        batches.setdefault(path, []).append(ch.to_record_batch())
    return dict(rows), batches


def _column(batches: list[Any], name: str) -> list[tuple[int, Any]]:
    """(sim_time ns, value) of a column over an entity's timed batches, in time order."""
    out = []
    for rb in batches:
        if "sim_time" not in rb.schema.names or name not in rb.schema.names:
            continue
        times = rb.column("sim_time").cast("int64").to_pylist()
        out += list(zip(times, rb.column(name).to_pylist(), strict=True))
    return sorted(out, key=lambda p: p[0])


def test_a_dock_run_reads_back_in_rerun(dock: Path, tmp_path: Path) -> None:
    rrd = tmp_path / "dock.rrd"
    res = api.export_rerun(dock, rrd)
    assert res.path == rrd and rrd.stat().st_size == res.bytes
    rows, batches = _read(rrd)
    msgs = list(decoded(dock))
    per_topic = Counter(topic for topic, *_ in msgs)
    per_child = Counter(t.child_frame_id for topic, _, _, m in msgs if topic == "/tf"
                        for t in m.transforms)
    # TF: an entity per frame, nested as the bag parents them; a row per transform
    assert rows["/tf/world/odom/base_link"] == per_child["base_link"] > 0
    assert rows["/tf/world/dock_cam_left"] == per_child["dock_cam_left"]
    assert rows["/tf/world/dock_cam_left/dock_cam_left_world#static"] == 1
    # ground truth, odometry and the worker: a position per message, the path once
    assert rows["/tf/world/ground_truth/forklift"] == per_topic["/gt/forklift/tf"]
    assert rows["/tf/world/workers/character_0"] == per_topic["/gt/character_0/tf"]
    assert rows["/tf/world/odom/odometry/odom"] == per_topic["/odom"]
    assert rows["/tf/world/workers/character_0/path#static"] == 1
    # cameras: every recorded image, raw, h264, JPEG and 16-bit PNG depth
    # under each camera's pinhole, in its optical frame, from its camera info
    left, right = "/tf/world/dock_cam_left/image", "/tf/world/dock_cam_right/image"
    for base, topic in ((left, "/dock_cam_left_rgb"), (left, "/dock_cam_left_depth"),
                        (left, "/dock_cam_left_rgb/h264"),
                        (right, "/dock_cam_right_rgb/compressed"),
                        (right, "/dock_cam_right_depth/compressed")):
        assert rows[f"{base}{topic}"] == per_topic[topic] > 0, topic
    assert rows[f"{left}/dock_cam_left_rgb/h264#static"] == 1  # the codec
    info = next(m for topic, _, _, m in msgs if topic == "/dock_cam_left_camera_info")
    (pinhole,) = batches[left]
    assert pinhole.column("Pinhole:image_from_camera").to_pylist()[0][0] == pytest.approx(
        list(np.asarray(info.k).reshape(3, 3).T.ravel()))  # Rerun's matrices: column-major
    assert pinhole.column("Pinhole:resolution").to_pylist()[0][0] == [info.width, info.height]
    # metric series, one value per frame the scoring scored
    ticks = per_topic["/clock"]
    assert rows["/metrics/control/forklift/cross_track_error"] == ticks
    assert rows["/metrics/safety/muted"] == ticks
    assert rows["/summary#static"] == 1
    # what the export says it logged is what Rerun reads
    assert {k: v for k, v in res.rows.items() if v} == {
        k: v for k, v in rows.items() if not k.endswith("#static")}
    # values: base_link's translation at a given time is the bag's
    bag_tf = [(t_ns, tf.transform.translation) for topic, _, t_ns, m in msgs if topic == "/tf"
              for tf in m.transforms if tf.child_frame_id == "base_link"]
    t_ns, want = bag_tf[len(bag_tf) * 2 // 3]
    got = dict(_column(batches["/tf/world/odom/base_link"], "Transform3D:translation"))
    assert got[t_ns][0] == pytest.approx([want.x, want.y, want.z], abs=1e-5)  # float32
    assert abs(want.x) > 0.5  # the forklift has moved: a value that could differ
    # the worker's ground truth position, and the raw image's pixels
    gt = [(t, m.transforms[0].transform.translation) for topic, _, t, m in msgs
          if topic == "/gt/character_0/tf"]
    w = dict(_column(batches["/tf/world/workers/character_0"], "Points3D:positions"))
    t_w, p = gt[-1]
    assert w[t_w][0] == pytest.approx([p.x, p.y, p.z], abs=1e-5)
    img = [(t, m) for topic, _, t, m in msgs if topic == "/dock_cam_left_rgb"][-1]
    buf = dict(_column(batches[f"{left}/dock_cam_left_rgb"], "Image:buffer"))
    assert bytes(buf[img[0]][0]) == bytes(img[1].data)
    depth = [(t, m) for topic, _, t, m in msgs if topic == "/dock_cam_left_depth"][-1]
    dbuf = dict(_column(batches[f"{left}/dock_cam_left_depth"], "DepthImage:buffer"))
    meter = dict(_column(batches[f"{left}/dock_cam_left_depth"], "DepthImage:meter"))
    assert bytes(dbuf[depth[0]][0]) == bytes(depth[1].data) and meter[depth[0]] == [1.0]
    # h264: the first sample is the stream's first access unit, byte for byte
    video = [(t, m) for topic, _, t, m in msgs if topic == "/dock_cam_left_rgb/h264"]
    samples = _column(batches[f"{left}/dock_cam_left_rgb/h264"], "VideoStream:sample")
    assert samples[0][0] == video[0][0] and bytes(samples[0][1][0]) == bytes(video[0][1].data)
    # a file Rerun reads as one recording of srr, named after the run
    (entry,) = _reader(rrd).recordings()
    assert "srr" in repr(entry)


def test_two_exports_of_a_run_hold_the_same_data_and_another_run_does_not(
        lidar: Path, tmp_path: Path) -> None:
    """Rerun's own comparison (``rerun rrd compare --unordered``, from the rerun-sdk wheel;
    Rerun may cut the data into chunks differently each time) of two exports
    of one run: equal; of another run's (another seed): not. The bytes differ (Rerun's chunk
    and row ids come from the wall clock), which the docs say."""
    rerun_cli = shutil.which("rerun", path=str(Path(sys.executable).parent))
    if rerun_cli is None:
        pytest.skip("the rerun command of rerun-sdk is not installed beside this Python")
    other = _run(tmp_path, "diffbot_urdf", "1", "--seed", "99")
    files = [tmp_path / f"{name}.rrd" for name in ("a", "b", "other")]
    for run, rrd in zip((lidar, lidar, other), files, strict=True):
        api.export_rerun(run, rrd)

    def compare(x: Path, y: Path) -> subprocess.CompletedProcess[str]:
        return subprocess.run([rerun_cli, "rrd", "compare", "--unordered", str(x), str(y)],
                              capture_output=True, text=True, timeout=120,
                              env={**os.environ, "RERUN_ANALYTICS": "0"})

    same = compare(files[0], files[1])
    assert same.returncode == 0, same.stdout + same.stderr
    assert compare(files[0], files[2]).returncode != 0


def test_a_lidar_scan_is_3d_points_in_its_frame(lidar: Path, tmp_path: Path) -> None:
    rrd = tmp_path / "lidar.rrd"
    assert main(["export", str(lidar), "--rerun", str(rrd)]) == 0
    rows, batches = _read(rrd)
    scan_entity = "/tf/world/odom/base_footprint/base_link/lidar_link/scan/scan"
    scans = [(t, m) for topic, _, t, m in decoded(lidar) if topic == "/scan"]
    assert rows[scan_entity] == len(scans) > 0
    t_ns, msg = scans[-1]
    r = np.asarray(msg.ranges)
    ok = np.isfinite(r) & (r >= msg.range_min) & (r <= msg.range_max)
    pts = dict(_column(batches[scan_entity], "Points3D:positions"))[t_ns]
    assert len(pts) == int(ok.sum()) > 0
    a = msg.angle_min + msg.angle_increment * np.flatnonzero(ok)[0]
    assert pts[0] == pytest.approx([r[ok][0] * np.cos(a), r[ok][0] * np.sin(a), 0.0],
                                   abs=1e-5)


def test_bad_input_is_one_line_exit_2_and_no_file(dock: Path, tmp_path: Path,
                                                  capsys: Any) -> None:
    rrd = tmp_path / "x.rrd"
    assert main(["export", str(tmp_path / "nowhere"), "--rerun", str(rrd)]) == 2
    assert "not a run directory" in capsys.readouterr().err
    # a bag cut in the middle: named, nothing written, the run left as it was
    broken = tmp_path / "broken"
    shutil.copytree(dock, broken)
    mcap = mcap_file(broken)
    mcap.write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    before = mcap.read_bytes()
    assert main(["export", str(broken), "--rerun", str(rrd)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "broken/bag" in err
    assert not rrd.exists() and list(tmp_path.glob("*.partial")) == []
    assert mcap.read_bytes() == before
    # rerun-sdk not installed: which extra to install, in a process where it cannot import
    proc = subprocess.run(
        [sys.executable, "-c", "import sys; sys.modules['rerun'] = None; "
         "from harness.cli import main; sys.exit(main(sys.argv[1:]))",
         "export", str(dock), "--rerun", str(rrd)],
        capture_output=True, text=True, check=False, cwd=Path(__file__).resolve().parents[2])
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "srr[rerun]" in proc.stderr
    assert not rrd.exists()


def _unwritable_folder(tmp_path: Path) -> Path:
    """A folder this process cannot create files in: a read-only one, or (root writes
    anywhere) ``/proc``."""
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        (ro / "probe").touch()
    except OSError:
        return ro
    (ro / "probe").unlink()
    if not Path("/proc/self").is_dir():
        pytest.skip("no folder this process cannot write to")
    return Path("/proc")


def test_a_folder_that_cannot_be_written_is_one_line_exit_2(lidar: Path, tmp_path: Path,
                                                            capsys: Any) -> None:
    folder = _unwritable_folder(tmp_path)
    rrd = folder / "x.rrd"
    assert main(["export", str(lidar), "--rerun", str(rrd)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--rerun {rrd}: cannot write" in err, err
    assert not rrd.exists() and not (folder / ".x.rrd.partial").exists()
