"""Perception metrics: known answers, and agreement with py-motmetrics on random data."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from harness.errors import SrrError
from harness.metrics.perception import assign, clear_mot, perception_metrics
from tests.metrics.helpers import gt_rows, make_frames, t_ns

ROOT = Path(__file__).resolve().parents[2]


def table(rows: list[tuple[int, object, float, float]], id_col: str) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=["frame", id_col, "x", "y"])


def test_known_id_switch() -> None:
    """One object, tracked as 7 for 5 frames then as 9: one ID switch, IDF1 5/10."""
    gt = table([(f, "a", float(f), 0.0) for f in range(10)], "oid")
    hyp = table([(f, 7 if f < 5 else 9, f + 0.1, 0.0) for f in range(10)], "hid")
    r = clear_mot(gt, hyp, gate=1.0)
    assert (r.tp, r.fp, r.fn, r.id_switches) == (10, 0, 0, 1)
    assert r.mota == pytest.approx(1 - 1 / 10)
    assert r.idtp == 5 and r.idf1 == pytest.approx(2 * 5 / 20)
    assert r.errors == pytest.approx([0.1] * 10)


def test_switch_back_counts_again_and_kept_match_wins_over_a_closer_track() -> None:
    gt = table([(f, "a", 0.0, 0.0) for f in range(4)], "oid")
    # frame 1: track 2 is closer, but track 1 (the previous match) is still within the gate
    hyp = table([(0, 1, 0.5, 0.0), (1, 1, 0.6, 0.0), (1, 2, 0.1, 0.0), (2, 2, 0.1, 0.0),
                 (3, 1, 0.2, 0.0)], "hid")
    r = clear_mot(gt, hyp, gate=1.0)
    assert r.id_switches == 2  # 1 → 2 at frame 2, 2 → 1 at frame 3
    assert r.errors.tolist() == pytest.approx([0.5, 0.6, 0.1, 0.2])  # frame 1 kept track 1
    assert (r.tp, r.fp, r.fn) == (4, 1, 0)


def test_gate_is_inclusive_and_misses_and_false_positives_count() -> None:
    gt = table([(0, "a", 0.0, 0.0), (0, "b", 10.0, 0.0), (1, "a", 0.0, 0.0)], "oid")
    hyp = table([(0, 1, 1.0, 0.0), (0, 2, 20.0, 0.0), (1, 1, 1.0000001, 0.0)], "hid")
    r = clear_mot(gt, hyp, gate=1.0)
    assert (r.objects, r.tracks, r.tp, r.fn, r.fp) == (3, 3, 1, 2, 2)
    assert r.precision == pytest.approx(1 / 3) and r.recall == pytest.approx(1 / 3)


def random_world(seed: int, n_frames: int = 100, n_obj: int = 7
                 ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Objects random-walking close to each other; tracks with noise, misses, clutter, id
    swaps and re-identifications, so that every branch of the matching is exercised."""
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0, 4, (n_obj, 2))
    track_of = list(range(n_obj))
    next_id = 100
    g_rows, h_rows = [], []
    for f in range(n_frames):
        pos += rng.normal(0, 0.15, pos.shape)
        present = rng.random(n_obj) > 0.1
        if rng.random() < 0.08:  # two tracks swap identities
            i, j = rng.choice(n_obj, 2, replace=False)
            track_of[i], track_of[j] = track_of[j], track_of[i]
        if rng.random() < 0.05:  # a track is re-born with a new id
            track_of[int(rng.integers(n_obj))] = next_id
            next_id += 1
        for o in range(n_obj):
            if not present[o]:
                continue
            g_rows.append((f, o, *pos[o]))
            if rng.random() < 0.85:
                h_rows.append((f, track_of[o], *(pos[o] + rng.normal(0, 0.4, 2))))
        for _ in range(rng.poisson(0.7)):
            h_rows.append((f, int(rng.integers(500, 505)), *rng.uniform(0, 4, 2)))
    return table(g_rows, "oid"), table(h_rows, "hid")


