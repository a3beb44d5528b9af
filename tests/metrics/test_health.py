"""Health gates: each one passes on good input and trips on the fault it exists for."""

from __future__ import annotations

import numpy as np
import pandas as pd

from harness.metrics.health import (
    OutputSpec,
    clock_monotonic,
    gt_not_frozen,
    health_gates,
    recorded_equals_published,
    sut_outputs_alive,
    tf_tree_gate,
    topic_rates,
)
from tests.metrics.helpers import gt_rows, make_frames, t_ns


def gate(results: list, name: str):
    (r,) = [r for r in results if r.name == name]
    return r


def topic_table(rows: list[tuple[str, int, int, int, int]]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=["name", "count", "first_ns", "last_ns", "max_gap_ns"]
                        ).assign(type="x")


def test_topic_rate_at_ninety_percent() -> None:
    topics = topic_table([("/odom", 180, 0, 0, 0), ("/scan", 13, 0, 0, 0)])
    res = topic_rates(topics, {"/odom": 60, "scan": 5, "/imu": 60}, duration_s=3.0)
    assert gate(res, "topic_rate:/odom").ok
    scan = gate(res, "topic_rate:/scan")  # 4.33 Hz < 4.5 Hz
    assert not scan.ok and "4.333 Hz" in scan.detail
    assert not gate(res, "topic_rate:/imu").ok  # never published
    assert gate(topic_rates(topics, {"/scan": 5}, duration_s=2.8), "topic_rate:/scan").ok


def test_recorded_equals_published() -> None:
    assert recorded_equals_published({"/a": 3, "/b": 1}, {"/a": 3, "b": 1})[0].ok
    bad = recorded_equals_published({"/a": 2}, {"/a": 3, "/c": 1})[0]
    assert not bad.ok
    assert "/a: published 3, recorded 2" in bad.detail and "/c: published 1" in bad.detail


def test_clock_strictly_monotonic() -> None:
    ok = pd.DataFrame({"t_ns": t_ns(np.arange(10))})
    assert clock_monotonic(ok)[0].ok
    repeated = pd.DataFrame({"t_ns": [0, 1, 1, 2]})
    assert not clock_monotonic(repeated)[0].ok
    backwards = pd.DataFrame({"t_ns": [0, 5, 3]})
    r = clock_monotonic(backwards)[0]
    assert not r.ok and "5 ns -> 3 ns" in r.detail
    assert not clock_monotonic(pd.DataFrame({"t_ns": []}))[0].ok


def test_ground_truth_frozen_missing_and_alive() -> None:
    ticks = np.arange(0, 60)
    frozen = gt_rows("forklift", ticks, np.full(60, -12.0), np.full(60, -3.0))
    moving = gt_rows("character_0", ticks, ticks * 0.02, np.zeros(60))
    parked = gt_rows("character_1", ticks, np.full(60, 3.0), np.zeros(60))
    g = pd.concat([frozen, moving, parked], ignore_index=True)
    res = gt_not_frozen(g, expected=["forklift", "character_0", "character_1", "character_2"],
                        odom_motion_m={"forklift": 4.0})
    assert not gate(res, "gt_not_frozen:forklift").ok
    assert "odometry travelled 4.000 m" in gate(res, "gt_not_frozen:forklift").detail
    assert gate(res, "gt_not_frozen:character_0").ok
    assert gate(res, "gt_not_frozen:character_1").ok  # standing still is allowed
    assert not gate(res, "gt_not_frozen:character_2").ok  # no messages at all
    still = gt_not_frozen(g, expected=["forklift"], odom_motion_m={"forklift": 0.01})
    assert gate(still, "gt_not_frozen:forklift").ok  # the robot did not move either
    walker = gt_not_frozen(g, expected=[], moving=["character_1"])
    assert not gate(walker, "gt_not_frozen:character_1").ok


