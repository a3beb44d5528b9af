"""The suite page (``OUT/index.html``) built from a suite summary: groups worst first with
links that resolve inside the folder, flakiness, statistics, sweep plots (dots, bands, the
verdict boundary) and history sparklines; then the page in a real headless Chromium.

The summary is built in the schema by :class:`tests.suite.fake_summary.SuiteBuilder`; every
repeat with a report links to a copy of a real run's ``report.html`` (the shared short
failing run of these tests).
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote, urlparse

import numpy as np
import pytest

from harness import api
from harness.metrics.safety import NEAR_AT, PASS_AT
from harness.report import render_suite_page, write_suite_page
from harness.report.suite_page import VERDICT_ORDER
from harness.report.templates import VERDICT_COLORS
from harness.suite.history import load_history
from tests.conftest import ModuleTmp
from tests.report.browser import VIEWPORT, page_requests, run_chromium
from tests.report.pngread import read_png
from tests.suite.fake_summary import FakeRun, SuiteBuilder

SPEEDS = (0.6, 1.0, 1.4, 1.8)
MATCH = {0.6: (99.1, 99.0, 99.2), 1.0: (97.5, 97.8, 97.6), 1.4: (88.0, 87.5, 88.4),
         1.8: (72.0, 70.5, 71.0)}
VERDICT_AT = {0.6: "PASS", 1.0: "PASS", 1.4: "REGRESSED", 1.8: "FAIL"}
MODES = ("strict", "normal", "lenient")


def _speed_sweep(b: SuiteBuilder) -> None:
    """workers.0.speed 0.6 … 1.8, 3 repeats each: the monitor's match rate falls from PASS
    through NEAR (regressed) to FAIL; 1.8 has no baseline."""
    ids = []
    for v in SPEEDS:
        runs = [FakeRun(VERDICT_AT[v], {"safety.match_rate": m,
                                        "control.cross_track_error.max": 0.30 + 0.02 * k,
                                        "control.goal_reached": 1.0 if v < 1.8 or k else 0.0},
                        reasons=() if VERDICT_AT[v] == "PASS" else ("see the report",))
                for k, m in enumerate(MATCH[v])]
        base = None if v == 1.8 else {"safety.match_rate": (97.0 if v > 1.0 else 99.0, 2.0),
                                      "control.cross_track_error.max": (0.31, 0.05),
                                      "control.goal_reached": (1.0, 0.0)}
        ids.append(b.group("dock_worker_crossing", runs, params={"workers.0.speed": v},
                           sweep="dock_worker_crossing", baselines=base))
    b.sweep("dock_worker_crossing", ["workers.0.speed"], ids)


def _mode_sweep(b: SuiteBuilder) -> None:
    """A 2-parameter grid with strings on x: mode × worker speed, 2 repeats; only the lenient
    monitor with the fast worker fails."""
    ids = []
    for speed in (0.8, 1.6):
        for mode in MODES:
            verdict = "FAIL" if (mode, speed) == ("lenient", 1.6) else "PASS"
            rate = 70.0 if verdict == "FAIL" else 98.0
            runs = [FakeRun(verdict, {"safety.match_rate": rate + k}) for k in range(2)]
            ids.append(b.group("monitor_modes", runs,
                               params={"systems_under_test.1.params.mode": mode,
                                       "workers.0.speed": speed}, sweep="monitor_modes",
                               baselines={"safety.match_rate": (98.0, 2.0)}))
    b.sweep("monitor_modes", ["systems_under_test.1.params.mode", "workers.0.speed"], ids)


def build_suite(out: Path, report: Path) -> dict[str, Any]:
    b = SuiteBuilder(out, report)
    b.group("forklift_nominal", [FakeRun("PASS", {"safety.match_rate": 99.0})] * 2,
            baselines={"safety.match_rate": (99.0, 1.0)},  # PASS first: the page must sort
            against_baseline={"digest_matches": False, "topics_differing": ["/odom", "/tf"],
                              "versions_differing": {"numpy": {"baseline": "2.4.6",
                                                               "run": "2.5.2"}}})
    _speed_sweep(b)
    regressed = {f"control.{m}": 2.0 for m in ("cross_track_error.max", "cross_track_error.mean",
                                               "heading_error.max")}
    regressed |= {"perception.recall": 0.5, "perception.precision": 0.6}
    b.group("perception_dock", [FakeRun("REGRESSED", regressed)],
            baselines={m: (0.9 if m.startswith("perception") else 0.3, 0.05) for m in regressed},
            reasons=["control.cross_track_error.max regressed"])
    b.group("forklift_warehouse", [FakeRun("PASS", digest="ab12" * 16),
                                   FakeRun("REGRESSED", digest="cd34" * 16),
                                   FakeRun("PASS", digest="ab12" * 16)],
            verdict="FLAKY", flaky_detail={
                "verdicts": ["PASS", "REGRESSED", "PASS"],
                "digests": ["ab12" * 16, "cd34" * 16, "ab12" * 16],
                "differing_topics": ["/cmd_vel", "/odom"],
                "first_divergence": "/cmd_vel message #0 at 0.000 s: linear.x: 1.5 vs 1.2",
                "compared": ["forklift_warehouse#1", "forklift_warehouse#2"]},
            reasons=["flaky over 3 repeats (PASS / REGRESSED / PASS): digests differ on "
                     "/cmd_vel, /odom"])
    b.group("turtlebot_teleop", [
        FakeRun("INVALID", crash="killed by signal SIGSEGV (a segmentation fault)"),
        FakeRun("INVALID", timed_out=True)],
        reasons=["#1: the worker crashed: killed by signal SIGSEGV", "#2: timed out"])
    _mode_sweep(b)
    return b.summary()


@pytest.fixture(scope="module")
def suite(failing_run: api.RunResult,
          module_tmp: ModuleTmp) -> tuple[Path, dict[str, Any], str]:
    out = module_tmp("suite")
    summary = build_suite(out, failing_run.run_dir / "report.html")
    (out / "summary.json").write_text(json.dumps(summary, indent=1), encoding="utf-8")
    page = write_suite_page(out, summary)
    return page, summary, page.read_text(encoding="utf-8")


def _between(html: str, start: str, end: str) -> str:
    i = html.index(start)
    return html[i:html.index(end, i)]


def _figure(html: str, sweep: str, metric: str) -> ET.Element:
    """The SVG of one sweep figure, parsed."""
    block = _between(html, f'<div class="sweep" data-sweep="{sweep}"', "</div></div>")
    fig = _between(block, f'<figure class="sweep-fig" data-metric="{metric}"', "</figure>")
    return ET.fromstring(_between(fig, "<svg", "</svg>") + "</svg>")


def _cls(e: ET.Element) -> list[str]:
    return (e.get("class") or "").split()


def _all(svg: ET.Element, cls: str) -> list[ET.Element]:
    return [e for e in svg.iter() if cls in _cls(e)]


def _ticks(svg: ET.Element) -> dict[str, float]:
    return {e.text or "": float(e.get("x", "nan")) for e in _all(svg, "x-tick")}


# --------------------------------------------------------------------------- groups table


@pytest.mark.slow
def test_groups_are_worst_first_and_every_link_resolves(suite: tuple[Path, dict, str]) -> None:
    page, summary, html = suite
    table = _between(html, '<table class="groups-table"', "</tbody>")
    order = re.findall(r'<tr data-group="[^"]*" data-verdict="([A-Z]+)"', table)
    assert len(order) == len(summary["groups"])
    assert [VERDICT_ORDER.index(v) for v in order] == sorted(
        VERDICT_ORDER.index(v) for v in order)
    assert order[:2] == ["INVALID", "FLAKY"] and order[-1] == "PASS"
    hrefs = re.findall(r'href="([^"]+)"', html)
    files = [h for h in hrefs if not h.startswith("#")]
    assert files and all(not h.startswith(("/", "http", "file:")) for h in files)
    for h in files:
        assert (page.parent / unquote(h)).is_file(), h
    for run in summary["runs"]:  # every repeat's report is linked, no report no link
        if run["report"]:
            assert f'href="{quote(run["report"], safe="/._-~")}"' in html
    for anchor in {h[1:] for h in hrefs if h.startswith("#")}:
        assert f'id="{anchor}"' in html
    banner = _between(html, '<header class="banner', "</header>")
    assert 'data-verdict="INVALID"' in banner and "wall time 123.4 s" in banner
    assert "executor local, 2 jobs" in banner and "started 2026-11-23T02:00:00Z" in banner
    assert '<span data-count="FLAKY">1 FLAKY</span>' in banner
    assert 'id="interrupted"' not in banner


@pytest.mark.slow
def test_key_lines_show_regressions_with_delta_and_count_the_rest(
        suite: tuple[Path, dict, str]) -> None:
    html = suite[2]
    row = _between(html, '<tr data-group="perception_dock"', "</tr>")
    keys = re.findall(r"<li>([^<]*)</li>", _between(row, '<ul class="key">', "</ul>"))
    assert len(keys) == 3 and "+2 more" in row
    # worst excess first: cross_track_error/heading error moved 1.7 / 0.05 = 34 tolerances
    assert keys[0].startswith("control.") and "vs baseline 0.3 m" in keys[0]
    assert "delta +1.7 m" in keys[0] and "tolerance ±0.05" in keys[0]
    # no regressed metric: the group's reasons instead
    invalid = _between(html, '<tr data-group="turtlebot_teleop"', "</tr>")
    assert "the worker crashed: killed by signal SIGSEGV" in invalid


@pytest.mark.slow
def test_runs_without_a_report_say_why_and_link_the_log(suite: tuple[Path, dict, str]) -> None:
    page, summary, html = suite
    row = _between(html, '<tr data-group="turtlebot_teleop"', "</tr>")
    first = _between(row, 'data-run="turtlebot_teleop#1"', "</li>")
    second = _between(row, 'data-run="turtlebot_teleop#2"', "</li>")
    assert "report</a>" not in first and "report</a>" not in second
    assert "crashed: killed by signal SIGSEGV (a segmentation fault)" in first
    assert "timed out after 60 s" in second
    runs = {r["id"]: r for r in summary["runs"]}
    for cell, rid in ((first, "turtlebot_teleop#1"), (second, "turtlebot_teleop#2")):
        log = re.search(r'<a href="([^"]+)">log</a>', cell)
        assert log and log.group(1) == runs[rid]["log"]
        assert (page.parent / log.group(1)).is_file()


@pytest.mark.slow
def test_a_group_that_recorded_other_bytes_than_its_baseline_says_so(
        suite: tuple[Path, dict, str]) -> None:
    html = suite[2]
    row = _between(html, '<tr data-group="forklift_nominal"', '<ul class="runs">')
    assert ('<div class="note other-bytes">recording differs from the baseline&#39;s in 2 '
            "topics (/odom, /tf); versions differ: numpy 2.4.6 → 2.5.2</div>") in row
    assert html.count("other-bytes") == 1  # not the flaky group, not the others


@pytest.mark.slow
def test_flaky_group_names_topics_divergence_and_each_repeat(
        suite: tuple[Path, dict, str]) -> None:
    html = suite[2]
    row = _between(html, '<tr data-group="forklift_warehouse"', '<ul class="runs">')
    flaky = _between(row, '<div class="flaky">', "</table></div>")
    assert "<code>/cmd_vel</code>, <code>/odom</code>" in flaky
    assert "linear.x: 1.5 vs 1.2" in flaky
    assert "forklift_warehouse#1 vs forklift_warehouse#2" in flaky
    repeats = re.findall(r'<td>(#\d)</td><td><span class="badge b-v-(\w+)">.*?title="(\w+)"',
                         flaky, re.S)
    assert repeats == [("#1", "PASS", "ab12" * 16), ("#2", "REGRESSED", "cd34" * 16),
                       ("#3", "PASS", "ab12" * 16)]


@pytest.mark.slow
def test_statistics_table_per_group(suite: tuple[Path, dict, str]) -> None:
    html = suite[2]
    details = re.findall(r'<details class="group-stats" id="g\d+" data-group="([^"]+)"', html)
    assert sorted(details) == sorted(g["id"] for g in suite[1]["groups"])
    block = _between(html, 'data-group="dock_worker_crossing[workers.0.speed=1.4]">',
                     "</details>")
    row = _between(block, 'data-metric="safety.match_rate"', "</tr>")
    cells = re.findall(r'<td class="num">([^<]*)</td>', row)
    # mean ± std, 95 % CI, min / max, n, baseline ± tolerance
    assert cells[0] == "87.97 % ± 0.451" and cells[1].count("%") == 2
    assert cells[2] == "87.5 % / 88.4 %" and cells[3] == "3" and cells[4] == "97 % ± 2"
    assert "b-regressed" in row and "b-NEAR" in row
    # safety first in the table
    assert block.index('data-metric="safety.match_rate"') < block.index(
        'data-metric="control.cross_track_error.max"')


# --------------------------------------------------------------------------- sweeps


@pytest.mark.slow
def test_sweep_dots_bands_and_boundaries(suite: tuple[Path, dict, str]) -> None:
    html = suite[2]
    block = _between(html, '<div class="sweep" data-sweep="dock_worker_crossing"', "</div></div>")
    metrics = re.findall(r'<figure class="sweep-fig" data-metric="([^"]+)"', block)
    assert metrics[0] == "safety.match_rate"
    svg = _figure(html, "dock_worker_crossing", "safety.match_rate")
    dots = _all(svg, "dot")
    assert len(dots) == len(SPEEDS) * 3
    bands = {e.get("data-verdict"): e for e in _all(svg, "band")}
    assert set(bands) == {"PASS", "NEAR", "FAIL"}
    assert bands["PASS"].get("data-lo") == f"{PASS_AT:g}"
    assert bands["NEAR"].get("data-lo") == f"{NEAR_AT:g}"
    assert bands["FAIL"].get("data-hi") == f"{NEAR_AT:g}"

    def inside(y: float, band: ET.Element) -> bool:
        top, h = float(band.get("y", "nan")), float(band.get("height", "nan"))
        return top - 0.1 <= y <= top + h + 0.1

    for d in dots:  # every dot lies in the band its value belongs to, in its verdict colour
        v, y = float(d.get("data-value", "nan")), float(d.get("cy", "nan"))
        want = "PASS" if v >= PASS_AT else "NEAR" if v >= NEAR_AT else "FAIL"
        assert inside(y, bands[want]), (v, want)
        assert d.get("fill") == VERDICT_COLORS[VERDICT_AT[float(d.get("data-x", "nan"))]]
    ticks = _ticks(svg)
    assert list(ticks) == ["0.6", "1", "1.4", "1.8"]
    gaps = np.diff([ticks[k] for k in ticks])
    assert np.allclose(gaps, gaps[0], atol=0.2)  # numeric axis: equal steps, equal gaps
    marks = {e.get("data-between"): float(e.get("x1", "nan")) for e in _all(svg, "boundary")}
    assert set(marks) == {"1|1.4", "1.4|1.8"}
    assert marks["1|1.4"] == pytest.approx((ticks["1"] + ticks["1.4"]) / 2, abs=0.11)
    assert marks["1.4|1.8"] == pytest.approx((ticks["1.4"] + ticks["1.8"]) / 2, abs=0.11)
    assert "PASS → REGRESSED: boundary between workers.0.speed = 1 and 1.4" in block
    assert "REGRESSED → FAIL: boundary between workers.0.speed = 1.4 and 1.8" in block
    # the mean line has one vertex per group
    line = _all(svg, "mean-line")
    assert len(line) == 1 and len(line[0].get("points", "").split()) == len(SPEEDS)


@pytest.mark.slow
def test_tolerance_band_follows_the_points_and_stops_without_baseline(
        suite: tuple[Path, dict, str]) -> None:
    html = suite[2]
    svg = _figure(html, "dock_worker_crossing", "control.cross_track_error.max")
    assert not _all(svg, "band")  # no fixed bands for a plain metric
    tol = _all(svg, "tol-band")
    assert len(tol) == 1 and tol[0].get("data-points") == "3"
    ticks = _ticks(svg)
    xs = {round(float(p.split(",")[0]), 1) for p in tol[0].get("points", "").split()}
    assert xs == {round(ticks[k], 1) for k in ("0.6", "1", "1.4")}  # absent at 1.8
    fig = _between(html, '<figure class="sweep-fig" data-metric="control.cross_track_error.max"',
                   "</figure>")
    assert "no baseline at 1.8: no band there" in fig
    goal = _figure(html, "dock_worker_crossing", "control.goal_reached")
    bands = {e.get("data-verdict"): e for e in _all(goal, "band")}
    assert set(bands) == {"PASS", "FAIL"} and bands["PASS"].get("data-lo") == "0.5"
    assert [e.get("data-value") for e in _all(goal, "threshold")] == ["0.5"]


@pytest.mark.slow
def test_string_sweep_is_equally_spaced_with_one_line_per_second_parameter(
        suite: tuple[Path, dict, str]) -> None:
    html = suite[2]
    svg = _figure(html, "monitor_modes", "safety.match_rate")
    ticks = _ticks(svg)
    assert list(ticks) == list(MODES)  # declaration order, labelled
    xs = [ticks[m] for m in MODES]
    assert xs[1] - xs[0] == pytest.approx(xs[2] - xs[1], abs=0.11)
    assert len(_all(svg, "dot")) == 6 * 2
    lines = {e.get("data-series"): e for e in _all(svg, "mean-line")}
    assert set(lines) == {"0.8", "1.6"}
    marks = _all(svg, "boundary")
    assert [(e.get("data-between"), e.get("data-series")) for e in marks] == [
        ("normal|lenient", "1.6")]
    assert float(marks[0].get("x1", "nan")) == pytest.approx((xs[1] + xs[2]) / 2, abs=0.11)
    block = _between(html, '<div class="sweep" data-sweep="monitor_modes"', "</div></div>")
    assert ("PASS → FAIL: boundary between systems_under_test.1.params.mode = normal and "
            "lenient (with 1.6)") in block


# --------------------------------------------------------------------------- history


def _night(root: Path, folder: str, started: str, summary: dict[str, Any],
           match_rate: float | None) -> None:
    """An earlier night: tonight's summary with another start time and match rates."""
    s = json.loads(json.dumps(summary))
    s["started_at"] = started
    s["verdict"] = "PASS"
    for g in s["groups"]:
        g["verdict"] = "PASS"
        if match_rate is None:
            g["stats"].pop("safety.match_rate", None)
        elif "safety.match_rate" in g["stats"]:
            g["stats"]["safety.match_rate"]["mean"] = match_rate
        g["stats"].pop("control.goal_reached", None)  # new tonight
    (root / folder).mkdir(parents=True)
    (root / folder / "summary.json").write_text(json.dumps(s), encoding="utf-8")


