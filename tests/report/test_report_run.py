"""The report of a real (short) failing run: what it holds, that it is self-contained, that
``srr report`` re-renders it, and that the plotted series are what was scored."""

from __future__ import annotations

import copy
import json
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from harness import api
from harness.cli import main
from harness.errors import SrrError
from harness.report import html as report_html
from harness.report import render_report
from harness.report.data import load_run, metric_windows
from harness.report.images import keyframes

pytestmark = pytest.mark.slow

# attributes through which a page can make the browser fetch something
URL_ATTRS = {"src", "href", "xlink:href", "srcset", "poster", "data", "action", "formaction",
             "background", "manifest", "ping", "cite", "longdesc", "codebase"}


class _Refs(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.refs: list[tuple[str, str, str]] = []
        self.tags: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append(tag)
        for k, v in attrs:
            if v is not None and (k in URL_ATTRS or k == "style"):
                self.refs.append((tag, k, v))


def test_run_writes_a_self_contained_report(failing_run: api.RunResult) -> None:
    assert failing_run.verdict == "REGRESSED" and failing_run.exit_code == 1
    html = (failing_run.run_dir / "report.html").read_text(encoding="utf-8")
    parser = _Refs()
    parser.feed(html)
    remote = [r for r in parser.refs if re.search(r"(?i)(https?:)?//", r[2])
              and not r[2].startswith("data:")]
    assert remote == [], f"remote references: {remote[:5]}"
    for tag, attr, value in parser.refs:
        if attr in ("src", "href") and not value.startswith(("data:image/png;base64,", "#")):
            # the camera videos: files of the run directory, linked relatively
            assert value.startswith("video/") and value.endswith(".webm"), (tag, attr, value)
            assert (failing_run.run_dir / value).is_file()
    assert "link" not in parser.tags
    assert not any(tag == "script" and attr == "src" for tag, attr, _ in parser.refs)
    assert "iframe" not in parser.tags and "object" not in parser.tags
    assert not re.search(r"(?i)@import|@font-face|url\(\s*['\"]?(https?:)?//", html)
    assert "mermaid.js" not in html and "mermaid.min.js" not in html


def test_report_leads_with_what_regressed(failing_run: api.RunResult, summary: dict) -> None:
    html = (failing_run.run_dir / "report.html").read_text(encoding="utf-8")
    regressed = [e["name"] for e in summary["comparison"] if e["status"] == "regressed"]
    assert "safety.mute_lag.max" in regressed
    head = html[html.index('id="headline"'):html.index('id="focus"')]
    for name in regressed:
        assert f'data-metric="{name}"' in head
    assert 'data-metric="perception.f1"' not in head  # ok rows stay in the full table
    # the headline shows the lag metric's window (edge -> response)
    row = head[head.index('data-metric="safety.mute_lag.max"'):]
    row = row[:row.index("</tr>")]
    (window,) = metric_windows("safety.mute_lag.max", load_run(failing_run.run_dir))
    assert f"{window[0]:.2f}–{window[1]:.2f}" in row
    # the focus panel is the safety group's, with the regressed windows outlined
    focus = html[html.index('id="focus"'):html.index('id="map"')]
    groups = re.findall(r'data-group="(\w+)"', focus)
    assert groups[0] == "safety" and 'class="hl-box"' in focus


def test_series_agree_with_the_metrics(failing_run: api.RunResult, summary: dict) -> None:
    data = load_run(failing_run.run_dir)
    assert data.problems == []
    metrics = {m["name"]: m for m in summary["metrics"]}
    s = data.safety
    assert s is not None
    for kind in ("over", "under"):
        longs = [[w.start_s, w.end_s] for w in s.mismatches if w.kind == kind and w.long]
        np.testing.assert_allclose(longs, metrics[f"safety.{kind}_mute"]["windows"] or
                                   np.zeros((0, 2)), atol=1e-6)
    match = 100.0 * float((s.actual == s.expected).mean())
    assert match == pytest.approx(metrics["safety.match_rate"]["value"])
    for kind in ("mute", "unmute"):
        lags = [e.lag_s for e in s.edges if e.kind == kind and e.lag_s is not None]
        assert max(lags) == pytest.approx(metrics[f"safety.{kind}_lag.max"]["value"])
    assert len(data.control) == 1
    c = data.control[0]
    assert c.source == "ground truth" and c.prefix == "control."
    assert c.cte.max() == pytest.approx(metrics["control.cross_track_error.max"]["value"])
    assert c.cte.mean() == pytest.approx(metrics["control.cross_track_error.mean"]["value"])
    assert [m.number for m in data.moments] == list(range(1, len(data.moments) + 1))
    starts = {round(m.t_s, 6) for m in data.moments}
    assert all(round(w.start_s, 6) in starts for w in s.mismatches if w.long)
    targets = [round(m.t_s * 1e9) for m in data.moments]
    frames = keyframes(failing_run.run_dir / "bag", targets)
    for t in targets:  # each rgb camera (5 Hz) once, its nearest image; depth left out
        assert sorted(k.topic for k in frames[t]) == ["/dock_cam_left_rgb",
                                                      "/dock_cam_right_rgb"]
        assert all(abs(k.t_ns - t) <= 100_000_000 for k in frames[t])
        assert all(k.png.startswith(b"\x89PNG") and (k.width, k.height) == (160, 120)
                   for k in frames[t])


def test_srr_report_rerenders_the_same_page(failing_run: api.RunResult,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    path = failing_run.run_dir / "report.html"
    before = path.read_bytes()
    path.unlink()
    assert main(["report", str(failing_run.run_dir)]) == 0
    assert capsys.readouterr().out.strip() == str(path)
    assert path.read_bytes() == before  # from the run directory alone, byte for byte


@pytest.mark.parametrize("what", ["missing", "not-a-run", "bad-json"])
def test_srr_report_refuses_what_is_not_a_run(tmp_path: Path, what: str,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "x"
    if what != "missing":
        target.mkdir()
    if what == "bad-json":
        (target / "summary.json").write_text("{", encoding="utf-8")
    assert main(["report", str(target)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("srr report: ") and str(target) in err
    assert "Traceback" not in err


def _variant(summary: dict, **changes: object) -> dict:
    s = copy.deepcopy(summary)
    s.update(changes)
    return s


def test_no_baseline_shows_values_only(failing_run: api.RunResult, summary: dict) -> None:
    note = "no baseline at baselines/x.json: bless one with `srr baseline bless RUN_DIR`"
    s = _variant(summary, verdict="FAIL", exit_code=1, reasons=[note], baseline=None,
                 comparison=[])
    html = render_report(failing_run.run_dir, summary=s)
    assert 'data-verdict="FAIL"' in html and "No baseline: metric values only" in html
    assert "<th class=\"num\">baseline</th>" not in html
    table = html[html.index('id="metrics"'):html.index('id="health"')]
    assert all(f'data-metric="{m["name"]}"' in table for m in summary["metrics"])


def test_invalid_run_leads_with_tripped_gates(failing_run: api.RunResult,
                                              summary: dict) -> None:
    health = copy.deepcopy(summary["health"])
    health[0]["ok"] = False
    health[0]["detail"] = "1.0 Hz (13 messages); expected 60 Hz"
    s = _variant(summary, verdict="INVALID", exit_code=3, health=health,
                 reasons=[f"health {health[0]['name']}: {health[0]['detail']}"])
    html = render_report(failing_run.run_dir, summary=s)
    head = html[html.index('id="headline"'):]
    assert "Tripped health gates" in head[:400] and health[0]["detail"] in head[:1500]
    assert 'id="focus"' not in html


def test_interrupted_run_renders(failing_run: api.RunResult, summary: dict) -> None:
    s = _variant(summary, verdict="INTERRUPTED", exit_code=130, interrupted=True,
                 reasons=["interrupted before the end of the scenario"])
    html = render_report(failing_run.run_dir, summary=s)
    assert 'class="banner v-INTERRUPTED"' in html
    # its (regressed) comparison is of a shorter run: not judged, not headlined as regressions
    assert any(e.get("status") == "regressed" for e in s["comparison"])
    head = html[html.index('id="headline"'):][:600]
    assert "Regressed metrics" not in head
    assert "not judged against the baseline" in head


def test_summary_is_kept_when_the_report_fails(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args: object, **kwargs: object) -> None:
        raise RuntimeError("boom")

    monkeypatch.setattr(report_html, "write_report", broken)  # the run imports it at its end
    sc = api.load(Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml",
                  duration=0.5)
    with pytest.raises(SrrError, match=r"report\.html.*boom"):
        api.run_scenario(sc, out=tmp_path / "r")
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["verdict"]


def test_the_report_overlays_the_baseline_from_its_reference_recording(
        failing_run: api.RunResult, tmp_path: Path) -> None:
    """The baseline was blessed with a reference recording; the regressed run's report draws
    both runs on one map and overlays their time series, without the baseline's run dir."""
    ref = Path(failing_run.summary["baseline"]["reference"])
    assert ref.suffix == ".mcap" and ref.is_file()
    html = (failing_run.run_dir / "report.html").read_text(encoding="utf-8")
    section = html[html.index('<section id="against">'):]
    section = section[:section.index("</section>")]
    assert "run-a" in section and "run-b" in section  # baseline and this run, both drawn
    assert "baseline: robot (ground truth)" in section and "this run: robot" in section
    assert section.count('class="panel') >= 2  # safety and control, overlaid
    # without the reference file the report says so and draws no overlay
    moved = tmp_path / ref.name
    ref.rename(moved)
    try:
        again = render_report(failing_run.run_dir)
    finally:
        moved.rename(ref)
    assert 'id="against"' not in again and "reference recording" in again and "is gone" in again


def test_the_run_writes_its_graphs_and_the_report_draws_them_from_there(
        failing_run: api.RunResult, summary: dict, tmp_path: Path) -> None:
    run = failing_run.run_dir
    sc = api.load(run / "scenario.yaml")
    source = summary["scenario_file"]
    # the files are what `srr graph` prints for the scene as run
    assert (run / "graphs.json").read_text(encoding="utf-8") == \
        api.graph_text(sc, "json", source=source)
    assert (run / "graphs.mmd").read_text(encoding="utf-8") == \
        api.graph_text(sc, "mermaid", source=source)
    # the page draws the file, not a scene built again: an edited file shows up
    copy = tmp_path / "run"
    shutil.copytree(run, copy)
    dump = json.loads((copy / "graphs.json").read_text(encoding="utf-8"))
    dump["graphs"][0]["path"] = "/World/DrawnFromTheFileGraph"
    (copy / "graphs.json").write_text(json.dumps(dump), encoding="utf-8")
    html = render_report(copy)
    assert "/World/DrawnFromTheFileGraph" in html
    assert html.count('<div class="graph-card">') == len(summary["graphs"])


def test_a_run_directory_without_graphs_still_gets_them_from_srr_report(
        failing_run: api.RunResult, summary: dict, tmp_path: Path) -> None:
    copy = tmp_path / "old"
    shutil.copytree(failing_run.run_dir, copy)
    (copy / "graphs.json").unlink()
    (copy / "graphs.mmd").unlink()
    lenient = render_report(copy)  # the renderer alone builds no scene: it says so
    assert '<div class="graph-card">' not in lenient
    assert "this run directory has no graphs.json" in lenient
    api.report(copy)  # the API builds the scene again, as for runs from before graphs.json
    html = (copy / "report.html").read_text(encoding="utf-8")
    assert html.count('<div class="graph-card">') == len(summary["graphs"])
    assert "graphs.json" not in html
    assert not (copy / "graphs.json").exists()  # nothing written but the page


def test_a_damaged_graphs_file_costs_the_graphs_not_the_report(
        failing_run: api.RunResult, tmp_path: Path) -> None:
    copy = tmp_path / "damaged"
    shutil.copytree(failing_run.run_dir, copy)
    (copy / "graphs.json").write_text("[1, 2", encoding="utf-8")
    html = render_report(copy)
    assert '<div class="graph-card">' not in html
    assert "graphs.json: could not be read" in html
