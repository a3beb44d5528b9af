"""Ground truth on /gt/*/tf: absent without srr_gt; with it, the true poses every tick."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness import api
from harness.builders.ground_truth import GRAPH_PATH
from harness.bus import Envelope
from harness.cli import main
from harness.engine import Simulation
from harness.geometry import (
    quat_wxyz_from_yaw,
    quat_wxyz_mul,
    quat_wxyz_rotate,
    xyzw_to_wxyz,
    yaw_from_quat_wxyz,
)
from tests.conftest import SCENARIOS
from tests.e2e.bagread import decoded

SCENARIO = SCENARIOS / "forklift_warehouse.yaml"
S = 1_000_000_000
# character_0 walks across the forklift's path, character_1 is disabled, "dana" is character_2
WORKERS = ("workers=[{route: [[-8, 2], [-8, -5]], speed: 1.0}, "
           "{route: [[0, 0], [1, 0]], enabled: false}, "
           "{name: dana, route: [[-10, 0], [-4, 0]], speed: 2.0, pause_s: 0.5}]")


def simulation(srr_gt: bool) -> Simulation:
    sc = api.load(SCENARIO, srr_gt=srr_gt, duration=2.0, overrides=[WORKERS])
    return Simulation(sc, source=str(SCENARIO))


def tf_of(msg: Any) -> tuple[np.ndarray, np.ndarray]:
    """(translation, wxyz) of a one-transform TFMessage."""
    (t,) = msg.transforms
    tr, q = t.transform.translation, t.transform.rotation
    return np.array([tr.x, tr.y, tr.z]), xyzw_to_wxyz([q.x, q.y, q.z, q.w])


def test_no_ground_truth_graph_or_topic_without_srr_gt() -> None:
    sim = simulation(srr_gt=False)
    assert GRAPH_PATH not in sim.graph_paths
    assert not sim.stage.has_graph(GRAPH_PATH)
    sim.run(5)
    assert not [t for t in sim.bus.topics() if t.startswith("/gt")]


def test_ground_truth_publishes_true_poses_every_tick() -> None:
    sim = simulation(srr_gt=True)
    assert GRAPH_PATH in sim.graph_paths
    seen: list[Envelope] = []
    sim.add_tap(seen.append)
    world = sim.world
    base = world.base_prim("forklift")
    chassis: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    people: dict[tuple[str, int], np.ndarray] = {}
    n = 90
    for k in range(n):
        t_ns = k * S // 60
        chassis[t_ns] = world.prim_pose(base)  # the state the graphs read during tick k
        sim.step_tick()
        for w in world.workers():  # physics does not move workers: still tick k's pose
            people[(w.frame, t_ns)] = world.prim_pose(w.prim)[0]

    by_topic: dict[str, list[Envelope]] = {}
    for env in seen:
        by_topic.setdefault(env.topic, []).append(env)
    assert {t for t in by_topic if t.startswith("/gt")} == {
        "/gt/forklift/tf", "/gt/character_0/tf", "/gt/character_2/tf"}
    for topic in ("/gt/forklift/tf", "/gt/character_0/tf", "/gt/character_2/tf"):
        assert len(by_topic[topic]) == n
        assert by_topic[topic][0].msgtype == "tf2_msgs/msg/TFMessage"

    # forklift: the chassis pose with robot_front (-X) turned onto +X, child frame = robot name
    for env in by_topic["/gt/forklift/tf"]:
        (t,) = env.msg.transforms
        stamp = t.header.stamp.sec * S + t.header.stamp.nanosec
        assert stamp == env.stamp_ns and (t.header.frame_id, t.child_frame_id) == (
            "world", "forklift")
        pos, q = tf_of(env.msg)
        cpos, cq = chassis[stamp]
        np.testing.assert_allclose(pos, cpos, atol=1e-12)
        np.testing.assert_allclose(q, quat_wxyz_mul(cq, quat_wxyz_from_yaw(math.pi)), atol=1e-12)
    first, last = (tf_of(by_topic["/gt/forklift/tf"][i].msg) for i in (0, -1))
    assert abs(yaw_from_quat_wxyz(first[1])) < 1e-6  # spawned at yaw 180°: ground truth faces +X
    travel = last[0] - first[0]
    assert travel[0] > 0.3  # the route follower drives it along +X ...
    assert abs(math.remainder(math.atan2(travel[1], travel[0]) - yaw_from_quat_wxyz(last[1]),
                              2 * math.pi)) < 0.15  # ... and ground truth faces that way

    # workers: their live pose, a pure function of time; frame character_<index>
    paths = {w.frame: w.path for w in world.workers()}
    for frame in ("character_0", "character_2"):
        for env in by_topic[f"/gt/{frame}/tf"]:
            (t,) = env.msg.transforms
            assert (t.header.frame_id, t.child_frame_id) == ("world", frame)
            pos, q = tf_of(env.msg)
            x, y, yaw = paths[frame].pose_at(env.stamp_ns)
            np.testing.assert_allclose(pos, [x, y, 0.0], atol=1e-12)
            np.testing.assert_allclose(pos, people[(frame, env.stamp_ns)], atol=1e-12)
            assert yaw_from_quat_wxyz(q) == pytest.approx(yaw, abs=1e-12)
    end = tf_of(by_topic["/gt/character_2/tf"][-1].msg)[0]
    assert end[0] == pytest.approx(-10.0 + 2.0 * (89 * S // 60) / S, abs=1e-12)


def test_ground_truth_equals_world_to_odom_composed_with_odometry() -> None:
    """Odometry and ground truth share the base convention, so they compare like with like."""
    sim = simulation(srr_gt=True)
    seen: list[Envelope] = []
    sim.add_tap(seen.append)
    sim.run(60)
    (static,) = [e for e in seen if e.topic == "/tf_static"]
    (w_odom,) = [t for t in static.msg.transforms if t.child_frame_id == "odom"]
    tr, rq = w_odom.transform.translation, w_odom.transform.rotation
    p0, q0 = np.array([tr.x, tr.y, tr.z]), xyzw_to_wxyz([rq.x, rq.y, rq.z, rq.w])
    odom = {e.stamp_ns: e.msg.pose.pose for e in seen if e.topic == "/odom"}
    gt = {e.stamp_ns: tf_of(e.msg) for e in seen if e.topic == "/gt/forklift/tf"}
    assert set(odom) == set(gt) and len(gt) == 60
    for stamp, pose in odom.items():
        o = pose.orientation
        pos = p0 + quat_wxyz_rotate(q0, [pose.position.x, pose.position.y, pose.position.z])
        q = quat_wxyz_mul(q0, xyzw_to_wxyz([o.x, o.y, o.z, o.w]))
        np.testing.assert_allclose(pos, gt[stamp][0], atol=1e-9)
        assert abs(np.dot(q, gt[stamp][1])) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.slow
def test_cli_run_with_srr_gt_records_ground_truth(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run"
    # 2 s is too short to reach the dock, so scoring would (rightly) regress: this test is
    # about what the ground-truth graph records, not about the drive.
    code = main(["run", str(SCENARIO), "--srr-gt", "--duration", "2", "--out", str(out), "-q",
                 "--set", WORKERS, "--set", "scoring.control=null"])
    printed = capsys.readouterr()
    assert code == 1, printed.err  # nothing scored: UNSCORED, not PASS
    assert "verdict: UNSCORED" in printed.out
    counts: dict[str, int] = {}
    children: set[tuple[str, str]] = set()
    for topic, schema, _, msg in decoded(out):
        counts[topic] = counts.get(topic, 0) + 1
        if topic.startswith("/gt/"):
            assert schema == "tf2_msgs/msg/TFMessage"
            children.add((topic, msg.transforms[0].child_frame_id))
    assert counts["/gt/forklift/tf"] == counts["/clock"] == 120
    assert counts["/gt/character_0/tf"] == counts["/gt/character_2/tf"] == 120
    assert children == {("/gt/forklift/tf", "forklift"), ("/gt/character_0/tf", "character_0"),
                        ("/gt/character_2/tf", "character_2")}