@pytest.mark.slow
def test_history_sparklines_one_point_per_night(suite: tuple[Path, dict, str],
                                                tmp_path: Path) -> None:
    _, summary, _ = suite
    hist = tmp_path / "history"
    # folder names do not sort by time: nights are ordered by started_at
    _night(hist, "c", "2026-11-20T02:00:00Z", summary, 98.0)
    _night(hist, "a", "2026-11-22T02:00:00Z", summary, 96.0)
    _night(hist, "b", "2026-11-21T02:00:00Z", summary, None)
    (hist / "broken").mkdir()
    (hist / "broken" / "summary.json").write_text('{"format": "srr-suite/1", "gro',
                                                  encoding="utf-8")
    block = load_history([hist], summary)
    assert any("broken" in w and "not valid JSON" in w for w in block["warnings"])
    s = dict(summary, history=block)
    out = tmp_path / "out"
    html = write_suite_page(out, s).read_text(encoding="utf-8")
    sect = _between(html, '<section id="history">', "</section>")
    assert "4 nights" in sect and "not valid JSON" in sect
    gid = "dock_worker_crossing[workers.0.speed=1.4]"
    group = _between(sect, f'data-group="{gid}"', "</details>")
    row = _between(group, 'data-metric="safety.match_rate"', "</tr>")
    svg = ET.fromstring(_between(row, "<svg", "</svg>") + "</svg>")
    nights = _all(svg, "night")
    assert len(nights) == 4
    assert [("missing" in _cls(e), "tonight" in _cls(e)) for e in nights] == [
        (False, False), (True, False), (False, False), (False, True)]
    assert "missing on 1 of 3 earlier nights (2026-11-21T02:00:00Z)" in row
    goal = _between(group, 'data-metric="control.goal_reached"', "</tr>")
    assert "new tonight" in goal
    strip = _between(group, "group verdict per night", "</tr>")
    cells = re.findall(r'class="strip-cell[^"]*"[^>]*data-verdict="(\w*)"', strip)
    assert cells == ["PASS", "PASS", "PASS", "REGRESSED"]
    assert f'<details class="group-history" data-group="{gid}" open>' in sect


