"""``srr diff SUITE_A SUITE_B`` on two real suites run once per module (a few seconds): runs
matched by their ids, runs only in one suite, verdict changes, recordings compared by their
digests first (the bags of identical runs are never opened), tolerances, the terminal lines,
``--json``, ``--html`` with each differing pair's page, and what is not a pair of suites
(exit 2, one line).

A (``diffcheck``) and B (``diffcheck-branch``, another suite file) share these entries:

* ``same``: the pallet truck as bundled, PASS in both: identical;
* ``speed``: the diffbot, its route follower at 0.5 m/s in A and 0.4 in B: PASS → REGRESSED
  (it no longer reaches its goal), the recording differs from its first ``/cmd_vel``;
* ``tolerant``: the pallet truck at 1.2 m/s in A, 1.19 in B: numbers differ a little;
* ``rebaselined``: the pallet truck judged against a baseline B does not have: PASS → FAIL
  with identical recordings;
* ``crash``: the pallet truck in A; in B its worker is killed before its first tick
  (INVALID, nothing recorded);
* ``dead``: killed before its first tick in both (INVALID, nothing to compare).

``gone`` is only in A, ``new`` only in B.
"""

from __future__ import annotations

import json
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import unquote

import pytest

from harness import api
from harness.cli import main
from harness.errors import SrrError
from harness.suite.diff import SuiteDiff
from tests.conftest import ModuleTmp
from tests.suite.plugins import PLANNER_PID

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
PALLET = ROOT / "scenarios" / "pallet_truck_mjcf.yaml"
DIFFBOT = ROOT / "scenarios" / "diffbot_urdf.yaml"
SPEED = "systems_under_test.route_follower.params.speed"
KILLED = '{systems_under_test.route_follower.plugin: "tests.suite.plugins:KilledAtStart"}'


def _suite_file(name: str, *, b: bool) -> str:
    def entry(path: Path, entry_name: str, overrides: str | None = None) -> str:
        return (f"  - path: {path}\n    name: {entry_name}\n"
                + (f"    set: {overrides}\n" if overrides else ""))

    return f"suite: {name}\nscenarios:\n" + "".join([
        entry(PALLET, "same"),
        entry(DIFFBOT, "speed", f"{{{SPEED}: 0.4}}" if b else None),
        entry(PALLET, "tolerant", f"{{{SPEED}: {1.19 if b else 1.2}}}"),
        entry(PALLET, "rebaselined", "{baseline: no_such_baseline}" if b else None),
        entry(PALLET, "crash", KILLED if b else None),
        entry(PALLET, "dead", KILLED),
        entry(PALLET, "new" if b else "gone", "{duration: 1}"),
    ])


@pytest.fixture(scope="module")
def suites(module_tmp: ModuleTmp) -> Iterator[tuple[Path, Path]]:
    root = module_tmp("suitediff")
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(ROOT)  # the plug-ins import from the project root, as with `srr suite`
        mp.setenv(PLANNER_PID, str(os.getpid()))
        outs = []
        for name, b in (("diffcheck", False), ("diffcheck-branch", True)):
            file = root / f"{name}.yaml"
            file.write_text(_suite_file(name, b=b), encoding="utf-8")
            outs.append(api.suite([file], jobs=2, out=root / name, fork=True).out_dir)
        yield outs[0], outs[1]


def _pairs(r: SuiteDiff) -> dict[str, tuple[str, str, str]]:
    return {p.id: (p.verdict_a, p.verdict_b, p.recording) for p in r.pairs}


