"""Several robots in one scene, correct by default.

* The bundled ``two_forklifts`` scene (a second forklift with default settings, added with
  ``robots+``): each robot gets its own namespace and frame prefix, each follower drives its
  own robot to the end of its route, the recorded TF is one tree under ``world`` (our own
  checks, and a real tf2 buffer), and both robots are scored against the blessed baseline; a
  slower driver of the second robot regresses that robot's metrics only.
* A forklift and a TurtleBot3 with defaults both work.
* A transform that conflicts with the tree at run time makes the run INVALID.
* A system under test in a namespace, with a remapping, drives a robot at the root.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from harness import api
from harness.errors import ScenarioError
from harness.scenario import scenario_from_mapping
from harness.wiring import Edge, roots, tree_problems
from tests.conftest import SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded
from tests.tf2check import tf2_accepts

pytestmark = pytest.mark.slow

TWO = SCENARIOS / "two_forklifts.yaml"


def metrics(res: api.RunResult) -> dict[str, Any]:
    return {m["name"]: m["value"] for m in res.summary["metrics"]}


def tf_edges(run_dir: Path) -> set[tuple[str, str, str]]:
    """(topic, parent, child) of every recorded transform on /tf and /tf_static."""
    return {(topic, t.header.frame_id, t.child_frame_id)
            for topic, _, _, msg in decoded(run_dir) if topic in ("/tf", "/tf_static")
            for t in msg.transforms}


@pytest.fixture(scope="module")
def fleet(module_tmp: ModuleTmp) -> api.RunResult:
    out = module_tmp("two_forklifts") / "run"
    return api.run_scenario(api.load(TWO), source=str(TWO), out=out)


def test_each_follower_drives_its_own_forklift_to_the_end_of_its_route(
        fleet: api.RunResult) -> None:
    m = metrics(fleet)
    for robot in ("forklift", "forklift_b"):
        assert m[f"control.{robot}.goal_reached"] == 1.0
        assert m[f"control.{robot}.goal_distance_final"] < 0.5
        assert m[f"control.{robot}.cross_track_error.max"] < 0.5
        assert m[f"control.{robot}.odom_drift.max"] < 1e-6  # defined for prefixed frames
    assert m["control.forklift.distance_travelled"] == pytest.approx(33.6, abs=0.3)
    assert m["control.forklift_b.distance_travelled"] == pytest.approx(19.9, abs=0.3)
    # the robots pass each other: robot-robot clearance counts, and it is the same pair
    assert 0.3 < m["control.forklift.min_clearance"] < 1.0
    assert m["control.forklift.min_clearance"] == m["control.forklift_b.min_clearance"]
    topics = set(fleet.summary["topics"])
    assert {"/forklift/cmd_vel", "/forklift/odom", "/forklift_b/cmd_vel",
            "/forklift_b/odom"} <= topics
    assert not {"/cmd_vel", "/odom"} & topics  # nothing shared at the root
    assert fleet.summary["warnings"] == []


def test_both_robots_are_scored_against_the_blessed_baseline(fleet: api.RunResult) -> None:
    assert (fleet.verdict, fleet.exit_code) == ("PASS", 0)
    cmp = fleet.summary["comparison"]
    per_robot = {e["name"].split(".")[1] for e in cmp}
    assert per_robot == {"forklift", "forklift_b"}
    assert len(cmp) == 30 and {e["status"] for e in cmp} == {"ok"}
    health = {h["name"]: h for h in fleet.summary["health"]}
    assert health["tf_tree"]["ok"] and health["tf_tree"]["detail"] == (
        "5 frames, one parent each; root: world")


def test_the_recorded_tf_is_one_tree_with_disjoint_robot_branches(fleet: api.RunResult) -> None:
    edges = tf_edges(fleet.run_dir)
    assert edges == {
        ("/tf_static", "world", "forklift/odom"), ("/tf", "forklift/odom", "forklift/base_link"),
        ("/tf_static", "world", "forklift_b/odom"),
        ("/tf", "forklift_b/odom", "forklift_b/base_link")}
    plain = [Edge(p, c, topic == "/tf_static", topic) for topic, p, c in edges]
    assert tree_problems(plain) == [] and roots(plain) == ["world"]
    for robot in ("forklift", "forklift_b"):  # odometry names its own prefixed frames
        odom = next(msg for topic, _, _, msg in decoded(fleet.run_dir)
                    if topic == f"/{robot}/odom")
        assert (odom.header.frame_id, odom.child_frame_id) == (f"{robot}/odom",
                                                               f"{robot}/base_link")


def test_a_real_tf2_buffer_accepts_the_recorded_tree(fleet: api.RunResult) -> None:
    res = tf2_accepts(fleet.run_dir)
    assert res.errors == [] and res.warnings == []
    parents = {f: v["parent"] for f, v in res.frames.items()}
    assert parents == {"forklift/odom": "world", "forklift/base_link": "forklift/odom",
                       "forklift_b/odom": "world", "forklift_b/base_link": "forklift_b/odom"}
    assert all(v["found"] for v in res.frames.values()), res.frames
    # tf2's world → base_link at the end is where ground truth put each robot
    last_gt = {}
    for topic, _, _, msg in decoded(fleet.run_dir):
        if topic.startswith("/gt/"):
            t = msg.transforms[0].transform.translation
            last_gt[topic.split("/")[2]] = (t.x, t.y)
    for robot in ("forklift", "forklift_b"):
        x, y, _ = res.frames[f"{robot}/base_link"]["xyz"]
        assert (x, y) == pytest.approx(last_gt[robot], abs=1e-6)


def test_a_slower_second_driver_regresses_that_robot_only(tmp_path: Path) -> None:
    sc = api.load(TWO, overrides=["systems_under_test.follower_b.params.speed=0.5"])
    res = api.run_scenario(sc, source=str(TWO), out=tmp_path / "run")
    assert (res.verdict, res.exit_code) == ("REGRESSED", 1)
    regressed = {e["name"] for e in res.summary["comparison"] if e["status"] == "regressed"}
    assert "control.forklift_b.time_to_goal" in regressed
    assert all(name.startswith("control.forklift_b.") for name in regressed), regressed


MIXED = {
    "format_version": 1, "name": "mixed_fleet", "seed": 2, "duration": 12.0, "srr_gt": True,
    "robots": [
        {"name": "forklift", "model": "forklift",
         "spawn": {"position": [-12.0, -3.0, 0.0], "rpy_deg": [0.0, 0.0, 180.0]},
         "odometry": {"robot_front": [-1.0, 0.0, 0.0]}},
        {"name": "turtlebot3", "model": "turtlebot3_waffle_pi",
         "spawn": {"position": [-12.0, 3.0, 0.0]}},
    ],
    "routes": {"lift": {"waypoints": [[-12.0, -3.0], [-4.0, -3.0]]},
               "tb3": {"waypoints": [[-12.0, 3.0], [-10.0, 3.0]]}},
    "systems_under_test": [
        {"name": "lift_driver", "robot": "forklift",
         "plugin": "harness.sut.route_follower:RouteFollower",
         "params": {"route": "lift", "speed": 1.2}},
        {"name": "tb3_driver", "robot": "turtlebot3",
         "plugin": "harness.sut.route_follower:RouteFollower",
         "params": {"route": "tb3", "speed": 0.22, "lookahead": 0.5, "goal_tolerance": 0.1,
                    "slow_radius": 0.5}},
    ],
    "scoring": {"control": [{"robot": "forklift", "route": "lift", "goal_tolerance": 0.3},
                            {"robot": "turtlebot3", "route": "tb3", "goal_tolerance": 0.15}]},
}


def test_a_forklift_and_a_turtlebot3_with_defaults_both_work(tmp_path: Path) -> None:
    sc = scenario_from_mapping(MIXED)
    assert api.validate(sc) == ()
    res = api.run_scenario(sc, out=tmp_path / "run")
    m = metrics(res)
    assert m["control.forklift.goal_reached"] == m["control.turtlebot3.goal_reached"] == 1.0
    assert m["control.turtlebot3.goal_distance_final"] < 0.15
    assert res.summary["health"] and all(h["ok"] for h in res.summary["health"])
    edges = {(p, c) for _, p, c in tf_edges(res.run_dir)}
    assert {("world", "forklift/odom"), ("forklift/odom", "forklift/base_link"),
            ("world", "turtlebot3/odom"), ("turtlebot3/odom", "turtlebot3/base_footprint"),
            ("turtlebot3/base_footprint", "turtlebot3/base_link"),
            ("turtlebot3/base_link", "turtlebot3/wheel_left_link")} <= edges
    assert all(c.startswith(("forklift/", "turtlebot3/")) for _, c in edges)
    tf2 = tf2_accepts(res.run_dir)
    assert tf2.errors == [] and tf2.warnings == []
    assert all(v["found"] for v in tf2.frames.values()), tf2.frames
    assert tf2.frames["turtlebot3/base_link"]["parent"] == "turtlebot3/base_footprint"
    assert res.verdict == "FAIL"  # both drove fine, but there is no baseline: said plainly
    assert any("no baseline" in r for r in res.summary["reasons"])


def test_a_conflicting_transform_at_run_time_makes_the_run_invalid(tmp_path: Path) -> None:
    sc = api.load(SCENARIOS / "forklift_warehouse.yaml", duration=2.0, overrides=[
        'systems_under_test=[{name: follower, plugin: "harness.sut.route_follower:'
        'RouteFollower", params: {route: dock_approach}}, {name: rogue, robot: forklift, '
        'plugin: "tests.wiring.plugins:RogueTransform"}]'])
    res = api.run_scenario(sc, source="forklift_warehouse.yaml", out=tmp_path / "run")
    assert (res.verdict, res.exit_code) == ("INVALID", 3)
    gate = next(h for h in res.summary["health"] if h["name"] == "tf_tree")
    assert not gate["ok"]
    assert "frame 'base_link' has 2 parents: 'map' from /tf; 'odom' from /tf" in gate["detail"]
    assert any("tf_tree" in r and "'base_link'" in r for r in res.summary["reasons"])


def test_a_namespaced_system_under_test_remaps_onto_a_root_robot(tmp_path: Path) -> None:
    """One robot (root names); the follower lives in /fleet and is remapped onto them."""
    sc = api.load(SCENARIOS / "forklift_warehouse.yaml", duration=3.0, overrides=[
        "systems_under_test.route_follower.namespace=fleet",
        "systems_under_test.route_follower.remap={odom: /odom, cmd_vel: /cmd_vel}"])
    assert api.validate(sc, "forklift_warehouse.yaml") == ()
    res = api.run_scenario(sc, source="forklift_warehouse.yaml", out=tmp_path / "run")
    assert res.summary["topics"]["/cmd_vel"]["count"] == 60
    assert metrics(res)["control.distance_travelled"] > 1.0  # the robot was driven
    # without the remapping the follower talks to /fleet/*: caught before running
    bad = api.load(SCENARIOS / "forklift_warehouse.yaml", overrides=[
        "systems_under_test.route_follower.namespace=fleet"])
    with pytest.raises(ScenarioError) as info:
        api.validate(bad, "forklift_warehouse.yaml")
    assert info.value.field == "robots[0].control.cmd_vel_topic"
    assert "published: /fleet/cmd_vel" in str(info.value)