@pytest.mark.slow
def test_interrupted_suite_says_so(suite: tuple[Path, dict, str], tmp_path: Path) -> None:
    s = dict(suite[1], interrupted=True, verdict="INTERRUPTED", exit_code=130)
    html = write_suite_page(tmp_path, s).read_text(encoding="utf-8")
    banner = _between(html, '<header class="banner', "</header>")
    assert 'class="banner v-INTERRUPTED"' in banner and 'id="interrupted"' in banner
    assert "exit code 130" in banner


@pytest.mark.slow
def test_page_is_deterministic_and_drops_links_to_missing_files(
        suite: tuple[Path, dict, str], tmp_path: Path) -> None:
    page, summary, html = suite
    copy = json.loads(json.dumps(summary))
    assert render_suite_page(copy, root=page.parent) == html
    # the same summary written elsewhere: nothing it points to is there
    other = write_suite_page(tmp_path, copy).read_text(encoding="utf-8")
    assert not [h for h in re.findall(r'href="([^"]+)"', other) if not h.startswith("#")]
    assert "runs/forklift_nominal/nominal/r1/report.html is missing from this folder" in other


def test_hostile_summary_fields_do_not_break_the_page(tmp_path: Path) -> None:
    """Odd values in a summary give a page, never a traceback; links out of the folder are
    not made."""
    s: dict[str, Any] = {
        "format": "srr-suite/1", "name": "<script>x</script>", "verdict": "WEIRD",
        "groups": [{"id": "g", "verdict": "PASS", "stats": {"m": {"mean": "NaN"}},
                    "params": [1], "runs": ["g#1", "g#2"]},
                   {"id": "h", "verdict": 3, "stats": None, "flaky": True}],
        "runs": [{"id": "g#1", "report": "../../etc/passwd", "log": "/abs.log"}],
        "sweeps": [{"name": "s", "params": ["p"], "groups": ["g", "missing"]}, {"params": []}],
        "history": {"nights": [{"started_at": "x"}], "series": {"g": {"m": "x"}}},
    }
    html = write_suite_page(tmp_path, s).read_text(encoding="utf-8")
    assert "<script>x" not in html and "&lt;script&gt;" in html
    assert "etc/passwd" not in re.findall(r'href="([^"]+)"', html)
    assert not [h for h in re.findall(r'href="([^"]+)"', html) if not h.startswith("#")]