def test_runs_are_matched_by_id_with_verdict_changes_and_runs_only_in_one(
        suites: tuple[Path, Path]) -> None:
    a, b = suites
    r = api.diff_suites(a, b)
    assert _pairs(r) == {
        "same#1": ("PASS", "PASS", "identical"),
        "speed#1": ("PASS", "REGRESSED", "differs"),
        "tolerant#1": ("PASS", "PASS", "differs"),
        "rebaselined#1": ("PASS", "FAIL", "identical"),
        "crash#1": ("PASS", "INVALID", "only_in_a"),
        "dead#1": ("INVALID", "INVALID", "none"),
    }
    assert [(u.id, u.verdict) for u in r.only_in_a] == [("gone#1", "MISMATCH")]
    assert [(u.id, u.verdict) for u in r.only_in_b] == [("new#1", "MISMATCH")]
    assert [(g.id, g.verdict_a, g.verdict_b) for g in r.groups] == [
        ("speed", "PASS", "REGRESSED"), ("rebaselined", "PASS", "FAIL"),
        ("crash", "PASS", "INVALID")]
    assert (r.verdict, r.equal, r.exit_code) == ("DIFFERENT", False, 1)
    assert [p.id for p in r.changed] == ["speed#1", "tolerant#1", "rebaselined#1", "crash#1"]
    # what changed between the pairs' inputs, each line once with the runs it is true of
    changes = dict(r.changes)
    assert changes["systems_under_test[0].params.speed: 0.5 → 0.4"] == ("speed#1",)
    assert changes["systems_under_test[0].params.speed: 1.2 → 1.19"] == ("tolerant#1",)
    speed = next(p for p in r.pairs if p.id == "speed#1")
    assert speed.diff is not None
    first = speed.diff.first_divergence
    assert first is not None and (first.topic, first.index) == ("/cmd_vel", 0)
    moved = {m.name: m for m in speed.moved}
    assert moved["control.goal_reached"].status == "regressed"
    line = speed.describe()
    assert line.startswith("PASS → REGRESSED; recording differs in ")
    assert "first at 0.000 s: /cmd_vel #0 linear.x" in line
    assert "control.goal_reached yes → no (regressed)" in line
    assert any("different suite files: 'diffcheck' (A) and 'diffcheck-branch' (B)" in n
               for n in r.notes)
    assert any("recorded nothing in either suite" in n and "dead#1" in n for n in r.notes)