def motmetrics_summary(gt: pd.DataFrame, hyp: pd.DataFrame, gate: float) -> pd.Series:
    motmetrics = pytest.importorskip("motmetrics")  # the dev extra installs it
    acc = motmetrics.MOTAccumulator(auto_id=False)
    gt_of = dict(list(gt.sort_values("oid", kind="stable").groupby("frame")))
    hyp_of = dict(list(hyp.sort_values("hid", kind="stable").groupby("frame")))
    empty = gt.iloc[:0]
    for f in sorted(set(gt_of) | set(hyp_of)):
        g, h = gt_of.get(f, empty), hyp_of.get(f, empty.rename(columns={"oid": "hid"}))
        gp, hp = g[["x", "y"]].to_numpy(), h[["x", "y"]].to_numpy()
        d = np.hypot(gp[:, None, 0] - hp[None, :, 0], gp[:, None, 1] - hp[None, :, 1])
        d = np.where(d <= gate, d, np.nan)  # Euclidean distance, inclusive gate
        acc.update(g["oid"].tolist(), h["hid"].tolist(), d, frameid=int(f))
    mh = motmetrics.metrics.create()
    return mh.compute(acc, metrics=["mota", "idf1", "idtp", "num_switches",
                                    "num_false_positives", "num_misses", "num_objects",
                                    "num_predictions", "precision", "recall"],
                      name="run").iloc[0]


@pytest.mark.parametrize(("seed", "gate"), [(0, 1.0), (1, 1.0), (2, 0.5)])
def test_mota_and_idf1_agree_with_motmetrics(seed: int, gate: float) -> None:
    gt, hyp = random_world(seed)
    ours = clear_mot(gt, hyp, gate=gate)
    ref = motmetrics_summary(gt, hyp, gate)
    assert ours.id_switches > 0 and ours.fp > 0 and ours.fn > 0  # the data exercises them
    assert ours.objects == ref["num_objects"] and ours.tracks == ref["num_predictions"]
    assert ours.id_switches == ref["num_switches"]
    assert ours.fp == ref["num_false_positives"] and ours.fn == ref["num_misses"]
    assert ours.idtp == ref["idtp"]
    assert abs(ours.mota - ref["mota"]) < 1e-9
    assert abs(ours.idf1 - ref["idf1"]) < 1e-9
    assert abs(ours.precision - ref["precision"]) < 1e-9
    assert abs(ours.recall - ref["recall"]) < 1e-9


