"""Report generation time for a 60 s scenario: ``srr report RUN_DIR`` on a finished run.

Runs ``scenarios/dock_worker_crossing.yaml`` once for ``--duration`` simulated seconds (two
160×120 cameras at 5 Hz, a worker, perception and safety SUTs), then renders its report
``--repeats`` times and prints, best of N:

* in-process ``write_report`` and where its time goes (reading the bag into frames and
  series, SVG panels and map, action graphs, camera keyframes, template);
* the ``srr report`` command as a user runs it (interpreter start and imports included);
* the ratio of the in-process report time to the ``srr run`` wall time of the same run
  (measured side by side, so meaningful on any machine), and the page's size.

    python benchmarks/bench_report.py [--duration 60] [--repeats 5] [--run DIR]
"""

from __future__ import annotations

import argparse
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from harness import api  # noqa: E402
from harness.report import html as report_html  # noqa: E402
from harness.report.data import load_run, read_summary  # noqa: E402
from harness.report.plots import map_svg, time_panels  # noqa: E402

SCENARIO = ROOT / "scenarios" / "dock_worker_crossing.yaml"


def best(fn: Callable[[], Any], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=60.0, help="simulated seconds")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--run", type=Path, default=None,
                    help="an existing run directory to report on (skips the run)")
    args = ap.parse_args()

    tmp = tempfile.TemporaryDirectory(prefix="bench_report_")
    run_dir = args.run
    run_s = None
    if run_dir is None:
        run_dir = Path(tmp.name) / "run"
        sc = api.load(SCENARIO, duration=args.duration)
        t0 = time.perf_counter()
        res = api.run_scenario(sc, source=str(SCENARIO), out=run_dir)
        run_s = time.perf_counter() - t0
        print(f"srr run: {args.duration:g} s simulated in {run_s:.2f} s wall, verdict "
              f"{res.verdict} (report included)")
    summary = read_summary(run_dir)
    bag_mb = sum(p.stat().st_size for p in (run_dir / "bag").glob("*")) / 1e6
    print(f"run: {run_dir}  bag {bag_mb:.1f} MB, "
          f"{sum(t['count'] for t in summary['topics'].values())} messages")

    report_html.write_report(run_dir)  # warm: imports, file cache
    total = best(lambda: report_html.write_report(run_dir), args.repeats)
    data = load_run(run_dir)
    stages = {
        "frames + series": best(lambda: load_run(run_dir), args.repeats),
        "time panels + map": best(lambda: (time_panels(data), map_svg(data)), args.repeats),
        "action graphs": best(lambda: report_html._graphs(data), args.repeats),
        "camera keyframes": best(lambda: report_html._keyframes(data), args.repeats),
    }
    cli = best(lambda: subprocess.run([sys.executable, "-m", "harness.cli", "report",
                                       str(run_dir)], check=True, capture_output=True,
                                      cwd=ROOT), max(1, min(args.repeats, 3)))
    size = (run_dir / "report.html").stat().st_size
    print(f"python {platform.python_version()} on {platform.machine()}, best of "
          f"{args.repeats}")
    print(f"write_report (in process): {total:.3f} s   report.html {size / 1e3:.0f} kB")
    for name, t in stages.items():
        print(f"  {name:<18} {t:.3f} s")
    print(f"srr report (command, incl. interpreter start + imports): {cli:.3f} s")
    if run_s is not None:
        print(f"report / run wall time: {total / run_s:.3f}")
    tmp.cleanup()


if __name__ == "__main__":
    main()
