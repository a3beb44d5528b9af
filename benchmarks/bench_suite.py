"""The bundled nightly suite on 1 and 2 workers, locally and on a real local Ray cluster.

Measured side by side in one process, on the same suite file and plan:

* local ×1, local ×2: ``srr suite --executor local --jobs N`` (a worker process per run);
* ray ×1, ray ×2:     ``srr suite --executor ray --jobs N`` (a Ray task per run, on a local
                      cluster that the suite starts and stops);
* ray start/stop:     ``ray.init`` + ``ray.shutdown`` alone (the cluster's fixed cost).

Prints each configuration's suite wall time, the speed-up of 2 workers over 1 (goal ≥ 0.8 × 2)
and, from the local ×1 pass, the per-run figures a cluster plan needs: wall time, the worker's
peak memory and the size of each run directory. Every pass must end PASS (a fast suite that
judges wrongly counts for nothing).

    python benchmarks/bench_suite.py [--suite scenarios/suites/nightly.yaml] [--repeat 1]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MUJOCO_GL", "egl")

from harness import api  # noqa: E402
from harness.suite.runner import plan_suite  # noqa: E402


def dir_mb(path: Path) -> float:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file()) / 2**20


def ray_fixed_cost() -> float:
    import logging

    import ray

    t0 = time.perf_counter()
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False,
             logging_level=logging.ERROR)
    ray.shutdown()
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--suite", type=Path, default=ROOT / "scenarios" / "suites" / "nightly.yaml")
    ap.add_argument("--repeat", type=int, default=1,
                    help="repeats per scenario (overrides the suite file's default)")
    ap.add_argument("--configs", default="local:1,local:2,ray:1,ray:2")
    args = ap.parse_args()
    os.chdir(ROOT)
    plan = plan_suite([args.suite], repeat=args.repeat)
    print(f"machine: {platform.machine()}, {os.cpu_count()} CPUs, Python "
          f"{platform.python_version()}, {platform.platform()}")
    print(f"suite: {args.suite.relative_to(ROOT)}, {len(plan.runs)} runs")
    walls: dict[tuple[str, int], float] = {}
    per_run: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for conf in args.configs.split(","):
            executor, jobs = conf.split(":")
            out = Path(tmp) / conf.replace(":", "x")
            t0 = time.perf_counter()
            res = api.run_planned_suite(plan, executor=executor, jobs=int(jobs), out=out)
            wall = time.perf_counter() - t0
            walls[(executor, int(jobs))] = wall
            runs = res.summary["runs"]
            work = sum(r["wall_s"] for r in runs)
            print(f"{executor:>5} ×{jobs}: {wall:6.1f} s wall, {res.summary['verdict']}, "
                  f"sum of run walls {work:6.1f} s")
            if res.summary["verdict"] != "PASS":
                raise SystemExit(f"{conf}: the suite did not pass ({res.summary['verdict']})")
            if (executor, int(jobs)) == ("local", 1):
                per_run = [{**r, "dir_mb": dir_mb(out / r["run_dir"])} for r in runs]
    for executor in ("local", "ray"):
        if (executor, 1) in walls and (executor, 2) in walls:
            s = walls[(executor, 1)] / walls[(executor, 2)]
            print(f"{executor}: speed-up ×2 workers = {s:.2f} (goal ≥ 1.60; "
                  f"efficiency {s / 2:.2f})")
    if ("local", 1) in walls and ("ray", 1) in walls:
        extra = (walls[("ray", 1)] - walls[("local", 1)]) / len(plan.runs)
        print(f"ray ×1 over local ×1: {extra:+.2f} s per run (cluster start/stop included)")
    print(f"ray start/stop alone: {ray_fixed_cost():.1f} s")
    if per_run:
        print("\nper run (local ×1):")
        print(f"{'run':44} {'wall s':>7} {'peak MiB':>9} {'dir MiB':>8}")
        for r in per_run:
            print(f"{r['id']:44} {r['wall_s']:7.1f} {r['peak_rss_mb']:9.0f} {r['dir_mb']:8.1f}")
        w = [r["wall_s"] for r in per_run]
        m = [r["peak_rss_mb"] for r in per_run]
        d = [r["dir_mb"] for r in per_run]
        print(f"{'mean':44} {statistics.mean(w):7.1f} {statistics.mean(m):9.0f} "
              f"{statistics.mean(d):8.1f}")
        print(f"{'max':44} {max(w):7.1f} {max(m):9.0f} {max(d):8.1f}")


if __name__ == "__main__":
    main()