@pytest.mark.slow
def test_scoring_imports_the_assignment_solver_only_when_it_matches() -> None:
    """Importing scipy.optimize takes ~0.5 s: a run whose frames never need an assignment
    (no tracks) does not pay it; the first assignment imports it."""
    code = (
        "import sys, numpy as np\n"
        "import harness.metrics.perception as p\n"
        "import harness.frames, harness.metrics.control, harness.metrics.safety\n"
        "before = 'scipy.optimize' in sys.modules\n"
        "pairs = p.assign(np.array([[1.0, 0.0], [0.0, 1.0]]))\n"
        "print(before, 'scipy.optimize' in sys.modules, pairs)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT).stdout.strip().split(maxsplit=2)
    assert out == ["False", "True", "[(0, 1), (1, 0)]"]


def test_assign_prefers_more_pairs_over_cheaper_ones() -> None:
    nan = np.nan
    cost = np.array([[0.1, 0.9], [0.2, nan]])  # (0,0) alone is cheapest; two pairs exist
    assert assign(cost) == [(0, 1), (1, 0)]
    assert assign(np.full((2, 2), nan)) == []


# --------------------------------------------------------------------------- on Frames


def person_frames(offset_ns: int = 0, extra_topic: bool = False):
    """Two workers, 30 Hz tracker, gt at 60 Hz; worker 1 tracked 0.3 m off, worker 0 exact;
    track ids of worker 0 change half-way; the tracker's stamps are shifted by offset_ns."""
    ticks = np.arange(0, 120)
    gt = pd.concat([
        gt_rows("character_0", ticks, ticks * 0.01, np.zeros(120)),
        gt_rows("character_1", ticks, np.full(120, 5.0), np.full(120, 5.0)),
        gt_rows("forklift", ticks, np.full(120, -5.0), np.zeros(120)),
    ], ignore_index=True)
    tf_rows, tr_rows = [], []
    for n, k in enumerate(range(0, 120, 2)):
        stamp = int(t_ns(k)) + offset_ns
        tf_rows.append((n, stamp, stamp, "/tracks"))
        tr_rows.append((n, stamp, "/tracks", "person", 1 if k < 60 else 2, k * 0.01, 0.0))
        tr_rows.append((n, stamp, "/tracks", "person", 5, 5.3, 5.0))
        tr_rows.append((n, stamp, "/tracks", "forklift", 3, -5.0, 0.0))  # other class
    track_frames = pd.DataFrame(tf_rows, columns=["frame", "t_ns", "log_ns", "topic"])
    tracks = pd.DataFrame(tr_rows, columns=["frame", "t_ns", "topic", "cls", "track_id",
                                            "x", "y"])
    if extra_topic:
        track_frames = pd.concat([track_frames, pd.DataFrame(
            [(999, 0, 0, "/other")], columns=track_frames.columns)], ignore_index=True)
    return make_frames(gt_poses=gt, track_frames=track_frames, tracks=tracks)


def by_name(results: list) -> dict:
    return {r.name: r for r in results}


def test_perception_metrics_on_frames() -> None:
    r = by_name(perception_metrics(person_frames()))
    assert r["perception.precision"].value == 1.0 and r["perception.recall"].value == 1.0
    assert r["perception.id_switches"].value == 1
    assert r["perception.mota"].value == pytest.approx(1 - 1 / 120)
    assert r["perception.idf1"].value == pytest.approx(2 * 90 / 240)
    assert r["perception.position_error.mean"].value == pytest.approx(0.15)
    assert r["perception.position_error.median"].value == pytest.approx(0.15)
    assert r["perception.position_error.p95"].value == pytest.approx(0.3)
    assert r["perception.recall_at_0_5m"].value == 1.0
    assert r["perception.recall_at_gate"].value == 1.0
    assert r["perception.mota"].direction == "higher" and r["perception.mota"].unit == "ratio"
    assert r["perception.position_error.p95"].direction == "lower"
    tight = by_name(perception_metrics(person_frames(), gate=0.2, recall_radii=(0.1,)))
    assert tight["perception.recall"].value == pytest.approx(0.5)
    assert tight["perception.recall_at_0_1m"].value == pytest.approx(0.5)
    forks = by_name(perception_metrics(person_frames(), cls="forklift", gt_prefix="forklift",
                                       prefix="perception.forklift"))
    assert forks["perception.forklift.recall"].value == 1.0


def test_time_alignment_within_half_a_tick() -> None:
    ok = by_name(perception_metrics(person_frames(offset_ns=5_000_000)))
    assert ok["perception.recall"].value == 1.0
    assert "60 of 60 frames scored" in ok["perception.recall"].detail
    # with a 3 ms tolerance, 5 ms off every gt stamp: nothing is scored
    off = by_name(perception_metrics(person_frames(offset_ns=5_000_000),
                                     time_tolerance_ns=3_000_000))
    assert "0 of 60 frames scored" in off["perception.recall"].detail
    assert off["perception.recall"].value is None


def test_several_marker_topics_need_a_choice() -> None:
    with pytest.raises(SrrError, match="topic="):
        perception_metrics(person_frames(extra_topic=True))
    r = by_name(perception_metrics(person_frames(extra_topic=True), topic="/tracks"))
    assert r["perception.recall"].value == 1.0


def test_no_ground_truth_gives_undefined_metrics() -> None:
    f = person_frames()
    bare = make_frames(track_frames=f.track_frames, tracks=f.tracks)
    for m in perception_metrics(bare):
        assert m.value is None and m.detail == "no ground truth"


def test_empty_tracker_frames_are_misses() -> None:
    f = person_frames()
    half = f.tracks[f.tracks["frame"] < 30]  # frames 30..59 published but empty
    r = by_name(perception_metrics(make_frames(gt_poses=f.gt_poses,
                                               track_frames=f.track_frames, tracks=half)))
    assert r["perception.recall"].value == pytest.approx(0.5)
    assert r["perception.precision"].value == 1.0
