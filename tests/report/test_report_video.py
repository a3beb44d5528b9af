"""The report's camera videos, in a real headless Chromium driven over the DevTools protocol
with the network unreachable: the WebM files are VP9 (so they play where h264 does not), the
<video> elements load and play, seeking to a moment shows the image the bag recorded at that
time (PSNR against the bag's frame), the one cursor moves the map's markers and follows a
click on a plot, and a clip plays its window. ``srr report`` writes the same videos again
(same bytes) and leaves the bag alone; ``--no-video`` and a run without cameras have none.
Served by a server that ignores byte ranges, the videos still seek (played from memory)."""

from __future__ import annotations

import base64
import functools
import hashlib
import http.server
import json
import shutil
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import av
import numpy as np
import pytest

from harness import api
from harness.cli import main
from harness.recording.bagread import open_indexed
from harness.report.data import load_run
from harness.report.html import clip_specs
from harness.report.images import image_array
from harness.report.video import read_videos
from harness.video.codec import psnr
from tests.conftest import ModuleTmp
from tests.report.cdp import VIDEO_READY, Page, open_page
from tests.report.pngread import read_png

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]

# Resolves, with their ready states, once every <video> has a frame to show (or fails on a
# media error).
LOADED = "(function () { " + VIDEO_READY + """
  return Promise.all(Array.prototype.map.call(document.querySelectorAll("video"),
    function (v) { return ready(v).then(function () { return v.readyState; }); })); })()"""

# Runs ACTION (a statement that seeks) and resolves once every <video> has finished seeking to
# the time ACTION gave it (a seek still in flight from before is not taken for this one).
SEEK = """(function () {
  var vs = Array.prototype.slice.call(document.querySelectorAll("video"));
  ACTION;
  var want = vs.map(function (v) { return v.currentTime; });
  return new Promise(function (ok) { (function check() {
    if (vs.every(function (v, i) { return !v.seeking && v.readyState >= 2
                                          && Math.abs(v.currentTime - want[i]) < 1e-6; })) {
      ok(want); } else { setTimeout(check, 20); } })(); });
})()"""

# Each <video>'s topic, current time and pixels (drawn into a canvas, read back as PNG).
GRAB = """Array.prototype.map.call(document.querySelectorAll("video"), function (v) {
  var c = document.createElement("canvas");
  c.width = v.videoWidth; c.height = v.videoHeight;
  c.getContext("2d").drawImage(v, 0, 0);
  return {topic: v.getAttribute("data-topic"), time: v.currentTime,
          png: c.toDataURL("image/png")}; })"""


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _tree(root: Path) -> dict[str, str]:
    return {p.relative_to(root).as_posix(): _sha(p) for p in sorted(root.rglob("*"))
            if p.is_file()}


def _frames(bag: Path, topic: str) -> list[tuple[float, np.ndarray]]:
    with open_indexed(bag) as r:
        conn = next(c for c in r.connections if c.topic == topic)
        out = []
        for _, ts, raw in r.messages(connections=[conn]):
            px = image_array(r.decode(raw, conn), max_width=None)
            assert px is not None
            out.append((ts / 1e9, px))
    return out


@pytest.fixture(scope="module")
def page(chromium: str, failing_run: api.RunResult,
         module_tmp: ModuleTmp) -> Iterator[Page]:
    with open_page(chromium, module_tmp("cdp"),
                   (failing_run.run_dir / "report.html").as_uri()) as p:
        p.eval(LOADED)
        yield p


