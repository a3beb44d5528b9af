"""``srr search`` against its planted defect: does it find the failure, how many runs does it
take, and how many runs per second does a search make (issue 25, items 5 and 6).

The system under test is ``scenarios/planted/dock_crossing_blind_spot.yaml``: a safety
monitor with a PLANTED DEFECT (it ignores people faster than 2 m/s while the clock is in
[23.5, 24.5) s). The searched space is the worker's speed (0.5–2.5 m/s) and start delay
(0–26 s), runs of 28 s simulated; a run violates the objective when the monitor stays muted
while a worker is in the ROI for more than 1.5 % of the run (``safety.over_mute > 1.5``).

Side by side, with the same budget of runs:

* ``tpe`` and ``random`` (optuna samplers), over ``--seeds`` seeds each, stopping at the
  first violation (``--stop-at-first``): found or not, and the runs it took;
* ``grid``: the sweep srr already has (``srr suite`` with a ``sweep:`` of 5 speeds × 4 start
  delays = 20 points, evenly spaced over the same ranges); it has no seed: run once, the runs
  it took are the position of the first violating point in grid order;
* no false alarm: the same search (tpe, the whole budget) on ``dock_worker_crossing.yaml``,
  the reference monitor, must find no violation;
* runs per second: the tpe searches' trials over their wall time (local × ``--jobs``), and one
  search on a local Ray cluster (``--ray-budget`` trials, ``--executor ray``, as many workers).

    python benchmarks/bench_search.py [--seeds 10] [--budget 20] [--jobs 2] [--json FILE]
    python benchmarks/bench_search.py --driver-trials 1000   # the search process's own cost
"""

from __future__ import annotations

import argparse
import json
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
os.chdir(ROOT)  # the planted plug-in imports from the project root
os.environ.setdefault("MUJOCO_GL", "egl")

from harness import api  # noqa: E402

PLANTED = "scenarios/planted/dock_crossing_blind_spot.yaml"
REFERENCE = "scenarios/dock_worker_crossing.yaml"
SPACE = ["workers.0.speed=0.5..2.5", "workers.0.start_delay=0..26"]
SET = ["duration=28"]
METRIC, ABOVE = "safety.over_mute", 1.5


def search(scenario: str, sampler: str, seed: int, budget: int, jobs: int, out: Path, *,
           stop_at_first: bool, executor: str = "local") -> dict[str, Any]:
    t0 = time.perf_counter()
    res = api.search(scenario, space=SPACE, overrides=SET, objective=METRIC,
                     violated_above=ABOVE, sampler=sampler, seed=seed, budget=budget,
                     stop_at_first=stop_at_first, jobs=jobs, out=out, executor=executor,
                     fork=True)
    wall = time.perf_counter() - t0
    s = res.summary
    first = s["first_violation"]
    return {"sampler": sampler, "seed": seed, "found": first is not None,
            "runs_to_first": None if first is None else first + 1,
            "trials": s["counts"]["trials"], "invalid": s["counts"]["invalid"],
            "violated": s["counts"]["violated"], "wall_s": wall,
            "runs_per_s": s["counts"]["trials"] / wall, "exit_code": res.exit_code}


def grid(budget: int, jobs: int, out: Path) -> dict[str, Any]:
    """The sweep srr already has: 5 speeds × 4 start delays over the same ranges."""
    assert budget >= 20, "the grid has 20 points"
    suite = out.parent / "grid_suite.yaml"
    suite.write_text(
        "suite: search-grid\nscenarios:\n"
        f"  - path: {ROOT / PLANTED}\n    name: grid\n    set: {{duration: 28}}\n"
        "    sweep:\n      workers.0.speed: {from: 0.5, to: 2.5, step: 0.5}\n"
        "      workers.0.start_delay: {from: 2, to: 26, step: 8}\n", encoding="utf-8")
    t0 = time.perf_counter()
    res = api.suite([suite], jobs=jobs, out=out, fork=True)
    wall = time.perf_counter() - t0
    runs = res.summary["runs"]  # plan order: the grid's order, the last parameter fastest
    hits = [i for i, r in enumerate(runs)
            if isinstance(r["metrics"].get(METRIC), int | float) and r["metrics"][METRIC] > ABOVE]
    return {"sampler": "grid", "seed": None, "found": bool(hits),
            "runs_to_first": hits[0] + 1 if hits else None, "trials": len(runs),
            "violated": len(hits), "wall_s": wall, "runs_per_s": len(runs) / wall,
            "points": [r["params"] for r in runs if r["metrics"].get(METRIC, 0) > ABOVE]}


