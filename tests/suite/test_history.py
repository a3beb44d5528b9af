"""``load_history``: earlier suite outputs → the ``history`` block of tonight's summary.

Nights are ordered by ``started_at`` (not by folder name), the last ``last`` kept plus
tonight; a night's value is the group's mean; damaged, foreign and other suites' summaries
are skipped with a warning; a missing history folder is one SrrError line.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from harness.errors import SrrError
from harness.suite.history import load_history
from tests.suite.fake_summary import stats_of

GID = "dock_worker_crossing[workers.0.speed=1.4]"


def summary(started: str, rates: dict[str, float | None], *, verdict: str = "PASS",
            name: str = "nightly") -> dict[str, Any]:
    """A suite summary with one group per entry of ``rates`` (None: no match rate that
    night), each with a cross-track error too."""
    groups = []
    for gid, rate in rates.items():
        stats = {"control.cross_track_error.max": stats_of("control.cross_track_error.max",
                                                           [0.3, 0.32])}
        if rate is not None:
            stats["safety.match_rate"] = stats_of("safety.match_rate", [rate - 0.5, rate + 0.5])
        groups.append({"id": gid, "verdict": verdict, "stats": stats, "runs": []})
    return {"format": "srr-suite/1", "name": name, "started_at": started, "verdict": verdict,
            "groups": groups, "runs": [], "sweeps": [], "history": None}


def write(root: Path, folder: str, s: dict[str, Any] | str) -> Path:
    d = root / folder
    d.mkdir(parents=True)
    (d / "summary.json").write_text(s if isinstance(s, str) else json.dumps(s),
                                    encoding="utf-8")
    return d


TONIGHT = summary("2026-11-23T02:00:00Z", {GID: 90.0, "new_group": 99.0}, verdict="REGRESSED")


def test_nights_in_time_order_with_one_value_each(tmp_path: Path) -> None:
    write(tmp_path, "z-oldest", summary("2026-11-20T02:00:00Z", {GID: 97.0}))
    write(tmp_path, "a-newest", summary("2026-11-22T02:00:00+00:00", {GID: 95.0},
                                        verdict="FAIL"))
    write(tmp_path, "m-middle", summary("2026-11-21T03:00:00+01:00", {GID: None}))
    (tmp_path / "logs").mkdir()  # not a suite output: ignored silently
    h = load_history([tmp_path], TONIGHT)
    assert [n["started_at"] for n in h["nights"]] == [
        "2026-11-20T02:00:00Z", "2026-11-21T03:00:00+01:00", "2026-11-22T02:00:00+00:00",
        "2026-11-23T02:00:00Z"]
    assert [n["path"] for n in h["nights"]] == [
        str(tmp_path / "z-oldest"), str(tmp_path / "m-middle"), str(tmp_path / "a-newest"), "."]
    assert [n["verdict"] for n in h["nights"]] == ["PASS", "PASS", "FAIL", "REGRESSED"]
    assert h["series"][GID]["safety.match_rate"] == [97.0, None, 95.0, 90.0]
    assert h["series"][GID]["control.cross_track_error.max"] == pytest.approx([0.31] * 4)
    assert h["series"]["new_group"]["safety.match_rate"] == [None, None, None, 99.0]
    assert h["verdicts"][GID] == ["PASS", "PASS", "FAIL", "REGRESSED"]
    assert h["verdicts"]["new_group"] == [None, None, None, "REGRESSED"]
    assert h["warnings"] == []
    assert set(h["series"]) == {GID, "new_group"}


def test_keeps_the_last_nights_plus_tonight(tmp_path: Path) -> None:
    for day in range(1, 21):
        write(tmp_path, f"n{day:02d}", summary(f"2026-11-{day:02d}T02:00:00Z", {GID: float(day)}))
    h = load_history([tmp_path], TONIGHT)
    assert len(h["nights"]) == 15  # the default: last 14 and tonight
    assert h["series"][GID]["safety.match_rate"][:2] == [7.0, 8.0]
    h = load_history([tmp_path], TONIGHT, last=3)
    assert h["series"][GID]["safety.match_rate"] == [18.0, 19.0, 20.0, 90.0]
    h = load_history([tmp_path], TONIGHT, last=0)
    assert [n["path"] for n in h["nights"]] == ["."]
    with pytest.raises(SrrError, match="0 or more"):
        load_history([tmp_path], TONIGHT, last=-1)


def test_damaged_and_foreign_summaries_are_skipped_with_a_warning(tmp_path: Path) -> None:
    write(tmp_path, "good", summary("2026-11-22T02:00:00Z", {GID: 96.0}))
    write(tmp_path, "truncated", '{"format": "srr-suite/1", "groups": [')
    write(tmp_path, "run-dir", json.dumps({"scenario": "x", "verdict": "PASS", "seed": 1}))
    write(tmp_path, "list", "[1, 2, 3]")
    write(tmp_path, "deep", "[" * 100_000 + "]" * 100_000)
    write(tmp_path, "binary", "\x00\xff garbage")
    (tmp_path / "latin1").mkdir()
    (tmp_path / "latin1" / "summary.json").write_bytes(b'{"name": "\xe9"}')
    write(tmp_path, "no-time", dict(summary("x", {GID: 1.0}), started_at="yesterday"))
    write(tmp_path, "bad-groups", dict(summary("2026-11-21T02:00:00Z", {}), groups={"a": 1}))
    write(tmp_path, "bad-stats", dict(summary("2026-11-21T02:00:00Z", {}),
                                      groups=[{"id": "g", "stats": [1]}]))
    write(tmp_path, "other-suite", summary("2026-11-21T02:00:00Z", {GID: 1.0}, name="smoke"))
    h = load_history([tmp_path], TONIGHT)
    assert len(h["nights"]) == 2 and h["nights"][0]["path"] == str(tmp_path / "good")
    warned = {w.split(str(tmp_path) + "/")[1].split("/")[0]: w for w in h["warnings"]}
    assert set(warned) == {"truncated", "run-dir", "list", "deep", "binary", "latin1",
                           "no-time", "bad-groups", "bad-stats", "other-suite"}
    assert all(w.startswith("history: skipped ") and "\n" not in w for w in h["warnings"])
    assert "not valid JSON" in warned["truncated"]
    assert "not an srr suite summary (format None" in warned["run-dir"]
    assert "'yesterday' is not an ISO 8601 time" in warned["no-time"]
    assert "another suite ('smoke', not 'nightly')" in warned["other-suite"]


def test_a_missing_history_folder_is_one_error_line(tmp_path: Path) -> None:
    gone = tmp_path / "nope"
    with pytest.raises(SrrError) as err:
        load_history([gone], TONIGHT)
    assert str(gone) in str(err.value) and "\n" not in str(err.value)
    (tmp_path / "file").write_text("x")
    with pytest.raises(SrrError, match="not a folder"):
        load_history([tmp_path / "file"], TONIGHT)


def test_one_suite_output_folder_tonight_and_later_nights(tmp_path: Path) -> None:
    one = write(tmp_path, "only", summary("2026-11-22T02:00:00Z", {GID: 96.0}))
    h = load_history([one], TONIGHT)  # DIR itself is a suite output
    assert [n["path"] for n in h["nights"]] == [str(one), "."]
    write(tmp_path, "tonight", TONIGHT)  # tonight's own output inside the history folder
    write(tmp_path, "zz-copy", summary("2026-11-22T02:00:00Z", {GID: 1.0}))
    write(tmp_path, "future", summary("2026-11-24T02:00:00Z", {GID: 1.0}))
    h = load_history([tmp_path], TONIGHT)
    assert [n["started_at"] for n in h["nights"]] == ["2026-11-22T02:00:00Z",
                                                      "2026-11-23T02:00:00Z"]
    assert h["series"][GID]["safety.match_rate"] == [96.0, 90.0]  # the first in name order
    assert any("same started_at" in w for w in h["warnings"])
    assert any("after tonight" in w for w in h["warnings"])
    empty = tmp_path / "empty"
    empty.mkdir()
    assert load_history([empty], TONIGHT)["warnings"] == [
        f"history: no earlier suite output (summary.json) in {empty}"]