def test_a_suite_against_itself_is_identical_without_opening_a_bag(
        suites: tuple[Path, Path], monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    def no_bags(*args: object, **kwargs: object) -> None:
        raise AssertionError("a bag was opened although every digest agrees")

    monkeypatch.setattr("harness.diff.core.diff_bags", no_bags)
    a, _ = suites
    r = api.diff_suites(a, a)
    assert (r.verdict, r.exit_code) == ("IDENTICAL", 0)
    assert not r.only_in_a and not r.only_in_b and not r.groups and not r.changed
    assert all(p.diff is not None and p.diff.verdict == "IDENTICAL"
               for p in r.pairs if p.id != "dead#1")
    assert main(["diff", str(a), str(a)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[-1] == ("verdict: IDENTICAL (7 matched runs: recordings 6 "
                                    "identical, 1 recorded by neither)")


def test_only_the_topics_whose_digests_differ_are_read(
        suites: tuple[Path, Path], monkeypatch: pytest.MonkeyPatch) -> None:
    from harness.diff.topics import diff_bags as real

    skipped: dict[str, frozenset[str]] = {}

    def spy(bag_a: Path, bag_b: Path, tolerances: object = (), *,
            skip: frozenset[str] = frozenset()) -> object:
        skipped[bag_a.parents[2].name] = frozenset(skip)  # runs/<entry>/nominal/r1/bag
        return real(bag_a, bag_b, tolerances, skip=skip)  # type: ignore[arg-type]

    monkeypatch.setattr("harness.diff.core.diff_bags", spy)
    a, b = suites
    r = api.diff_suites(a, b)
    assert sorted(skipped) == ["speed", "tolerant"]  # entries whose recordings differ
    speed = next(p for p in r.pairs if p.id == "speed#1").diff
    assert speed is not None
    read = {t.name for t in speed.topics} - skipped["speed"]
    assert "/clock" in skipped["speed"] and "/cmd_vel" in read
    # the topics left unread are those both summaries record alike
    sa = json.loads((a / "runs/speed/nominal/r1/summary.json").read_text())["topics"]
    sb = json.loads((b / "runs/speed/nominal/r1/summary.json").read_text())["topics"]
    assert skipped["speed"] == {n for n in sa if sa[n]["sha256"] == sb.get(n, {}).get("sha256")}
    # and the same result as the run diff that reads every message
    full = api.diff_runs(a / "runs/speed/nominal/r1", b / "runs/speed/nominal/r1")
    assert [(t.name, t.status, t.count_a, t.sha256_b) for t in speed.topics] == \
        [(t.name, t.status, t.count_a, t.sha256_b) for t in full.topics]
    assert speed.first_divergence == full.first_divergence


def _view(src: Path, dst: Path, keep: set[str]) -> Path:
    """A suite folder holding only the runs ``keep`` of suite ``src`` (its runs/ linked)."""
    dst.mkdir()
    (dst / "runs").symlink_to(src / "runs")
    s = json.loads((src / "summary.json").read_text())
    s["runs"] = [r for r in s["runs"] if r["id"] in keep]
    s["groups"] = [g for g in s["groups"] if g["id"] in {k.split("#")[0] for k in keep}]
    (dst / "summary.json").write_text(json.dumps(s), encoding="utf-8")
    return dst


def test_differences_within_tolerance_exit_0(suites: tuple[Path, Path], tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    a, b = suites
    keep = {"same#1", "tolerant#1"}
    va, vb = _view(a, tmp_path / "a", keep), _view(b, tmp_path / "b", keep)
    assert main(["diff", str(va), str(vb)]) == 1
    capsys.readouterr()
    assert main(["diff", str(va), str(vb), "--tolerance", "*=1", "--tolerance",
                 "/nothing=1"]) == 0
    out, err = capsys.readouterr()
    assert "  tolerant#1: PASS; recording within tolerance in " in out
    assert out.splitlines()[-1] == ("verdict: EQUAL WITHIN TOLERANCE (2 matched runs: "
                                    "recordings 1 identical, 1 within tolerance)")
    assert "srr diff: note: --tolerance '/nothing=1' matches no topic of any run" in err


@pytest.mark.parametrize(("keep_a", "keep_b", "says"), [
    ({"same#1"}, {"same#1"}, "verdict: IDENTICAL (1 matched run: recordings 1 identical)"),
    ({"same#1", "rebaselined#1"}, {"same#1", "rebaselined#1"},
     "verdict: DIFFERENT (2 matched runs: recordings 2 identical; 1 verdict changed)"),
    ({"same#1", "gone#1"}, {"same#1"},
     "verdict: DIFFERENT (1 matched run: recordings 1 identical; 1 only in A)"),
    ({"same#1"}, {"same#1", "new#1"},
     "verdict: DIFFERENT (1 matched run: recordings 1 identical; 1 only in B)"),
])
def test_a_verdict_change_or_a_run_of_one_suite_alone_is_a_difference(
        suites: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str],
        keep_a: set[str], keep_b: set[str], says: str) -> None:
    a, b = suites
    va, vb = _view(a, tmp_path / "a", keep_a), _view(b, tmp_path / "b", keep_b)
    assert main(["diff", str(va), str(vb)]) == (0 if "IDENTICAL" in says else 1)
    assert capsys.readouterr().out.splitlines()[-1] == says


def test_terminal_lines_and_json(suites: tuple[Path, Path], tmp_path: Path,
                                 capsys: pytest.CaptureFixture[str]) -> None:
    a, b = suites
    file = tmp_path / "diff.json"
    assert main(["diff", str(a), str(b), "--json", str(file)]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"A: {a}  (suite diffcheck, 7 runs, INVALID, started ")
    assert "group verdicts that changed:" in out and "  speed: PASS → REGRESSED" in out
    assert out[out.index("runs only in A (1):") + 1] == "  gone#1: MISMATCH"
    assert out[out.index("runs only in B (1):") + 1] == "  new#1: MISMATCH"
    i = out.index("runs that differ (4 of 6 matched):")
    assert [line.split(":")[0] for line in out[i + 1:i + 5]] == [
        "  speed#1", "  tolerant#1", "  rebaselined#1", "  crash#1"]
    assert out[i + 3] == "  rebaselined#1: PASS → FAIL; recording identical"
    assert out[i + 4] == "  crash#1: PASS → INVALID; recorded only in A"
    assert f"details of a pair: srr diff {a / 'runs/speed/nominal/r1'} " \
           f"{b / 'runs/speed/nominal/r1'}" in out
    assert out[-2].startswith("verdict: DIFFERENT (6 matched runs: recordings 2 identical, 3 "
                              "different, 1 recorded by neither; 3 verdicts changed; ")
    assert out[-1] == f"json: {file}"
    data = json.loads(file.read_text())
    assert {k: data[k] for k in ("verdict", "equal", "exit_code")} == {
        "verdict": "DIFFERENT", "equal": False, "exit_code": 1}
    assert data["a"]["name"] == "diffcheck" and data["b"]["runs"] == 7
    assert [r["id"] for r in data["only_in_a"]] == ["gone#1"]
    assert [r["id"] for r in data["only_in_b"]] == ["new#1"]
    assert data["groups_changed"][0] == {"id": "speed", "verdict_a": "PASS",
                                         "verdict_b": "REGRESSED"}
    pairs = {p["id"]: p for p in data["pairs"]}
    assert len(pairs) == 6 and pairs["same#1"]["recording"] == "identical"
    speed = pairs["speed#1"]
    assert (speed["verdict_a"], speed["verdict_b"], speed["verdict_changed"]) == (
        "PASS", "REGRESSED", True)
    assert speed["first_divergence"].startswith("/cmd_vel message #0 at 0.000 s: linear.x")
    assert "/cmd_vel" in [t["name"] for t in speed["topics"]]
    assert all(t["status"] != "identical" for t in speed["topics"])
    reached = next(m for m in speed["metrics_moved"] if m["name"] == "control.goal_reached")
    assert (reached["value_a"], reached["value_b"], reached["status"]) == (1.0, 0.0,
                                                                           "regressed")
    assert speed["summary"].startswith("PASS → REGRESSED; recording differs")
    assert pairs["crash#1"]["run_b"] is not None and pairs["crash#1"]["topics"] == []


def test_html_links_every_pair_and_its_details(suites: tuple[Path, Path], tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    a, b = suites
    page = tmp_path / "pages" / "suite-diff.html"
    page.parent.mkdir()
    assert main(["diff", str(a), str(b), "--html", str(page), "--no-video"]) == 1
    html = page.read_text(encoding="utf-8")
    rows = re.findall(r'<tr class="st-(\w+)" data-run="([^"]+)" data-recording="(\w+)"', html)
    assert [(run, rec) for _, run, rec in rows[:4]] == [
        ("speed#1", "differs"), ("tolerant#1", "differs"), ("rebaselined#1", "identical"),
        ("crash#1", "only_in_a")]  # those that differ first
    assert {run for _, run, _ in rows} == {"same#1", "speed#1", "tolerant#1", "rebaselined#1",
                                           "crash#1", "dead#1"}
    assert 'data-run="gone#1"' in html.split('id="only-in-a"')[1].split("</section>")[0]
    assert 'data-run="new#1"' in html.split('id="only-in-b"')[1]
    links = [unquote(h) for h in re.findall(r'href="([^"#][^"]*)"', html)]
    assert links and all(not h.startswith(("/", "http", "file:")) for h in links)
    for h in links:
        assert (page.parent / h).is_file(), h
    details = sorted(h for h in links if h.startswith("suite-diff.html.pairs/"))
    # a page per pair that differs and that both suites recorded
    assert details == ["suite-diff.html.pairs/rebaselined_1.html",
                       "suite-diff.html.pairs/speed_1.html",
                       "suite-diff.html.pairs/tolerant_1.html"]
    assert 'data-topic="/cmd_vel" data-status="differs"' in (
        page.parent / details[1]).read_text(encoding="utf-8")
    assert "http://" not in html and "https://" not in html and "<script" not in html


def _damaged(root: Path, how: str) -> Path:
    d = root / how
    (d / "runs").mkdir(parents=True)
    run = {"id": "x#1", "group": "x", "verdict": "PASS", "run_dir": "runs/x/nominal/r1",
           "report": None, "digest": "0" * 64}
    summary: object = {"format": "srr-suite/1", "name": "s", "runs": [run], "groups": []}
    if how == "bad-json":
        (d / "summary.json").write_text("{", encoding="utf-8")
        return d
    if how == "no-summary":
        return d
    assert isinstance(summary, dict)
    if how == "runs-not-a-list":
        summary["runs"] = {"x#1": run}
    elif how == "leaves-the-folder":
        run["run_dir"] = "../../etc"
    elif how == "twice":
        summary["runs"] = [run, run]
    elif how == "other-format":
        summary["format"] = "srr-search/1"
    (d / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
    return d


@pytest.mark.parametrize(("how", "says"), [
    ("bad-json", "summary.json: not valid JSON"),
    ("no-summary", "summary.json: missing (not a finished suite folder"),
    ("runs-not-a-list", "summary.json: runs: expected a list of runs"),
    ("leaves-the-folder", "summary.json: runs[0].run_dir: '../../etc' leaves the suite folder"),
    ("twice", "summary.json: runs[1].id: 'x#1' is there twice"),
    ("other-format", "summary.json: format: 'srr-search/1', expected 'srr-suite/1'"),
])
def test_a_damaged_suite_summary_is_one_line_exit_2(
        suites: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str],
        how: str, says: str) -> None:
    good = suites[0]
    bad = _damaged(tmp_path, how)
    page = tmp_path / "diff.html"
    for args in ([str(good), str(bad)], [str(bad), str(good)]):
        assert main(["diff", *args, "--html", str(page)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith(f"srr diff: {bad}"), err
        assert says in err and "Traceback" not in err
        assert not page.exists()


def test_a_suite_against_a_run_or_a_summary_file_is_one_line_exit_2(
        suites: tuple[Path, Path], tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    a, b = suites
    run = a / "runs/same/nominal/r1"
    for args, says in (
            ([a, run], f"srr diff: {run}: not a suite folder; {a} is one: srr diff compares "
                       "two suite folders, or two runs"),
            ([run, b], f"srr diff: {run}: not a suite folder; {b} is one"),
            ([a, tmp_path / "nope"], f"srr diff: {tmp_path / 'nope'}: no such directory; {a} "
                                     "is one"),
            ([a, b / "summary.json"], f"srr diff: {b / 'summary.json'}: the summary of the "
                                      f"suite {b}: give the suite folder")):
        assert main(["diff", *map(str, args)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith(says), err
    with pytest.raises(SrrError, match="--tolerance"):
        api.diff_suites(a, b, tolerances=["/odom=x"])


def test_a_damaged_bag_is_bad_input_where_it_is_read(suites: tuple[Path, Path],
                                                     tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]
                                                     ) -> None:
    """The digests decide which bags are read: a bag cut short where the digests agree goes
    unnoticed (the summaries are trusted); where they differ it is one line, exit 2."""
    a, b = suites
    keep = {"same#1", "speed#1"}
    va, vb = _view(a, tmp_path / "a", keep), tmp_path / "b"
    vb.mkdir()
    shutil.copytree(b / "runs" / "same", vb / "runs" / "same")
    shutil.copytree(b / "runs" / "speed", vb / "runs" / "speed")
    s = json.loads((b / "summary.json").read_text())
    s["runs"] = [r for r in s["runs"] if r["id"] in keep]
    (vb / "summary.json").write_text(json.dumps(s), encoding="utf-8")
    for entry in ("same", "speed"):
        (mcap,) = (vb / "runs" / entry / "nominal/r1/bag").glob("*.mcap")
        mcap.write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    assert main(["diff", str(va), str(vb)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert err.startswith(f"srr diff: {vb / 'runs/speed/nominal/r1/bag'}"), err
