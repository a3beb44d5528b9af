"""The bundled forklift scenario end to end: bag contents, route completion, determinism."""

from __future__ import annotations

import itertools
import json
import math
from collections import Counter
from pathlib import Path

import pytest
import yaml

from harness import api
from harness.cli import main
from tests.conftest import SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def run(module_tmp: ModuleTmp) -> api.RunResult:
    path = SCENARIOS / "forklift_warehouse.yaml"
    sc = api.load(path)
    return api.run_scenario(sc, source=str(path), out=module_tmp("run") / "r")


def test_run_directory_follows_the_contract(run: api.RunResult) -> None:
    names = {p.name for p in run.run_dir.iterdir()}
    assert {"scenario.yaml", "bag", "summary.json", "junit.xml"} <= names
    meta = yaml.safe_load((run.run_dir / "bag" / "metadata.yaml").read_text())
    info = meta["rosbag2_bagfile_information"]
    assert info["storage_identifier"] == "mcap" and info["version"] == 9
    assert len(info["relative_file_paths"]) == 1
    resolved = yaml.safe_load((run.run_dir / "scenario.yaml").read_text())
    assert resolved["robots"][0]["control"]["wheelbase"] == 1.49  # include expanded
    summary = json.loads((run.run_dir / "summary.json").read_text())
    assert summary["verdict"] == "PASS" and summary["seed"] == 7


def test_every_message_decodes_with_an_independent_reader(run: api.RunResult) -> None:
    counts: Counter[str] = Counter()
    last_clock = -1
    for topic, _schema, log_ns, msg in decoded(run.run_dir):
        counts[topic] += 1
        if topic == "/clock":
            ns = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec
            assert ns == log_ns and ns > last_clock
            last_clock = ns
        if topic == "/odom":
            assert msg.header.frame_id == "odom" and msg.child_frame_id == "base_link"
    summary = run.summary
    assert dict(counts) == {t: v["count"] for t, v in summary["topics"].items()}
    assert {"/clock", "/tf", "/tf_static", "/odom", "/cmd_vel"} <= set(counts)
    ticks = summary["ticks"]
    assert counts["/clock"] == counts["/odom"] == counts["/tf"] == ticks == 35 * 60
    assert counts["/cmd_vel"] == ticks // 3  # 20 Hz follower on a 60 Hz tick


def test_recorded_equals_published_and_tf_static_is_transient_local(run: api.RunResult) -> None:
    (check,) = [h for h in run.summary["health"] if h["name"] == "recorded_equals_published"]
    assert check["ok"]
    for topic in run.summary["topics"].values():
        assert topic["count"] == topic["published"]
    meta = yaml.safe_load((run.run_dir / "bag" / "metadata.yaml").read_text())
    qos = {t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"]
           for t in meta["rosbag2_bagfile_information"]["topics_with_message_count"]}
    assert "transient_local" in str(qos["/tf_static"])
    assert "transient_local" not in str(qos["/tf"])


def test_forklift_reaches_the_end_of_its_route(run: api.RunResult) -> None:
    """Odometry, moved into the world by the recorded world → odom transform, ends at the
    route's last waypoint; the forklift was driven only through cmd_vel."""
    world_odom = None
    odom = []
    for topic, _, _, msg in decoded(run.run_dir):
        if topic == "/tf_static":
            (tf,) = [t for t in msg.transforms if t.child_frame_id == "odom"]
            world_odom = tf.transform
        elif topic == "/odom":
            odom.append(msg.pose.pose.position)
    assert world_odom is not None
    q = world_odom.rotation
    yaw = 2 * math.atan2(q.z, q.w)
    end = odom[-1]
    wx = world_odom.translation.x + math.cos(yaw) * end.x - math.sin(yaw) * end.y
    wy = world_odom.translation.y + math.sin(yaw) * end.x + math.cos(yaw) * end.y
    assert math.hypot(wx - 21.0, wy - 0.0) < 0.5, (wx, wy)
    travelled = sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in itertools.pairwise(odom))
    assert 32.0 < travelled < 36.0  # route length is 33.7 m


def test_three_runs_give_identical_digests(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    from tests.conftest import SCENARIOS

    code = main(["run", str(SCENARIOS / "forklift_warehouse.yaml"), "--repeat", "3",
                 "--out", str(tmp_path), "-q"])
    out = capsys.readouterr().out
    assert code == 0, out
    report = json.loads((tmp_path / "determinism.json").read_text())
    assert report["identical"] and len(set(report["digests"])) == 1
    assert "identical per-topic digests across 3 runs" in out


def test_ctrl_c_in_a_repeat_stops_the_series(tmp_path: Path) -> None:
    """Ctrl-C in the second of three runs ends that run INTERRUPTED and starts no third; the
    cut-short recording is no evidence against determinism (exit 130, not 'digests DIFFER')."""
    from tests.conftest import SCENARIOS

    sc = api.load(SCENARIOS / "forklift_warehouse.yaml", duration=1.0)
    seen = {"ticks": 0}

    def press_ctrl_c(done: int, total: int) -> None:
        seen["ticks"] += 1
        if seen["ticks"] == total + 20:  # tick 20 of the second run
            raise KeyboardInterrupt

    rep = api.run_repeat(sc, 3, out=tmp_path, progress=press_ctrl_c)
    assert [r.verdict for r in rep.runs][1:] == ["INTERRUPTED"] and len(rep.runs) == 2
    assert not (tmp_path / "run_3").exists()
    assert (rep.interrupted, rep.identical, rep.exit_code) == (True, True, 130)
    report = json.loads((tmp_path / "determinism.json").read_text())
    assert report["interrupted"] and report["differing_topics"] == []


def test_different_seed_or_physics_changes_digests(run: api.RunResult, tmp_path: Path) -> None:
    """The digest comparison can fail: a changed wheelbase changes the recorded motion."""
    from tests.conftest import SCENARIOS

    sc = api.load(SCENARIOS / "forklift_warehouse.yaml", duration=5.0,
                  overrides=["robots.forklift.control.wheelbase=1.3"])
    other = api.run_scenario(sc, out=tmp_path / "o")
    assert other.summary["topics"]["/odom"]["sha256"] != run.summary["topics"]["/odom"]["sha256"]
    assert other.summary["topics"]["/clock"]["count"] == 300
