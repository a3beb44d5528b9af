"""``srr diff`` time for two runs of a dock scene.

Runs ``scenarios/dock_worker_crossing.yaml`` for ``--duration`` simulated seconds (two
160×120 cameras at 5 Hz with depth, a worker, perception and safety SUTs) three times — seed
11 twice and seed 12, the worker's speed varied by the seed (``workers.0.variation=0.2``) —
then, best of ``--repeats``:

* ``diff_runs`` on the identical pair and on the pair whose seeds differ (the worker, the
  forklift after it, the cameras, perception and safety part at ~22 s);
* a bare pass of the rosbags reader over both bags (every message read, nothing compared):
  the floor, measured side by side, so the ratio means something on any machine;
* ``write_diff`` (the ``--html`` page) for the differing pair.

    python benchmarks/bench_diff.py [--duration 36] [--repeats 5] [--runs A A2 B]
"""

from __future__ import annotations

import argparse
import platform
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from rosbags.rosbag2 import Reader  # noqa: E402

from harness import api  # noqa: E402

SCENARIO = ROOT / "scenarios" / "dock_worker_crossing.yaml"


def best(fn: Callable[[], Any], repeats: int) -> tuple[float, float]:
    """(best, median) wall time of ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    times.sort()
    return times[0], times[len(times) // 2]


def bare_read(*runs: Path) -> int:
    n = 0
    for run in runs:
        with Reader(run / "bag") as reader:
            for _ in reader.messages():
                n += 1
    return n


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=36.0, help="simulated seconds")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--runs", type=Path, nargs=3, default=None, metavar=("A", "A2", "B"),
                    help="existing run directories: A and A2 identical, B different")
    args = ap.parse_args()

    tmp = tempfile.TemporaryDirectory(prefix="bench_diff_")
    if args.runs is None:
        runs = []
        for name, seed in (("a", 11), ("a2", 11), ("b", 12)):
            sc = api.load(SCENARIO, duration=args.duration, seed=seed,
                          overrides=["workers.0.variation=0.2"])
            runs.append(api.run_scenario(sc, source=str(SCENARIO),
                                         out=Path(tmp.name) / name).run_dir)
        a, a2, b = runs
    else:
        a, a2, b = args.runs
    mb = sum(p.stat().st_size for r in (a, b) for p in (r / "bag").glob("*")) / 1e6
    n = bare_read(a, b)
    print(f"python {platform.python_version()} on {platform.machine()}, best of "
          f"{args.repeats} (median in brackets); two bags: {n} messages, {mb:.1f} MB")
    same = api.diff_runs(a, a2)
    diff = api.diff_runs(a, b)
    print(f"identical pair: {same.verdict}; differing pair: {diff.verdict}, "
          f"{len(diff.differing)} topics differ, "
          f"{sum(t.messages_differ for t in diff.topics)} message pairs differ")
    floor = best(lambda: bare_read(a, b), args.repeats)
    t_same = best(lambda: api.diff_runs(a, a2), args.repeats)
    t_diff = best(lambda: api.diff_runs(a, b), args.repeats)
    page = Path(tmp.name) / "diff.html"
    t_html = best(lambda: api.write_diff(diff, page), max(1, min(args.repeats, 3)))
    for label, (t, med) in (("bare read of both bags", floor), ("diff, identical", t_same),
                            ("diff, seeds differ", t_diff)):
        print(f"  {label:<24} {t:.3f} s ({med:.3f})  {n / t / 1e3:6.1f} k msgs/s  "
              f"{t / floor[0]:.2f} × bare read")
    print(f"  {'--html page':<24} {t_html[0]:.3f} s ({t_html[1]:.3f})  (loads both runs, "
          "renders, writes)")
    print(f"page: {page.stat().st_size / 1e3:.0f} kB")
    tmp.cleanup()


if __name__ == "__main__":
    main()