def test_videos_are_vp9_files_beside_the_report(failing_run: api.RunResult) -> None:
    run = failing_run.run_dir
    vs = read_videos(run)
    assert vs is not None
    assert sorted(v.topic for v in vs.videos) == ["/dock_cam_left_rgb", "/dock_cam_right_rgb"]
    assert vs.clips, "a regressed run has clips"
    html = (run / "report.html").read_text(encoding="utf-8")
    for f in [*vs.videos, *(f for c in vs.clips for f in c.files)]:
        path = run / f.file
        assert f.file.startswith("video/") and path.is_file()
        with av.open(str(path)) as c:
            stream = c.streams.video[0]
            assert c.format.name.startswith("matroska,webm")
            assert stream.codec_context.name in ("vp9", "libvpx-vp9")
            n = sum(1 for _ in c.decode(video=0))
        assert n == f.frames
    for v in vs.videos:  # the page links each file relatively, with its time origin
        assert f'<video src="{v.file}" data-t0="{v.t0_s:.6f}"' in html
        frames = _frames(run / "bag", v.topic)
        assert v.frames == len(frames) and v.t0_s == frames[0][0]
    # a clip for each regressed metric's windows and each moment, listed above the plots
    data = load_run(run)
    assert [c.spec for c in vs.clips] == clip_specs(data)
    assert {c.spec.kind for c in vs.clips} == {"metric", "moment"}
    for m in data.moments:
        assert any(c.spec.start_s <= m.t_s <= c.spec.end_s for c in vs.clips)
    assert html.index('id="clips"') < html.index('id="focus"')
    for c in vs.clips:
        assert f'href="{c.files[0].file}"' in html
        assert all(c.spec.start_s - 1e-6 <= f.t0_s <= f.last_s <= c.spec.end_s + 1e-6
                   for f in c.files)


def test_videos_load_and_play(page: Page) -> None:
    states = page.eval(LOADED)
    assert len(states) == 2 and all(s >= 2 for s in states)  # HAVE_CURRENT_DATA or more
    played = page.eval("""new Promise(function (ok) {
      var v = document.querySelector("video");
      srrCursor.seek(1.0);
      v.addEventListener("timeupdate", function f() {
        if (v.currentTime > 1.5) { v.removeEventListener("timeupdate", f);
          ok({video: v.currentTime, cursor: parseFloat(
            document.getElementById("cursor").getAttribute("data-time"))}); } });
      document.getElementById("cursor-play").click();
    })""")
    page.eval("srrCursor.pause()")
    assert played["video"] > 1.5
    assert played["cursor"] > 1.0  # the cursor follows the playing video


def test_seeking_to_a_moment_shows_the_recorded_frame(page: Page,
                                                      failing_run: api.RunResult) -> None:
    run = failing_run.run_dir
    data = load_run(run)
    topics = ["/dock_cam_left_rgb", "/dock_cam_right_rgb"]
    frames = {t: _frames(run / "bag", t) for t in topics}

    def shown_at(topic: str, t: float) -> int:  # a frame shows from its log time on
        times = [ft for ft, _ in frames[topic]]
        return max(i for i, ft in enumerate(times) if ft <= t + 1e-9)

    def moving(m: Any) -> bool:  # the moment's frame differs from the one before it
        return any((i := shown_at(t, m.t_s)) > 0
                   and psnr(frames[t][i][1], frames[t][i - 1][1]) < 40 for t in topics)

    moment = next(m for m in data.moments if moving(m))
    page.eval(SEEK.replace("ACTION", f'document.getElementById("moment-{moment.number}")'
                                     '.click()'))
    assert abs(page.eval("srrCursor.time()") - moment.t_s) < 1e-3

    def scores() -> dict[str, list[float]]:
        out = {}
        for g in page.eval(GRAB):
            img = read_png(base64.b64decode(g["png"].split(",", 1)[1]))[:, :, :3]
            out[g["topic"]] = [psnr(img, px) for _, px in frames[g["topic"]]]
        return out

    # Chromium may paint a seeked frame a little after the seek has ended (seen once in a
    # loaded full run): the frame shown within a second is the one judged.
    for _ in range(20):
        got = scores()
        if all(s[shown_at(t, moment.t_s)] >= 28.0 for t, s in got.items()):
            break
        time.sleep(0.05)
    assert set(got) == set(topics)
    for topic, s in got.items():
        want = shown_at(topic, moment.t_s)
        assert s[want] >= 28.0, f"{topic}: {s[want]:.1f} dB"
        best = int(np.argmax(s))  # no other recorded frame matches better
        assert best == want or np.array_equal(frames[topic][best][1],
                                              frames[topic][want][1]), (best, want)