# --------------------------------------------------------------------------- in Chromium

PROBE = """<script>
(function () {
  var out = {svgs: Array.prototype.map.call(document.querySelectorAll(
      "#sweeps svg, #groups table"), function (s) {
        var b = s.getBoundingClientRect(); return [b.width, b.height]; }),
    banner: document.getElementById("verdict").getBoundingClientRect().height,
    links: Array.prototype.map.call(document.querySelectorAll("a[href]"), function (a) {
        return a.href; })};
  var pre = document.createElement("pre"); pre.id = "probe";
  pre.textContent = JSON.stringify(out); document.body.appendChild(pre);
})();
</script>"""


@pytest.mark.slow
def test_console_detector_catches_errors(chromium: str, tmp_path: Path) -> None:
    page = tmp_path / "bad.html"
    page.write_text("<script>console.error('boom'); notAFunction();</script>")
    console: list[str] = []
    run_chromium(chromium, tmp_path, page.as_uri(), ["--dump-dom"], console=console)
    assert any("boom" in c for c in console) and any("notAFunction" in c for c in console)


@pytest.mark.slow
def test_page_in_chromium(chromium: str, suite: tuple[Path, dict, str],
                          tmp_path: Path) -> None:
    page, _, html = suite
    console: list[str] = []
    run_chromium(chromium, tmp_path, page.as_uri(),
                 ["--dump-dom", f"--log-net-log={tmp_path / 'net.json'}"], console=console)
    assert page_requests(tmp_path / "net.json") == []
    assert console == []
    probe = page.with_name("probe.html")  # beside the page, so relative links resolve alike
    probe.write_text(html.replace("</body>", PROBE + "</body>"), encoding="utf-8")
    try:
        dom = run_chromium(chromium, tmp_path, probe.as_uri(), ["--dump-dom"])
    finally:
        probe.unlink()
    found = re.search(r'<pre id="probe">(.*?)</pre>', dom, re.S)
    assert found, "the probe did not run"
    data = json.loads(found.group(1).replace("&amp;", "&").replace("&lt;", "<")
                      .replace("&gt;", ">").replace("&quot;", '"'))
    assert data["svgs"] and all(w > 100 and h > 50 for w, h in data["svgs"])
    files = [u for u in data["links"] if not urlparse(u).fragment]
    assert len(files) > 20
    for u in files:
        assert Path(unquote(urlparse(u).path)).is_file(), u
    shot = tmp_path / "shot.png"
    run_chromium(chromium, tmp_path, page.as_uri(), [f"--screenshot={shot}"])
    px = read_png(shot.read_bytes())[:, :, :3]
    assert px.shape[:2] == (VIEWPORT[1], VIEWPORT[0])
    packed = (px[..., 0].astype(np.uint32) << 16) | (px[..., 1].astype(np.uint32) << 8) \
        | px[..., 2]
    assert len(np.unique(packed)) > 50
    banner = tuple(int(VERDICT_COLORS["INVALID"][i:i + 2], 16) for i in (1, 3, 5))
    top = px[:60].reshape(-1, 3)
    assert float((np.abs(top.astype(int) - banner).sum(axis=1) <= 6).mean()) > 0.5
