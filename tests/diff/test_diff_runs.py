"""``srr diff`` on real runs: identical runs, runs whose seed changes the data, tolerances,
counts and topic sets that differ, and what is not a pair of runs (exit 2)."""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from harness import api
from harness.cli import main
from tests.diff.conftest import Runs
from tests.e2e.bagread import decoded

pytestmark = pytest.mark.slow

GT = "/gt/character_0/tf"


def _worker_x(run: Path) -> tuple[np.ndarray, np.ndarray]:
    """(log times, x) of the worker's ground truth, read with the independent mcap reader."""
    rows = [(t, m.transforms[0].transform.translation.x) for topic, _, t, m in decoded(run)
            if topic == GT]
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows])


def test_identical_runs_exit_0(runs: Runs, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = runs.get("same_a"), runs.get("same_b")
    r = api.diff_runs(a, b)
    assert r.equal and r.exit_code == 0 and r.verdict == "IDENTICAL"
    assert r.first_divergence is None and r.notes == ()
    summary = json.loads((a / "summary.json").read_text())
    assert [t.name for t in r.topics] == sorted(summary["topics"])
    for t in r.topics:  # digests recomputed from the bags agree with the recorder's
        assert t.status == "identical" and t.sha256_a == t.sha256_b
        assert t.sha256_a == summary["topics"][t.name]["sha256"]
        assert t.count_a == t.count_b == summary["topics"][t.name]["count"]
    assert all(m.status == "ok" and m.delta in (0.0, None) for m in r.metrics)
    assert main(["diff", str(a), str(b)]) == 0
    out = capsys.readouterr().out
    assert "verdict: IDENTICAL" in out and "first divergence:" not in out


def test_seeds_that_change_the_data_exit_1_naming_the_first_divergence(
        runs: Runs, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = runs.get("seed_7"), runs.get("seed_8")
    r = api.diff_runs(a, b)
    assert not r.equal and r.exit_code == 1 and r.verdict == "DIFFERENT"
    assert [t.name for t in r.differing] == [GT]
    # what the independent reader says: the first message whose x differs, and by how much
    ta, xa = _worker_x(a)
    tb, xb = _worker_x(b)
    assert np.array_equal(ta, tb)
    first = int(np.flatnonzero(xa != xb)[0])
    d = r.first_divergence
    assert d is not None
    assert (d.topic, d.index, d.stamp_a_ns, d.stamp_b_ns) == (GT, first, ta[first], tb[first])
    assert d.path == "transforms[0].transform.translation.x"
    (t,) = r.differing
    assert t.count_a == t.count_b == ta.size and t.messages_differ == int((xa != xb).sum())
    fx = next(f for f in t.fields if f.path == "transforms[0].transform.translation.x")
    delta = np.abs(xb - xa)
    assert fx.max_abs == pytest.approx(delta.max())
    assert fx.at_index == int(np.argmax(delta)) and fx.at_ns == ta[fx.at_index]
    assert fx.rms == pytest.approx(np.sqrt(np.mean(delta[delta > 0] ** 2)))
    assert main(["diff", str(a), str(b)]) == 1
    out = capsys.readouterr().out
    assert (f"first divergence: {GT} message #{first} at {ta[first] / 1e9:.3f} s: "
            "transforms[0].transform.translation.x: ") in out
    assert "verdict: DIFFERENT" in out


def test_a_tolerance_that_covers_the_difference_exits_0(runs: Runs, tmp_path: Path) -> None:
    a, b = runs.get("seed_7"), runs.get("seed_8")
    _, xa = _worker_x(a)
    _, xb = _worker_x(b)
    worst = float(np.abs(xb - xa).max())
    field = f"{GT}:transforms[*].transform.translation.*"
    r = api.diff_runs(a, b, tolerances=[f"{field}={worst * 1.01}"])
    assert r.equal and r.exit_code == 0 and r.verdict == "EQUAL_WITHIN_TOLERANCE"
    (t,) = [t for t in r.topics if t.name == GT]
    assert t.status == "within_tolerance" and t.first is not None and t.first_beyond is None
    # half of it: the first divergence is the first message beyond the tolerance
    r = api.diff_runs(a, b, tolerances=[f"{field}={worst / 2}"])
    assert r.exit_code == 1
    d = r.first_divergence
    assert d is not None and d.index == int(np.flatnonzero(np.abs(xb - xa) > worst / 2)[0])
    # a relative tolerance is relative to A's value; a tolerance on another field covers nothing
    moved = xa != xb
    rel = float(np.max(np.abs(xb - xa)[moved] / np.abs(xa[moved])))
    assert api.diff_runs(a, b, tolerances=[f"{GT}=0,{rel * 1.01}"]).exit_code == 0
    assert api.diff_runs(a, b, tolerances=[f"{GT}:*.rotation.*=1"]).exit_code == 1
    # through the CLI, with --json
    out = tmp_path / "diff.json"
    assert main(["diff", str(a), str(b), "--tolerance", f"{field}={worst * 1.01}",
                 "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["exit_code"] == 0 and data["verdict"] == "EQUAL_WITHIN_TOLERANCE"
    assert data["tolerances"][0]["field"] == "transforms[*].transform.translation.*"


def test_arrays_name_the_first_differing_element(runs: Runs) -> None:
    r = api.diff_runs(runs.get("scan_1"), runs.get("scan_2"))
    assert [t.name for t in r.differing] == ["/scan"]
    d = r.first_divergence
    assert d is not None and d.topic == "/scan" and d.index == 0
    m = re.fullmatch(r"ranges\[(\d+)\]", d.path)
    assert m and int(m.group(1)) < 360
    assert re.search(r"\(\d+ of 360 values differ, max \|Δ\| ", d.detail)
    (f,) = r.differing[0].fields
    assert f.path == "ranges[*]" and f.values == 360 * r.differing[0].count_a


def test_counts_and_topic_sets_that_differ(runs: Runs) -> None:
    r = api.diff_runs(runs.get("same_a"), runs.get("short"))
    assert r.exit_code == 1
    clock = next(t for t in r.topics if t.name == "/clock")
    assert (clock.count_a, clock.count_b) == (120, 90) and clock.status == "differs"
    assert clock.first_beyond is not None and clock.first_beyond.index == 90
    assert clock.first_beyond.path == "(message)" and clock.first_beyond.stamp_b_ns is None
    assert clock.messages_differ == 0  # the 90 they share are identical
    r = api.diff_runs(runs.get("same_a"), runs.get("seed_7"))
    ((name, status),) = [(t.name, t.status) for t in r.differing]
    assert (name, status) == (GT, "only_in_b")
    assert r.first_divergence is not None and r.first_divergence.path == "(topic)"


def test_what_changed_between_the_runs_is_said_in_their_scenarios_words(
        runs: Runs, capsys: pytest.CaptureFixture[str]) -> None:
    """The resolved scenarios' fields that differ, A → B (a system under test's parameter
    too, which a baseline comparison leaves out), and a note for topics that differ only in
    their message counts, the messages both runs have being identical."""
    assert api.diff_runs(runs.get("same_a"), runs.get("same_b")).changes == ()
    r = api.diff_runs(runs.get("same_a"), runs.get("slower"))
    assert r.changes == ("systems_under_test[0].params.speed: 1.5 → 1.0",)
    assert main(["diff", str(runs.get("same_a")), str(runs.get("slower"))]) == 1
    out = capsys.readouterr().out
    assert "what changed (A → B):\n  systems_under_test[0].params.speed: 1.5 → 1.0\n" in out
    r = api.diff_runs(runs.get("same_a"), runs.get("short"))
    assert r.changes == ("duration: 2.0 → 1.5",)
    assert r.to_dict()["changes"] == ["duration: 2.0 → 1.5"]
    (note,) = [n for n in r.notes if "only in how many messages" in n]
    shared = [t.name for t in r.topics if t.status == "differs"]
    assert note.startswith(f"{len(shared)} topic(s) differ only in how many messages they "
                           f"have ({shared[0]}, ")
    assert note.endswith("the messages both runs recorded are identical; A has 2 s of "
                         "simulated time, B 1.5 s")
    assert "seed: 7 → 8" in api.diff_runs(runs.get("seed_7"), runs.get("seed_8")).changes


def test_a_metric_one_run_lacks_shows_a_dash_not_a_dash_and_unit(
        runs: Runs, capsys: pytest.CaptureFixture[str]) -> None:
    from harness.cli import _print_diff
    from harness.diff.result import MetricDelta

    r = api.diff_runs(runs.get("same_a"), runs.get("same_b"))
    lost = MetricDelta("control.time_to_goal", "s", "lower", 24.68, None, None, 1.23,
                       "regressed")
    _print_diff(dataclasses.replace(r, metrics=(lost,)))
    (row,) = [line for line in capsys.readouterr().out.splitlines()
              if "control.time_to_goal" in line]
    cells = [c.strip() for c in row.strip("│ ").split("│")]
    assert cells[:3] == ["control.time_to_goal", "24.68 s", "—"], cells


def test_result_is_frozen_data(runs: Runs) -> None:
    r = api.diff_runs(runs.get("same_a"), runs.get("same_b"))
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.topics[0].status = "differs"  # type: ignore[misc]


def _corrupt(run: Path, dst: Path, how: str, other: Path | None = None) -> Path:
    if how == "missing":
        return dst / "nope"
    if how == "empty-dir":
        dst.mkdir()
        return dst
    shutil.copytree(run, dst)
    (mcap,) = (dst / "bag").glob("*.mcap")
    if how == "no-bag":
        shutil.rmtree(dst / "bag")
    elif how == "no-metadata":
        (dst / "bag" / "metadata.yaml").unlink()
    elif how == "truncated":
        data = mcap.read_bytes()
        mcap.write_bytes(data[: len(data) // 2])
    elif how == "overwritten":  # bytes zeroed inside a chunk: its CRC no longer holds
        data = bytearray(mcap.read_bytes())
        data[len(data) // 3:len(data) // 3 + 64] = bytes(64)
        mcap.write_bytes(bytes(data))
    elif how == "swapped":  # a valid bag, but not the one this summary recorded
        assert other is not None
        (other_mcap,) = (other / "bag").glob("*.mcap")
        mcap.write_bytes(other_mcap.read_bytes())
    elif how == "summary-file":  # the run's summary.json given for its run directory
        return dst / "summary.json"
    elif how == "bad-json":
        (dst / "summary.json").write_text("{", encoding="utf-8")
    elif how == "bad-metric":
        s = json.loads((dst / "summary.json").read_text())
        s["metrics"][0]["value"] = "fast"
        (dst / "summary.json").write_text(json.dumps(s), encoding="utf-8")
    return dst


@pytest.mark.parametrize(("how", "names"), [
    ("missing", "nope: not a run directory"),
    ("empty-dir", "summary.json: missing"),
    ("no-bag", "bag: missing"),
    ("no-metadata", "metadata.yaml: missing"),
    ("truncated", "cannot read bag"),
    ("overwritten", "cannot read bag: Chunk checksum mismatch"),
    ("swapped", "does not match summary.json"),
    ("summary-file", "summary.json: the summary of the run "),
    ("bad-json", "summary.json: not valid JSON"),
    ("bad-metric", "summary.json: metrics[0].value: expected a number, got 'fast'"),
])
def test_bad_runs_exit_2_with_one_line_and_no_page(
        runs: Runs, tmp_path: Path, capsys: pytest.CaptureFixture[str], how: str,
        names: str) -> None:
    good = runs.get("same_a")
    bad = _corrupt(good, tmp_path / "bad", how, other=runs.get("short"))
    page = tmp_path / "diff.html"
    for args in ([str(good), str(bad)], [str(bad), str(good)]):
        assert main(["diff", *args, "--html", str(page)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith("srr diff: ")
        assert names in err and str(bad) in err and "Traceback" not in err
        assert not page.exists()


@pytest.mark.parametrize("spec", ["/odom", "/odom=x", "/odom:=1", "/odom=1,2,3", "/odom=-1"])
def test_bad_tolerance_exits_2_naming_the_option(
        runs: Runs, tmp_path: Path, capsys: pytest.CaptureFixture[str], spec: str) -> None:
    page = tmp_path / "diff.html"
    code = main(["diff", str(runs.get("same_a")), str(runs.get("same_b")), "--tolerance", spec,
                 "--html", str(page)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert err.startswith(f"srr diff: --tolerance {spec!r}: ") and not page.exists()


def test_html_into_a_missing_directory_exits_2(runs: Runs, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "no" / "such" / "diff.html"
    assert main(["diff", str(runs.get("same_a")), str(runs.get("same_b")), "--html",
                 str(target)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("srr diff: --html ") and "does not exist" in err


def test_camera_images_compare_pixel_bytes(runs: Runs) -> None:
    a, b = runs.get("dock_11"), runs.get("dock_12")
    topic = "/dock_cam_left_rgb"

    def images(run: Path) -> list[np.ndarray]:
        return [np.frombuffer(bytes(m.data), dtype=np.uint8) for t, _, _, m in decoded(run)
                if t == topic]

    ia, ib = images(a), images(b)
    assert len(ia) == len(ib) > 0
    deltas = [np.abs(x.astype(int) - y.astype(int)) for x, y in zip(ia, ib, strict=True)]
    differ = [int(np.count_nonzero(d)) for d in deltas]
    assert any(differ)  # the worker walks at another speed in front of the cameras
    r = api.diff_runs(a, b)
    t = next(t for t in r.topics if t.name == topic)
    (f,) = t.fields
    assert f.path == "data[*]" and f.differ == sum(differ)
    assert f.values == sum(d.size for d, n in zip(deltas, differ, strict=True) if n)
    assert f.max_abs == max(int(d.max()) for d in deltas)
    first = next(i for i, n in enumerate(differ) if n)
    assert t.first is not None and t.first.index == first
    assert t.first.path == f"data[{int(np.flatnonzero(deltas[first])[0])}]"
    assert t.worst is not None and t.worst.values == max(differ)
    # every pixel byte may move by 255: the camera topics are then equal within tolerance
    r = api.diff_runs(a, b, tolerances=["/dock_cam_*_rgb:data*=255"])
    assert {t.name: t.status for t in r.topics}[topic] == "within_tolerance"