def test_the_cursor_moves_the_map_markers_and_follows_a_plot(page: Page,
                                                             failing_run: api.RunResult
                                                             ) -> None:
    data = load_run(failing_run.run_dir)
    robot = next(t for t in data.tracks if t.kind == "robot")
    read = """(function () {
      var f = document.querySelector("svg.map g.map-frame");
      var m = document.querySelector('svg.map .cursor-marker[data-track="NAME"]');
      var l = document.querySelector("#focus svg .cursor-line");
      return {sx: f.getAttribute("data-sx"), sy: f.getAttribute("data-sy"),
              cx: parseFloat(m.getAttribute("cx")), cy: parseFloat(m.getAttribute("cy")),
              line: parseFloat(l.getAttribute("x1")), t: srrCursor.time()}; })()
      """.replace("NAME", robot.name)
    # click the first (regressed group's) panel where 70 % of the time axis lies
    clicked = page.eval("""(function () {
      var g = document.querySelector("#focus svg g.t-axis"), svg = g.ownerSVGElement;
      var x = parseFloat(g.getAttribute("data-x0")) + 0.7 * (parseFloat(g.getAttribute(
        "data-x1")) - parseFloat(g.getAttribute("data-x0")));
      var p = svg.createSVGPoint(); p.x = x; p.y = parseFloat(g.getAttribute("data-y1")) - 2;
      var s = p.matrixTransform(svg.getScreenCTM());
      svg.dispatchEvent(new MouseEvent("click", {clientX: s.x, clientY: s.y, bubbles: true}));
      return {x: x, t1: parseFloat(g.getAttribute("data-t1"))}; })()""")
    first = page.eval(read)
    assert abs(first["t"] - 0.7 * clicked["t1"]) < 0.02  # the click's time, within a pixel
    assert abs(first["line"] - clicked["x"]) < 1.5  # the cursor line is there (a pixel)

    def expected(t: float, sx: str, sy: str) -> tuple[float, float]:
        x = float(np.interp(t, robot.t, robot.x))
        y = float(np.interp(t, robot.t, robot.y))
        (dx, rx, kx), (dy, ry, ky) = ([float(v) for v in s.split()] for s in (sx, sy))
        return rx + (x - dx) * kx, ry + (y - dy) * ky

    ex, ey = expected(first["t"], first["sx"], first["sy"])
    assert abs(first["cx"] - ex) < 1.5 and abs(first["cy"] - ey) < 1.5
    page.eval("srrCursor.seek(0.5)")
    second = page.eval(read)
    ex, ey = expected(0.5, second["sx"], second["sy"])
    assert abs(second["cx"] - ex) < 1.5 and abs(second["cy"] - ey) < 1.5
    assert abs(second["cx"] - first["cx"]) + abs(second["cy"] - first["cy"]) > 10  # it moved


def test_a_clip_plays_its_window(page: Page) -> None:
    clip = page.eval("""(function () { var a = document.querySelector("#clips a.clip-play");
      return {start: parseFloat(a.getAttribute("data-seek")),
              until: parseFloat(a.getAttribute("data-until"))}; })()""")
    end = page.eval("""new Promise(function (ok) {
      var bar = document.getElementById("cursor");
      new MutationObserver(function (_, obs) {
        if (!bar.classList.contains("playing")) { obs.disconnect(); ok(srrCursor.time()); }
      }).observe(bar, {attributes: true, attributeFilter: ["class"]});
      document.querySelector("#clips a.clip-play").click();
      if (!bar.classList.contains("playing")) { ok(-1); }
    })""", timeout=120)
    assert end == pytest.approx(clip["until"], abs=1e-6), clip


class _WholeFiles(http.server.SimpleHTTPRequestHandler):
    """A static file server that ignores byte ranges, as ``python -m http.server`` does."""

    def log_message(self, format: str, *args: Any) -> None:
        pass


# Resolves, within 20 s, with each <video>'s seekable end and duration (once every one can
# be put anywhere in its file, or when the time is up).
SEEKABLE = """new Promise(function (ok) {
  var vs = Array.prototype.slice.call(document.querySelectorAll("video"));
  var until = performance.now() + 20000;
  function state() { return vs.map(function (v) { var s = v.seekable;
    return {end: s.length ? s.end(s.length - 1) : 0, duration: v.duration}; }); }
  (function check() {
    var st = state();
    if (st.every(function (x) { return x.duration > 0 && x.end >= x.duration - 0.05; })
        || performance.now() > until) { ok(st); } else { setTimeout(check, 50); }
  })(); })"""


