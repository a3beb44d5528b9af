"""``srr diff --html``: one page with both runs (and their camera videos side by side),
opened in a real headless Chromium with the network unreachable."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path
from typing import Any

import pytest

from harness import api
from harness.cli import main
from harness.diff.html import diff_moments
from harness.report.data import load_run
from tests.conftest import ModuleTmp
from tests.diff.conftest import Runs
from tests.report.browser import page_requests, run_chromium
from tests.report.cdp import VIDEO_READY, open_page

pytestmark = pytest.mark.slow

# Reads back, from inside the test's copy of the page, what the DOM holds and whether every
# image decoded and every SVG has a size.
PROBE = """<script>
(function () {
  function all(s, f) { return Array.prototype.map.call(document.querySelectorAll(s), f); }
  function text(e) { return e.textContent.replace(/\\s+/g, " ").trim(); }
  function img(e) { return e ? {w: e.naturalWidth, h: e.naturalHeight, ok: e.complete} : null; }
  var out = {
    verdict: document.querySelector("#verdict").getAttribute("data-verdict"),
    first: (function (e) { return e ? {topic: e.getAttribute("data-topic"),
      index: e.getAttribute("data-index"), path: e.getAttribute("data-path")} : null; })(
      document.querySelector("#first-divergence")),
    maps: document.querySelectorAll("svg.map").length,
    mapA: document.querySelectorAll("svg.map polyline.robot-path.run-a").length,
    mapB: document.querySelectorAll("svg.map polyline.robot-path.run-b").length,
    workersA: document.querySelectorAll("svg.map polyline.worker-path.run-a").length,
    workersB: document.querySelectorAll("svg.map polyline.worker-path.run-b").length,
    legend: all(".map-legend .key", text),
    metrics: all("table.metric-delta-table tr[data-metric]", function (r) {
      return [r.getAttribute("data-metric"), r.getAttribute("data-status")]; }),
    topics: all("table.topic-table tr[data-topic]", function (r) {
      return [r.getAttribute("data-topic"), r.getAttribute("data-status")]; }),
    pairs: all(".pair", function (p) {
      return {topic: p.getAttribute("data-topic"), a: img(p.querySelector(".side-a img")),
              b: img(p.querySelector(".side-b img")),
              d: img(p.querySelector(".side-diff img"))}; }),
    rows: document.querySelectorAll(".pair-row").length,
    seriesA: document.querySelectorAll("#timeseries .run-a").length,
    seriesB: document.querySelectorAll("#timeseries .run-b").length,
    panels: all("#timeseries figure.panel", function (f) { return f.id; }),
    images: all("img", img),
    svgs: all("svg", function (s) { var b = s.getBoundingClientRect();
      return [s.getAttribute("class"), b.width, b.height]; })
  };
  var pre = document.createElement("pre");
  pre.id = "probe"; pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
})();
</script>"""


# Resolves, once every <video> has its first frame, with what each plays.
LOADED = "(function () { " + VIDEO_READY + """
  return Promise.all(Array.prototype.map.call(document.querySelectorAll("video"),
    function (v) { return ready(v).then(function () {
      return {ready: v.readyState, topic: v.getAttribute("data-topic"),
              run: v.getAttribute("data-run"), src: decodeURI(v.src.slice(7))}; }); })); })()"""
# Seeks the cursor and resolves, once every <video> has seeked, with their times.
SEEK = """(function (t) {
  var vs = Array.prototype.slice.call(document.querySelectorAll("video"));
  var done = Promise.all(vs.map(function (v) { return new Promise(function (ok) {
    v.addEventListener("seeked", function () { ok(); }, {once: true}); }); }));
  srrCursor.seek(t);
  return done.then(function () { return vs.map(function (v) {
    return {t0: parseFloat(v.getAttribute("data-t0")), time: v.currentTime}; }); });
})(%r)"""


def _probe(chromium: str, page: Path, tmp: Path) -> dict[str, Any]:
    copy = tmp / "probe.html"
    copy.write_text(page.read_text(encoding="utf-8").replace("</body>", PROBE + "</body>"),
                    encoding="utf-8")
    dom = run_chromium(chromium, tmp, copy.as_uri(), ["--dump-dom"])
    found = re.search(r'<pre id="probe">(.*?)</pre>', dom, re.S)
    assert found, "the probe did not run"
    return dict(json.loads(found.group(1).replace("&amp;", "&").replace("&lt;", "<")
                           .replace("&gt;", ">").replace("&quot;", '"')))


@pytest.fixture(scope="module")
def dock_page(runs: Runs, module_tmp: ModuleTmp) -> tuple[Path, Any]:
    a, b = runs.get("dock_11"), runs.get("dock_12")
    page = module_tmp("diff-html") / "diff.html"
    assert main(["diff", str(a), str(b), "--html", str(page)]) == 1
    return page, api.diff_runs(a, b)


def test_page_is_self_contained(dock_page: tuple[Path, Any]) -> None:
    page = dock_page[0]
    html = page.read_text(encoding="utf-8")
    assert "<script src" not in html and "<link" not in html and "<iframe" not in html
    videos = []
    for attr, value in re.findall(r'\s(src|href)="([^"]*)"', html):
        if not value.startswith(("data:image/png;base64,", "#")):
            # the runs' own videos, linked relative to the page
            assert attr == "src" and value.endswith(".webm"), (attr, value[:60])
            assert (page.parent / value).is_file()
            videos.append(value)
    assert len(videos) == 4  # two cameras of each run
    # no CSS url(...) (the script's URL.createObjectURL( is no fetch of a resource)
    assert not re.search(r"(?i)@import|@font-face|(?<![\w.])url\(", html)


def test_page_says_what_changed_between_the_runs(dock_page: tuple[Path, Any]) -> None:
    page, result = dock_page
    assert result.changes == ("seed: 11 → 12",)
    html = page.read_text(encoding="utf-8")
    section = html[html.index('<div class="changes" id="changes">'):]
    assert "What changed (A → B)" in section[:200]
    assert '<li class="mono">seed: 11 → 12</li>' in section[:400]


def test_page_shows_both_runs_in_chromium_offline(chromium: str, dock_page: tuple[Path, Any],
                                                  runs: Runs, tmp_path: Path) -> None:
    page, result = dock_page
    run_chromium(chromium, tmp_path, page.as_uri(),
                 ["--dump-dom", f"--log-net-log={tmp_path / 'net.json'}"])
    assert page_requests(tmp_path / "net.json") == []
    p = _probe(chromium, page, tmp_path)
    assert p["verdict"] == "DIFFERENT"
    first = result.first_divergence
    assert p["first"] == {"topic": first.topic, "index": str(first.index), "path": first.path}
    # one map, both runs' forklift and worker on it, both named in its legend
    assert p["maps"] == 1 and p["mapA"] == 1 and p["mapB"] == 1
    assert p["workersA"] == 1 and p["workersB"] == 1
    assert "baseline (A): robot (ground truth)" in p["legend"]
    assert "candidate (B): robot (ground truth)" in p["legend"]
    # every metric of both runs in the delta table, regressed-like rows first
    names = {m["name"] for run in ("dock_11", "dock_12") for m in
             json.loads((runs.get(run) / "summary.json").read_text())["metrics"]}
    assert {name for name, _ in p["metrics"]} == names
    order = [s in ("regressed", "missing") for _, s in p["metrics"]]
    assert order == sorted(order, reverse=True)
    assert sorted(t for t, _ in p["topics"]) == [t.name for t in result.topics]
    assert dict(p["topics"])[first.topic] == "differs"
    # camera keyframes in pairs (A | B | difference) at every moment, all decoded
    moments = diff_moments(result, load_run(runs.get("dock_11")), load_run(runs.get("dock_12")))
    assert moments and p["rows"] == len(moments)
    assert moments[0].t_s == pytest.approx(first.t_ns / 1e9)
    assert {q["topic"] for q in p["pairs"]} == {"/dock_cam_left_rgb", "/dock_cam_right_rgb"}
    assert len(p["pairs"]) == 2 * len(moments)
    for q in p["pairs"]:
        for side in ("a", "b", "d"):
            assert q[side] and q[side]["ok"] and (q[side]["w"], q[side]["h"]) == (160, 120)
    # time series of both runs overlaid
    assert p["seriesA"] >= 3 and p["seriesB"] >= 3
    assert {"panel-safety", "panel-control", "panel-perception.person.error",
            "panel-perception.person.count"} <= set(p["panels"])
    assert p["images"] and all(i["ok"] and i["w"] > 0 for i in p["images"])
    assert all(w > 50 and h > 30 for _, w, h in p["svgs"])


def test_the_most_differing_camera_frame_is_a_moment(dock_page: tuple[Path, Any]) -> None:
    _, result = dock_page
    cams = [t for t in result.topics if t.name.endswith("_rgb") and t.worst is not None]
    assert cams
    worst = max(cams, key=lambda t: t.worst.values)
    labels = [m.label for m in diff_moments(result)]
    assert any(f"most differing {worst.name} frame (#{worst.worst.index}," in x
               for x in labels)


def test_identical_runs_page(chromium: str, runs: Runs, tmp_path: Path) -> None:
    page = tmp_path / "same.html"
    assert main(["diff", str(runs.get("same_a")), str(runs.get("same_b")), "--html",
                 str(page)]) == 0
    p = _probe(chromium, page, tmp_path)
    assert p["verdict"] == "IDENTICAL" and p["first"] is None
    assert p["mapA"] == 1 and p["mapB"] == 1 and p["rows"] == 0
    assert {s for _, s in p["topics"]} == {"identical"}
    assert p["metrics"] and {s for _, s in p["metrics"]} == {"ok"}


def test_both_runs_play_side_by_side_on_one_cursor(chromium: str,
                                                   dock_page: tuple[Path, Any],
                                                   runs: Runs, tmp_path: Path) -> None:
    """Each camera's A and B video side by side, from the runs' own report videos; a seek
    puts all four at the same simulation time, playing keeps them together."""
    page, _ = dock_page
    with open_page(chromium, tmp_path, page.as_uri()) as p:
        vids = p.eval(LOADED)
        assert len(vids) == 4 and all(v["ready"] >= 2 for v in vids)
        assert [(v["topic"], v["run"]) for v in vids] == [
            ("/dock_cam_left_rgb", "a"), ("/dock_cam_left_rgb", "b"),
            ("/dock_cam_right_rgb", "a"), ("/dock_cam_right_rgb", "b")]
        for v in vids:  # the runs' own files, not copies
            run = runs.get("dock_11" if v["run"] == "a" else "dock_12")
            assert Path(v["src"]).resolve().is_relative_to(run.resolve() / "video")
        seeked = p.eval(SEEK % 3.3)
        assert all(abs(v["t0"] + v["time"] - 3.3) < 0.01 for v in seeked)
        p.eval(SEEK % 1.0)
        played = p.eval("""new Promise(function (ok) {
          var vs = Array.prototype.slice.call(document.querySelectorAll("video"));
          vs[0].addEventListener("timeupdate", function f() {
            if (vs[0].currentTime > 3.0) { vs[0].removeEventListener("timeupdate", f);
              srrCursor.pause();
              ok(vs.map(function (v) { return parseFloat(v.getAttribute("data-t0"))
                + v.currentTime; })); } });
          document.getElementById("cursor-play").click(); })""")
        assert min(played) > 2.5 and max(played) - min(played) < 0.5, played


def test_a_run_without_videos_gets_them_beside_the_page(runs: Runs, tmp_path: Path) -> None:
    """A run rendered with --no-video: its bag's cameras are encoded beside the page; the
    run directory is not written."""
    b = tmp_path / "dock_12"
    shutil.copytree(runs.get("dock_12"), b)
    assert main(["report", str(b), "--no-video"]) == 0
    before = sorted(p.relative_to(b) for p in b.rglob("*"))
    page = tmp_path / "out" / "diff.html"
    page.parent.mkdir()
    assert main(["diff", str(runs.get("dock_11")), str(b), "--html", str(page)]) == 1
    assert sorted(p.relative_to(b) for p in b.rglob("*")) == before
    srcs = re.findall(r'<video src="([^"]*)"[^>]*data-run="(a|b)"', page.read_text())
    assert sorted(r for _, r in srcs) == ["a", "a", "b", "b"]
    for src, run in srcs:
        assert (page.parent / src).is_file()
        assert src.startswith("diff.html.video/b/video/") == (run == "b"), src
    assert main(["diff", str(runs.get("dock_11")), str(b), "--html", str(page),
                 "--no-video"]) == 1
    assert "<video" not in page.read_text()
