"""What the report's camera videos cost: time and bytes added to a run, and the page's load
time in headless Chromium.

Runs ``scenarios/dock_worker_crossing.yaml`` once as bundled (36 s, two 160×120 cameras at
5 Hz, raw images in the bag), then, alternating, best of ``--repeats``:

* ``write_report`` without videos and with them (VP9 WebM of each camera plus the clips):
  the difference is the time the videos add to the run (wall and CPU time of the process,
  which other jobs on the machine disturb less);
* the bytes of ``video/`` (whole-run files, clips) beside ``report.html`` and the bag;
* the page in headless Chromium (DevTools protocol, network blocked): from navigation to the
  ``load`` event, and to every ``<video>`` having its first frame (``readyState`` ≥ 2).

``--scale N`` renders the cameras N× larger (``resolution`` override) to show how the cost
grows with the picture (frames wider than 640 px are shrunk for the video).

    python benchmarks/bench_report_video.py [--repeats 5] [--scale 1] [--duration 36]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from harness import api  # noqa: E402
from harness.report.html import write_report  # noqa: E402
from harness.report.video import read_videos  # noqa: E402
from tests.report.browser import chromium_path  # noqa: E402
from tests.report.cdp import open_page  # noqa: E402

SCENARIO = ROOT / "scenarios" / "dock_worker_crossing.yaml"

# in the page: ms from navigation start to the load event and to every video's first frame
TIMING = """Promise.all(Array.prototype.map.call(document.querySelectorAll("video"),
  function (v) { return new Promise(function (ok) {
    if (v.readyState >= 2) { ok(); } else { v.addEventListener("loadeddata", ok); } }); }))
  .then(function () { var nav = performance.getEntriesByType("navigation")[0];
    return {load_ms: nav.loadEventEnd, videos_ms: performance.now(),
            n: document.querySelectorAll("video").length}; })"""


def _bytes(root: Path) -> int:
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file())


def _load(chromium: str, page: Path, tmp: Path) -> dict[str, float]:
    with open_page(chromium, tmp, page.as_uri()) as p:
        return dict(p.eval(TIMING))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--scale", type=int, default=1, help="camera resolution × N")
    ap.add_argument("--duration", type=float, default=None)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    overrides = [f"cameras.{i}.resolution=[{160 * args.scale}, {120 * args.scale}]"
                 for i in (0, 1)] if args.scale != 1 else []
    chromium = chromium_path()
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        sc = api.load(SCENARIO, duration=args.duration, overrides=overrides)
        t0 = time.perf_counter()
        res = api.run_scenario(sc, source=str(SCENARIO), out=tmp / "run")
        run_s = time.perf_counter() - t0
        run = res.run_dir
        plain, video, plain_cpu, video_cpu = [], [], [], []
        for _ in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            write_report(run, video=False)
            plain.append(time.perf_counter() - t0)
            plain_cpu.append(time.process_time() - c0)
            t0, c0 = time.perf_counter(), time.process_time()
            write_report(run, video=True)
            video.append(time.perf_counter() - t0)
            video_cpu.append(time.process_time() - c0)
        vs = read_videos(run)
        assert vs is not None
        whole = sum(v.bytes for v in vs.videos)
        clips = vs.bytes - whole
        out: dict[str, Any] = {
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python "
                       f"{platform.python_version()}",
            "simulated_s": res.summary["simulated_s"], "run_wall_s": run_s,
            "cameras": [f"{v.topic} {v.width}x{v.height}, {v.frames} frames, {v.bytes} B"
                        for v in vs.videos],
            "report_s_without_video": min(plain), "report_s_with_video": min(video),
            "video_s": min(video) - min(plain),
            "video_cpu_s": min(video_cpu) - min(plain_cpu),
            "video_bytes_whole_run": whole, "video_bytes_clips": clips, "clips": len(vs.clips),
            "report_html_bytes": (run / "report.html").stat().st_size,
            "bag_bytes": _bytes(run / "bag"),
        }
        if chromium:
            loads = [_load(chromium, run / "report.html", tmp) for _ in range(args.repeats)]
            nov = tmp / "novideo"
            shutil.copytree(run, nov)
            write_report(nov, video=False)
            loads_nov = [_load(chromium, nov / "report.html", tmp) for _ in range(args.repeats)]
            out["chromium_load_ms"] = min(x["load_ms"] for x in loads)
            out["chromium_videos_ready_ms"] = min(x["videos_ms"] for x in loads)
            out["chromium_load_ms_without_video"] = min(x["load_ms"] for x in loads_nov)
    for k, v in out.items():
        print(f"{k:32s} {v:.3f}" if isinstance(v, float) else f"{k:32s} {v}")
    if args.json is not None:
        args.json.write_text(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