def test_videos_seek_when_the_server_sends_whole_files(chromium: str,
                                                       failing_run: api.RunResult,
                                                       tmp_path: Path) -> None:
    """Over HTTP from a server without byte ranges a <video> can only play from its start:
    the page fetches such a file once and plays it from memory, so a moment still seeks
    every video, and playing from there keeps the cursor where it was put."""
    handler = functools.partial(_WholeFiles, directory=str(failing_run.run_dir))
    with http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler) as server:
        threading.Thread(target=server.serve_forever, daemon=True).start()
        try:
            url = f"http://127.0.0.1:{server.server_address[1]}/report.html"
            with open_page(chromium, tmp_path, url, loopback=True) as p:
                p.eval(LOADED)
                st = p.eval(SEEKABLE, timeout=60)
                assert all(x["end"] >= x["duration"] - 0.05 for x in st), st
                t0s = p.eval('Array.prototype.map.call(document.querySelectorAll("video"), '
                             'function (v) { return parseFloat(v.getAttribute("data-t0")); })')
                want = p.eval(SEEK.replace("ACTION", "srrCursor.seek(8.0)"))
                assert want == pytest.approx([8.0 - t0 + 0.001 for t0 in t0s], abs=1e-3)
                played = p.eval("""new Promise(function (ok) {
                  srrCursor.seek(5.0); srrCursor.play();
                  setTimeout(function () { var t = srrCursor.time(); srrCursor.pause();
                    ok(t); }, 600); })""")
                assert 5.0 <= played < 6.5  # from 5 s on, not from the file's start
        finally:
            server.shutdown()


def test_srr_report_writes_the_same_videos_and_leaves_the_bag(failing_run: api.RunResult,
                                                              tmp_path: Path) -> None:
    run = tmp_path / "run"
    shutil.copytree(failing_run.run_dir, run)
    before, bag = _tree(run / "video"), _tree(run / "bag")
    shutil.rmtree(run / "video")
    assert main(["report", str(run)]) == 0
    assert _tree(run / "video") == before  # VP9 with one thread: the same bytes again
    assert _tree(run / "bag") == bag
    assert main(["report", str(run), "--no-video"]) == 0
    html = (run / "report.html").read_text(encoding="utf-8")
    assert not (run / "video").exists()
    assert "<video" not in html and 'id="clips"' not in html
    assert 'id="cursor"' in html  # the cursor still drives the plots and the map
    assert _tree(run / "bag") == bag


def test_a_run_without_cameras_has_no_video_section(tmp_path: Path) -> None:
    path = ROOT / "scenarios" / "forklift_warehouse.yaml"
    res = api.run_scenario(api.load(path, duration=1.0), source=str(path),
                           out=tmp_path / "nocam")
    html = (res.run_dir / "report.html").read_text(encoding="utf-8")
    assert not (res.run_dir / "video").exists()
    assert "<video" not in html and 'id="video"' not in html and 'id="clips"' not in html
    tracks = json.loads(html.split('<script type="application/json" id="srr-tracks">', 1)[1]
                        .split("</script>", 1)[0])
    assert any(t["kind"] == "robot" for t in tracks)


def test_srr_run_no_video_leaves_the_videos_out(tmp_path: Path) -> None:
    """`srr run --no-video`: the camera run's report has no videos or clips, its recording is
    the one the same run with videos makes, and `srr report` adds the videos later."""
    path = ROOT / "scenarios" / "dock_worker_crossing.yaml"
    runs = {}
    for name, extra in (("with", []), ("without", ["--no-video"])):
        code = main(["run", str(path), "--duration", "1", "--out", str(tmp_path / name), "-q",
                     *extra])
        assert code in (0, 1)
        runs[name] = tmp_path / name
    assert (runs["with"] / "video").is_dir()
    assert not (runs["without"] / "video").exists()
    html = (runs["without"] / "report.html").read_text(encoding="utf-8")
    assert "<video" not in html and 'id="clips"' not in html
    assert _tree(runs["without"] / "bag").keys() == _tree(runs["with"] / "bag").keys()
    digest = [json.loads((r / "summary.json").read_text())["digest"] for r in runs.values()]
    assert digest[0] == digest[1]
    assert main(["report", str(runs["without"])]) == 0
    assert (runs["without"] / "video").is_dir()