def test_sut_outputs_alive() -> None:
    s = 1_000_000_000
    topics = topic_table([
        ("/cmd_vel", 600, 0, 30 * s - s // 20, s // 20),
        ("/late", 100, 5 * s, 30 * s, s // 10),
        ("/gappy", 100, 0, 30 * s, 4 * s),
        ("/died", 100, 0, 10 * s, s // 10),
    ])
    spec = OutputSpec(min_count=10, first_within_s=2.0, max_silence_s=1.0)
    res = sut_outputs_alive(topics, {t: spec for t in ("/cmd_vel", "/late", "/gappy",
                                                       "/died", "/never")},
                            start_ns=0, end_ns=30 * s)
    assert gate(res, "sut_output_alive:/cmd_vel").ok
    assert "first message at 5.000 s" in gate(res, "sut_output_alive:/late").detail
    assert "silent for 4.000 s between" in gate(res, "sut_output_alive:/gappy").detail
    assert "silent for the last 20.000 s" in gate(res, "sut_output_alive:/died").detail
    assert not gate(res, "sut_output_alive:/never").ok
    assert [r.ok for r in res].count(True) == 1


def test_health_gates_on_frames() -> None:
    ticks = np.arange(0, 120)
    clock = pd.DataFrame({"t_ns": t_ns(ticks), "log_ns": t_ns(ticks)})
    odom = pd.DataFrame({"t_ns": t_ns(ticks), "topic": "/odom", "frame": "world",
                         "x": ticks * 0.05, "y": 0.0, "yaw": 0.0, "vx": 3.0, "wz": 0.0})
    gt = gt_rows("forklift", ticks, np.zeros(120), np.zeros(120))  # frozen while moving
    topics = topic_table([("/clock", 120, 0, int(t_ns(119)), int(t_ns(1))),
                          ("/cmd_vel", 40, 0, int(t_ns(117)), int(t_ns(3)))])
    frames = make_frames(clock=clock, odom=odom, gt_poses=gt, topics=topics)
    res = health_gates(frames, expected_hz={"/clock": 60, "/cmd_vel": 20},
                       published={"/clock": 120, "/cmd_vel": 40}, gt_expected=["forklift"],
                       robots={"forklift": "/odom"},
                       outputs={"/cmd_vel": OutputSpec(max_silence_s=0.2)})
    names = {r.name: r.ok for r in res}
    assert names == {"topic_rate:/clock": True, "topic_rate:/cmd_vel": True,
                     "recorded_equals_published": True, "clock_monotonic": True,
                     "gt_not_frozen:forklift": False, "sut_output_alive:/cmd_vel": True}
    assert health_gates(frames) == clock_monotonic(clock)  # nothing configured: clock only


def _tf_rows(rows: list[tuple[str, str, str, int]], **pose: float) -> pd.DataFrame:
    """(topic, parent, child, tick) → the frames' ``tf`` table."""
    topic = [r[0] for r in rows]
    return pd.DataFrame({
        "t_ns": [int(t_ns(r[3])) for r in rows], "log_ns": [int(t_ns(r[3])) for r in rows],
        "topic": topic, "tree": ["/" if t.count("/") == 1 else t.rsplit("/", 1)[0]
                                 for t in topic],
        "static": [t.endswith("tf_static") for t in topic],
        "parent": [r[1] for r in rows], "child": [r[2] for r in rows],
        **{k: [pose.get(k, 1.0 if k == "qw" else 0.0)] * len(rows)
           for k in ("x", "y", "z", "qx", "qy", "qz", "qw")}})


def test_tf_gate_passes_one_tree_and_names_its_root() -> None:
    rows = [("/tf_static", "world", "a/odom", 0)] + [
        ("/tf", "a/odom", "a/base_link", k) for k in range(5)]
    (g,) = tf_tree_gate(_tf_rows(rows))
    assert g.ok and g.name == "tf_tree"
    assert g.detail == "3 frames, one parent each; root: world"


def test_tf_gate_trips_on_a_second_parent_published_at_run_time() -> None:
    rows = [("/tf_static", "world", "odom", 0), ("/tf", "odom", "base_link", 0),
            ("/tf", "map", "base_link", 1)]
    (g,) = tf_tree_gate(_tf_rows(rows))
    assert not g.ok
    assert "frame 'base_link' has 2 parents: 'map' from /tf; 'odom' from /tf" in g.detail


def test_tf_gate_trips_on_two_sources_with_one_stamp() -> None:
    rows = [("/tf", "odom", "base_link", k) for k in range(3)] * 2
    (g,) = tf_tree_gate(_tf_rows(rows))
    assert not g.ok
    assert "frame 'base_link' published 2 times with the same stamp at 3 time(s)" in g.detail


def test_tf_gate_trips_on_conflicting_static_transforms() -> None:
    a = _tf_rows([("/tf_static", "world", "odom", 0)], x=1.0)
    b = _tf_rows([("/tf_static", "world", "odom", 0)], x=2.0)
    (g,) = tf_tree_gate(pd.concat([a, b], ignore_index=True))
    assert not g.ok and "static frame 'odom' was given 2 different transforms" in g.detail
    # float noise below a micrometre is the same transform
    c = _tf_rows([("/tf_static", "world", "odom", 0)], x=1.0 + 1e-9)
    (g,) = tf_tree_gate(pd.concat([a, c], ignore_index=True))
    assert g.ok


def test_tf_gate_checks_each_namespace_tree_apart() -> None:
    rows = [("/tf", "odom", "base_link", 0), ("/r2/tf", "odom", "base_link", 0)]
    gates = tf_tree_gate(_tf_rows(rows))
    assert [(g.name, g.ok) for g in gates] == [("tf_tree", True), ("tf_tree:/r2", True)]
    assert tf_tree_gate(_tf_rows([])) == []


def test_tf_tree_gate_memory_stays_below_the_table_it_checks() -> None:
    """A long run's ``/tf`` table has hundreds of thousands of rows and grows with the run:
    checking it works on the frames' one-byte category codes, never on a copy of the table's
    size (with 64-bit codes it took 1.14 × the table; peak memory grew with run length)."""
    import tracemalloc

    n = 200_000
    stamps = np.repeat(np.arange(n // 4, dtype=np.int64) * 10_000_000, 4)
    tf = pd.DataFrame({
        "t_ns": stamps, "log_ns": stamps,
        "topic": pd.Categorical(np.full(n, "/tf", dtype=object)),
        "tree": pd.Categorical(np.full(n, "/", dtype=object)),
        "static": np.zeros(n, bool),
        "parent": pd.Categorical(np.where(np.arange(n) % 4 == 0, "odom", "base_link")
                                 .astype(object)),
        "child": pd.Categorical(np.tile(np.array(["base_link", "lidar", "camera", "wheel"],
                                                 dtype=object), n // 4)),
        **{k: np.zeros(n) for k in ("x", "y", "z", "qx", "qy", "qz")}, "qw": np.ones(n)})
    tracemalloc.start()
    try:
        (gate,) = tf_tree_gate(tf)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert gate.ok and gate.detail.startswith("5 frames, one parent each"), gate
    assert peak < 0.8 * tf.memory_usage(deep=True).sum()
