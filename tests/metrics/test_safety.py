"""Safety metrics on hand-built frames with known answers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from harness.metrics.safety import (
    Tripwire,
    expected_muted,
    mute_metrics,
    points_in_polygon,
    safety_metrics,
    verdict,
)
from tests.metrics.helpers import gt_rows, make_frames, t_ns

# trailer: past x = 15 (segment pointing +y, inside on its right); ROI: x 10..15, y -3..3
WIRE = Tripwire((15.0, -1.3), (15.0, 1.3), inside="right")
ROI = ((10.0, -3.0), (15.0, -3.0), (15.0, 3.0), (10.0, 3.0))


def by_name(results: list) -> dict:
    return {r.name: r for r in results}


def forklift_inside(ticks: np.ndarray, inside_ranges: list[tuple[int, int]]) -> pd.DataFrame:
    x = np.full(ticks.size, 12.0)
    for a, b in inside_ranges:
        x[(ticks >= a) & (ticks < b)] = 16.0
    return gt_rows("forklift", ticks, x, np.zeros(ticks.size))


def muted_msgs(*pairs: tuple[float, bool]) -> pd.DataFrame:
    return pd.DataFrame({"t_ns": [round(s * 1e9) for s, _ in pairs],
                         "value": [v for _, v in pairs]})


def test_known_under_mute_window_and_lag() -> None:
    ticks = np.arange(0, 8 * 60)
    gt = forklift_inside(ticks, [(120, 300)])  # expected muted 2.0 s - 5.0 s
    frames = make_frames(gt_poses=gt,
                         muted=muted_msgs((0.0, False), (2.5, True), (5.0, False)))
    r = by_name(safety_metrics(frames, tripwire=WIRE, roi=ROI))
    under = r["safety.under_mute"]
    assert under.windows == ((2.0, 2.5),)
    assert under.value == pytest.approx(100 * 30 / 480)
    assert r["safety.over_mute"].value == 0.0 and r["safety.over_mute"].windows == ()
    assert r["safety.match_rate"].value == pytest.approx(100 * 450 / 480)
    assert r["safety.match_rate"].verdict == "NEAR"  # 93.75 %
    assert r["safety.mute_lag.p50"].value == pytest.approx(0.5)
    assert r["safety.mute_lag.max"].value == pytest.approx(0.5)
    assert r["safety.unmute_lag.max"].value == 0.0  # released on the very tick
    assert r["safety.mute_never_engaged"].value == 0
    assert r["safety.unmute_never_released"].value == 0
    assert r["safety.match_rate"].direction == "higher"
    assert r["safety.under_mute"].unit == "%" and r["safety.mute_lag.p95"].unit == "s"


def test_short_mismatch_counts_in_percent_but_gets_no_window() -> None:
    ticks = np.arange(0, 8 * 60)
    gt = forklift_inside(ticks, [(120, 300)])
    frames = make_frames(gt_poses=gt,
                         muted=muted_msgs((0.0, False), (2.25, True), (5.4, False)))
    r = by_name(safety_metrics(frames, tripwire=WIRE, roi=ROI))
    assert r["safety.under_mute"].windows == ()  # 0.25 s < 0.5 s
    assert r["safety.under_mute"].value == pytest.approx(100 * 15 / 480)
    assert r["safety.over_mute"].windows == ()  # 0.4 s
    assert r["safety.over_mute"].value == pytest.approx(100 * 24 / 480)
    assert r["safety.unmute_lag.max"].value == pytest.approx(0.4)


def test_known_never_engaged_and_never_released() -> None:
    ticks = np.arange(0, 12 * 60)
    # expected muted 2-5 s (followed) and 6-7 s (never muted); stuck muted after 9-10 s
    gt = forklift_inside(ticks, [(120, 300), (360, 420), (540, 600)])
    frames = make_frames(gt_poses=gt, muted=muted_msgs(
        (0.0, False), (2.1, True), (5.2, False), (9.3, True)))
    r = by_name(safety_metrics(frames, tripwire=WIRE, roi=ROI))
    assert r["safety.mute_never_engaged"].value == 1  # the 6-7 s window
    assert r["safety.unmute_never_released"].value == 1  # muted from 9.3 s to the end
    lags = [r[f"safety.mute_lag.{s}"].value for s in ("p50", "p95", "max")]
    assert lags == pytest.approx([0.2, 0.1 + 0.95 * 0.2, 0.3])  # lags 0.1 (2 s), 0.3 (9 s)
    assert r["safety.unmute_lag.max"].value == pytest.approx(0.2)  # 5.0 → 5.2; 7.0 → 0
    assert r["safety.over_mute"].windows == ((10.0, 12.0),)
    assert r["safety.under_mute"].windows == ((6.0, 7.0),)


def test_before_the_first_message_counts_as_not_muted() -> None:
    ticks = np.arange(0, 4 * 60)
    gt = forklift_inside(ticks, [(0, 240)])  # should be muted the whole time
    r = by_name(safety_metrics(make_frames(gt_poses=gt, muted=muted_msgs((1.0, True))),
                               tripwire=WIRE, roi=ROI))
    assert r["safety.under_mute"].windows == ((0.0, 1.0),)
    assert r["safety.match_rate"].value == pytest.approx(75.0)
    assert r["safety.match_rate"].verdict == "FAIL"
    none = by_name(safety_metrics(make_frames(gt_poses=gt), tripwire=WIRE, roi=ROI))
    assert none["safety.match_rate"].value == 0.0
    assert none["safety.mute_lag.max"].value is None  # no edge: nothing to measure
    assert "no expected mute edge" in none["safety.mute_lag.max"].detail


def test_worker_in_roi_suppresses_the_expected_mute() -> None:
    ticks = np.arange(0, 6 * 60)
    fork = forklift_inside(ticks, [(60, 360)])  # inside from 1 s on
    wx = np.where((ticks >= 180) & (ticks < 240), 12.0, 5.0)  # in the ROI 3-4 s
    worker = gt_rows("character_0", ticks, wx, np.zeros(ticks.size))
    far = gt_rows("character_1", ticks, np.full(ticks.size, -5.0), np.zeros(ticks.size))
    exp = expected_muted(fork, pd.concat([worker, far]), tripwire=WIRE, roi=ROI)
    e = exp["expected"].to_numpy()
    assert not e[:60].any() and e[60:180].all() and not e[180:240].any() and e[240:].all()
    assert exp["worker_in_roi"].sum() == 60
    frames = make_frames(gt_poses=pd.concat([fork, worker, far], ignore_index=True),
                         muted=muted_msgs((1.0, True)))  # ignores the worker
    r = by_name(safety_metrics(frames, tripwire=WIRE, roi=ROI))
    assert r["safety.over_mute"].windows == ((3.0, 4.0),)
    assert r["safety.unmute_never_released"].value == 1
    assert r["safety.mute_lag.max"].value == 0.0


def test_match_rate_does_not_mutate_its_inputs() -> None:
    ticks = np.arange(0, 120)
    exp = pd.DataFrame({"t_ns": t_ns(ticks)[::-1], "expected": ticks[::-1] > 60})
    muted = muted_msgs((1.5, True), (0.0, False))
    before = (exp.copy(), muted.copy())
    mute_metrics(exp, muted)
    pd.testing.assert_frame_equal(exp, before[0])
    pd.testing.assert_frame_equal(muted, before[1])


@pytest.mark.parametrize(("rate", "band"), [(100.0, "PASS"), (95.0, "PASS"), (94.99, "NEAR"),
                                            (80.0, "NEAR"), (79.9, "FAIL"), (0.0, "FAIL")])
def test_verdict_bands(rate: float, band: str) -> None:
    assert verdict(rate) == band


def test_tripwire_sides() -> None:
    x = np.array([14.0, 16.0])
    y = np.zeros(2)
    assert WIRE.past(x, y).tolist() == [False, True]
    left = Tripwire((15.0, -1.3), (15.0, 1.3), inside="left")
    assert left.past(x, y).tolist() == [True, False]
    assert not WIRE.past(np.array([15.0]), np.array([0.0]))[0]  # on the line: not past


def test_point_in_polygon_agrees_with_shapely() -> None:
    shapely = pytest.importorskip("shapely")  # the dev extra installs it
    rng = np.random.default_rng(3)
    # a concave polygon (an L with a notch)
    poly = [(0.0, 0.0), (6.0, 0.0), (6.0, 2.0), (3.0, 2.0), (2.0, 4.0), (4.0, 6.0),
            (0.0, 6.0)]
    x, y = rng.uniform(-1, 7, 5000), rng.uniform(-1, 7, 5000)
    ours = points_in_polygon(x, y, poly)
    theirs = shapely.contains_xy(shapely.Polygon(poly), x, y)
    assert ours.tolist() == theirs.tolist()
    assert 0 < ours.sum() < ours.size
