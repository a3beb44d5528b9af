"""The report in a real headless Chromium with the network unreachable: it renders fully,
makes no request, and a 1280×900 window shows the regressed metric and its window first."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from harness import api
from harness.report.templates import VERDICT_COLORS
from tests.report.browser import VIEWPORT, page_requests, run_chromium
from tests.report.pngread import read_png

pytestmark = pytest.mark.slow

# Reads back, from inside the page, where things landed in the first view and whether every
# image decoded and every SVG has a size. Only the test's copy of the page gets this script.
PROBE = """<script>
(function () {
  function box(e) { var b = e.getBoundingClientRect();
    return {top: b.top, bottom: b.bottom, left: b.left, right: b.right,
            w: b.width, h: b.height}; }
  function q(s) { var e = document.querySelector(s); return e ? box(e) : null; }
  var out = {
    banner: q("#verdict"), headline: q("#headline table"),
    focus: Array.prototype.map.call(document.querySelectorAll("#focus figure"), function (f) {
      return {group: f.getAttribute("data-group"), box: box(f),
              hl: Array.prototype.map.call(f.querySelectorAll(".hl-box"), box)}; }),
    rows: Array.prototype.map.call(document.querySelectorAll("#headline tr[data-metric]"),
      function (r) { return {metric: r.getAttribute("data-metric"), box: box(r)}; }),
    images: Array.prototype.map.call(document.images, function (i) {
      return {w: i.naturalWidth, h: i.naturalHeight, ok: i.complete}; }),
    svgs: Array.prototype.map.call(document.querySelectorAll("svg"), function (s) {
      return [s.getAttribute("class"), s.getBoundingClientRect().width,
              s.getBoundingClientRect().height]; })
  };
  var pre = document.createElement("pre");
  pre.id = "probe"; pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
})();
</script>"""


def test_netlog_catches_page_requests(chromium: str, tmp_path: Path) -> None:
    """The request detector below is not vacuous: a page with remote references trips it."""
    page = tmp_path / "remote.html"
    page.write_text('<img src="https://cdn.example.org/x.png">'
                    '<link rel="stylesheet" href="http://fonts.example.org/a.css">')
    run_chromium(chromium, tmp_path, page.as_uri(),
                 ["--dump-dom", f"--log-net-log={tmp_path / 'net.json'}"])
    seen = page_requests(tmp_path / "net.json")
    assert any("cdn.example.org" in u for u in seen)
    assert any("fonts.example.org" in u for u in seen)


def test_renders_fully_offline_without_requests(chromium: str, failing_run: api.RunResult,
                                                summary: dict, tmp_path: Path) -> None:
    report = failing_run.run_dir / "report.html"
    dom = run_chromium(chromium, tmp_path, report.as_uri(),
                       ["--dump-dom", f"--log-net-log={tmp_path / 'net.json'}"])
    assert page_requests(tmp_path / "net.json") == []
    assert 'data-verdict="REGRESSED"' in dom and ">REGRESSED<" in dom
    for e in summary["comparison"]:  # every metric has its row in the full table
        assert f'data-metric="{e["name"]}"' in dom
    assert len(re.findall(r'<svg class="plot"', dom)) >= 4  # safety, control, perception x2
    # the run's own map, and both runs on one map against the baseline's reference recording
    assert len(re.findall(r'<svg class="plot map"', dom)) == 2
    assert 'id="against"' in dom
    assert len(re.findall(r'<svg class="graph-svg"', dom)) == len(summary["graphs"])
    images = re.findall(r'<img src="data:image/png;base64,', dom)
    assert len(images) >= 2
    for topic in ("/dock_cam_left_rgb", "/dock_cam_right_rgb"):
        assert topic in dom
    assert summary["command"] in dom and summary["digest"][:16] in dom


def test_first_view_shows_the_regression_and_its_window(chromium: str,
                                                        failing_run: api.RunResult,
                                                        tmp_path: Path) -> None:
    html = (failing_run.run_dir / "report.html").read_text(encoding="utf-8")
    probe_page = tmp_path / "probe.html"
    probe_page.write_text(html.replace("</body>", PROBE + "</body>"), encoding="utf-8")
    dom = run_chromium(chromium, tmp_path, probe_page.as_uri(), ["--dump-dom"])
    found = re.search(r'<pre id="probe">(.*?)</pre>', dom, re.S)
    assert found, "the probe did not run"
    probe = json.loads(found.group(1).replace("&amp;", "&").replace("&lt;", "<")
                       .replace("&gt;", ">").replace("&quot;", '"'))
    height = VIEWPORT[1]
    assert probe["banner"]["top"] == 0 and probe["banner"]["bottom"] < 200
    assert probe["rows"] and all(r["box"]["bottom"] <= height for r in probe["rows"])
    first = probe["focus"][0]
    assert first["group"] == "safety"
    assert first["box"]["bottom"] <= height, "the regressed group's panel is below the fold"
    assert first["hl"] and all(b["w"] > 5 and b["bottom"] <= height for b in first["hl"])
    assert probe["images"] and all(i["ok"] and i["w"] > 0 and i["h"] > 0
                                   for i in probe["images"])
    assert all(w > 50 and h > 30 for _, w, h in probe["svgs"])


def test_screenshot_is_not_blank(chromium: str, failing_run: api.RunResult,
                                 tmp_path: Path) -> None:
    shot = tmp_path / "shot.png"
    run_chromium(chromium, tmp_path, (failing_run.run_dir / "report.html").as_uri(),
                 [f"--screenshot={shot}"])
    px = read_png(shot.read_bytes())[:, :, :3]
    assert px.shape[:2] == (VIEWPORT[1], VIEWPORT[0])
    packed = (px[..., 0].astype(np.uint32) << 16) | (px[..., 1].astype(np.uint32) << 8) \
        | px[..., 2]
    colours = np.unique(packed)
    assert len(colours) > 200, f"only {len(colours)} distinct colours"
    banner = tuple(int(VERDICT_COLORS["REGRESSED"][i:i + 2], 16) for i in (1, 3, 5))
    top = px[:60].reshape(-1, 3)
    share = float((np.abs(top.astype(int) - banner).sum(axis=1) <= 6).mean())
    assert share > 0.5, f"banner colour covers {share:.0%} of the top 60 rows"
    # regressed rows and the red status badges are in the first view
    red = float((np.abs(px.reshape(-1, 3).astype(int) - (220, 38, 38)).sum(axis=1) <= 12)
                .mean())
    assert red > 0.001