def driver_overhead(n: int, batch: int, db: Path, sampler: str) -> dict[str, float]:
    """The search process's own cost per trial, without runs: ask and tell on the
    SQLite study, in batches of ``batch``, a synthetic objective; seconds per trial over the
    first and the last 100 trials (TPE's cost grows with the history)."""
    from harness.search.objective import parse_objective
    from harness.search.space import parse_space
    from harness.search.study import ATTR, ask_batch, open_study

    space = parse_space(SPACE)
    study = open_study(db, parse_objective(METRIC, below=None, above=ABOVE), {"bench": 1})
    per: list[float] = []
    while len(per) < n:
        t0 = time.perf_counter()
        trials = ask_batch(study, space, sampler, 0, batch)
        for t in trials:
            v = float(t.params[space[0].path]) * float(t.params[space[1].path])
            t.set_user_attr(ATTR, {"status": "holds", "value": v})
            study.tell(t, v)
        per += [(time.perf_counter() - t0) / batch] * batch
    return {"first100_s": statistics.mean(per[:100]), "last100_s": statistics.mean(per[-100:]),
            "trials": float(len(per))}


def summarise(rows: list[dict[str, Any]], name: str) -> str:
    mine = [r for r in rows if r["sampler"] == name]
    found = [r for r in mine if r["found"]]
    took = [r["runs_to_first"] for r in found]
    med = f"{statistics.median(took):g}" if took else "—"
    rng = f"{min(took)}–{max(took)}" if took else "—"
    return f"| {name} | {len(found)} / {len(mine)} | {med} | {rng} |"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--no-grid", action="store_true")
    ap.add_argument("--no-reference", action="store_true")
    ap.add_argument("--budget", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--samplers", default="tpe,random")
    ap.add_argument("--ray-budget", type=int, default=8, help="0: no Ray pass")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--driver-sampler", default="tpe")
    ap.add_argument("--driver-trials", type=int, default=0,
                    help="only time the search process's cost per trial over N trials")
    args = ap.parse_args()
    if args.driver_trials:
        with tempfile.TemporaryDirectory(prefix="srr-bench-search-") as tmp:
            d = driver_overhead(args.driver_trials, 16, Path(tmp) / "study.db",
                                args.driver_sampler)
        print(f"driver: {args.driver_sampler} ask + tell on SQLite, batches of 16: "
              f"{d['first100_s']*1e3:.0f} ms per trial over the first 100, "
              f"{d['last100_s']*1e3:.0f} ms over the last 100 of {d['trials']:.0f}")
        return
    print(f"{platform.node()}: {os.cpu_count()} CPUs, Python {platform.python_version()}, "
          f"budget {args.budget}, seeds {args.seeds}, local × {args.jobs}", flush=True)
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="srr-bench-search-") as tmp:
        base = Path(tmp)
        for sampler in args.samplers.split(","):
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                r = search(PLANTED, sampler, seed, args.budget, args.jobs,
                           base / f"{sampler}-{seed}", stop_at_first=True)
                rows.append(r)
                print(json.dumps(r), flush=True)
        g = fa = None
        if not args.no_grid:
            g = grid(args.budget, args.jobs, base / "grid")
            rows.append(g)
            print(json.dumps(g), flush=True)
        if not args.no_reference:
            fa = search(REFERENCE, "tpe", 0, args.budget, args.jobs, base / "reference",
                        stop_at_first=False)
            fa["sampler"] = "reference (tpe, no defect)"
            rows.append(fa)
            print(json.dumps(fa), flush=True)
        ray = None
        if args.ray_budget:
            ray = search(PLANTED, "random", 0, args.ray_budget, args.jobs, base / "ray",
                         stop_at_first=False, executor="ray")
            ray["sampler"] = "ray"
            rows.append(ray)
            print(json.dumps(ray), flush=True)
    print("\n| method | found a violation | runs to the first (median) | range |")
    print("| --- | --- | --- | --- |")
    for name in [*args.samplers.split(","), *([] if g is None else ["grid"])]:
        print(summarise(rows, name))
    if fa is not None:
        print(f"\nno false alarm: reference monitor, {fa['trials']} trials, "
              f"{fa['violated']} violated, exit {fa['exit_code']}")
        print(f"runs/s local × {args.jobs}: reference search {fa['runs_per_s']:.3f} "
              f"({fa['trials']} runs in {fa['wall_s']:.1f} s)")
    if g is not None:
        print(f"runs/s local × {args.jobs}: grid sweep (srr suite) {g['runs_per_s']:.3f}")
    if ray is not None:
        print(f"runs/s ray × {args.jobs} (local cluster, start and stop included): "
              f"{ray['runs_per_s']:.3f} ({ray['trials']} runs in {ray['wall_s']:.1f} s)")
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1), encoding="utf-8")


if __name__ == "__main__":
    main()
