"""How a suite scales with local workers, and where the wall time goes.

Runs ``srr suite SUITE --jobs N --repeat R -q`` as a user would (a fresh process, this tree
first on ``PYTHONPATH``; ``--other DIR`` also runs another checkout, e.g. an older commit
unpacked with ``git archive COMMIT | tar -x -C DIR``, alternating with this one) for each
``--configs`` entry ``JOBS:REPEAT``, and prints per pass: runs, the command's wall time, runs/s,
the wall time outside the runs (start-up, planning and checking, the wait for the first run,
judging and pages; from the suite's ``timeline`` where the tree writes one, else the command's
wall time less the runs' walls over the workers), the workers' utilization, the runs' summed
steps (from ``timings``), when the first run began after the command was launched, and the
verdict (every pass must end PASS). Then, per tree, the efficiency of every entry with N > 1
workers against the 1-worker entry: runs/s at N ÷ (N × runs/s at 1); several entries may share
N (``1:2,16:6,16:12``: the same 16 workers on 59 and on 113 runs). ``--rounds R`` runs the
whole list R times (the trees alternating in each round); each efficiency is then the median
runs/s at N over the median at 1, with the range of every N-worker pass against every
1-worker pass beside it: on a shared host one 1-worker pass moves by up to a fifth, and the
ratio divides by it.

Where the tree's runs time their CPU (``timings["cpu_s"]``), each pass also prints the runs'
CPU seconds, per run, and how many CPUs a run kept busy; each efficiency line then adds the
CPU ceiling, min(1, C ÷ (N × the CPU seconds the 1-worker pass's runs spent per second of its
wall)) on a machine of C CPUs (N workers cannot finish runs faster than C CPUs do their work,
if a run's work is what it was at 1 worker), and the CPU a run took at N workers against 1
(above 1: each CPU did less at N, the machine's share per process, not srr's scheduling).
Each efficiency line also gives the efficiency inside the runs' span (first start to last
finish, each pass's own): what the workers achieved once running, without the start-up
before the first run and the judging after the last, which every pass pays once.

    MUJOCO_GL=egl python benchmarks/bench_suite_scale.py --configs 1:2,16:6 [--other DIR] \
        [--rounds 3]
    python benchmarks/bench_suite_scale.py --show OUT/summary.json     # one suite's timeline
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
ORDER = ("start", "load", "build", "first_tick", "loop", "finish", "exit")


#: ``srr suite`` as ``python -m harness.cli`` runs it, noting when the first run began (the
#: earliest ``ready`` instant of the runs' clocks, read as the executor takes each clock; the
#: clocks are ``time.monotonic``, one clock for every process of a Linux machine).
CLI = """
import os, sys
first = []
try:  # a tree older than the suite's timeline records no first start
    import harness.suite.timeline as tl
except ImportError:
    tl = None
if tl is not None:
    _take = tl.take_clock
    def take(path, submitted, reaped):
        clock = _take(path, submitted, reaped)
        first.append(clock.get("ready", reaped))
        return clock
    tl.take_clock = take
from harness.cli import main
try:
    code = main(sys.argv[1:])
finally:
    if first:
        with open(os.environ["SRR_BENCH_FIRST"], "w") as f:
            f.write(repr(min(first)))
sys.exit(code)
"""


def one_pass(tree: Path, suite: str, jobs: int, repeat: int, out: Path) -> dict[str, Any]:
    first_file = out.with_name(out.name + ".first")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        p for p in (str(tree), os.environ.get("PYTHONPATH")) if p),
        "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"), "SRR_BENCH_FIRST": str(first_file)}
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, "-c", CLI, "suite", suite, "--jobs",
                           str(jobs), "--repeat", str(repeat), "--out", str(out), "-q"],
                          cwd=tree, env=env, capture_output=True, text=True, check=False)
    wall = time.monotonic() - t0
    try:
        to_first: float | None = float(first_file.read_text()) - t0
    except (OSError, ValueError):
        to_first = None
    if proc.returncode == 2 or not (out / "summary.json").is_file():
        raise SystemExit(f"{tree}: the suite did not run (exit {proc.returncode}):\n"
                         f"{proc.stderr[-2000:]}")
    s = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    runs = s["runs"]
    busy = sum(r["wall_s"] for r in runs)
    tl = s.get("timeline") or {}
    span = (tl["last_finish_s"] - tl["first_start_s"]) if "last_finish_s" in tl else None
    return {"runs": len(runs), "wall": wall, "busy": busy, "verdict": s["verdict"],
            "outside": wall - span if span is not None else wall - busy / jobs,
            "checked": tl.get("checked_s"), "first": tl.get("first_start_s"),
            "after": (s["wall_s"] - tl["last_finish_s"]) if span is not None else None,
            "util": busy / (jobs * (span if span else wall)), "steps": tl.get("steps_s"),
            "to_first": to_first, "cpu": tl.get("cpu_s"), "cpus": tl.get("cpus"),
            "span": span, "summary": s}


def _median(passes: list[dict[str, Any]], num: str, den: str) -> float | None:
    """The median of ``num / den`` over ``passes``; None when a pass lacks either (a tree
    that records no CPU time or no timeline)."""
    if not all(p[num] and p[den] for p in passes):
        return None
    return float(statistics.median(p[num] / p[den] for p in passes))


def show(summary: dict[str, Any], width: int = 100) -> None:
    """Each worker slot's runs along the suite's time, one character a step."""
    runs = [r for r in summary["runs"] if r.get("timings")]
    if not runs:
        print("no timings in this summary")
        return
    end = max(r["timings"]["finished_s"] for r in runs)
    scale = width / end if end > 0 else 1.0
    letters = {"start": "s", "load": "l", "build": "b", "first_tick": "g", "loop": "=",
               "finish": "f", "exit": "x"}
    slots: list[list[str]] = []
    free: list[float] = []
    for r in sorted(runs, key=lambda r: r["timings"]["started_s"]):
        t = r["timings"]
        k = next((i for i, f in enumerate(free) if f <= t["started_s"] + 1e-6), None)
        if k is None:
            slots.append([" "] * (width + 1))
            free.append(0.0)
            k = len(slots) - 1
        free[k] = t["finished_s"]
        at = t["started_s"]
        for step in letters:
            secs = t["steps"].get(step)
            if secs is None:
                continue
            a, b = round(at * scale), round((at + secs) * scale)
            for c in range(a, max(a + 1, b)):
                slots[k][min(c, width)] = letters.get(step, "?")
            at += secs
    tl = summary.get("timeline", {})
    print(f"{summary['name']}: {len(summary['runs'])} runs on {summary['jobs']} workers, "
          f"{summary['wall_s']:.1f} s from the first submission (checking before: "
          f"{tl.get('checked_s', 0):.1f} s), one column = {end / width:.2f} s")
    print("  s start  l load  b build  g first tick  = ticks  f score+report  x exit")
    for i, row in enumerate(slots):
        print(f"{i:3d} |{''.join(row).rstrip()}")
    steps = tl.get("steps_s") or {}
    print("summed steps (s): " + "  ".join(f"{k} {steps[k]:.1f}" for k in letters if k in steps)
          + f"  gl_context {tl.get('gl_context_s', 0):.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--suite", default="scenarios/suites/nightly.yaml")
    ap.add_argument("--configs", default="1:2,16:6", help="JOBS:REPEAT,...")
    ap.add_argument("--other", type=Path, help="another checkout to run alternately")
    ap.add_argument("--rounds", type=int, default=1,
                    help="run the whole list of configurations this many times (the trees "
                         "alternating in each); efficiencies from each configuration's median")
    ap.add_argument("--json", type=Path, help="write every pass's figures here")
    ap.add_argument("--timeline", action="store_true", help="draw each pass's timeline")
    ap.add_argument("--show", type=Path, help="only draw this summary.json's timeline")
    ap.add_argument("--keep", type=Path, help="copy each pass's summary.json into this folder")
    args = ap.parse_args()
    if args.show:
        try:
            summary = json.loads(args.show.read_text(encoding="utf-8"))
            if not isinstance(summary, dict) or not isinstance(summary.get("runs"), list):
                raise ValueError("not a suite's summary.json (no runs)")
        except (OSError, ValueError) as err:
            print(f"--show {args.show}: {err}", file=sys.stderr)
            raise SystemExit(2) from None
        show(summary)
        return
    trees = [("other", args.other.resolve()), ("this", ROOT)] if args.other else [("this", ROOT)]
    configs = [tuple(int(x) for x in c.split(":")) for c in args.configs.split(",")]
    print(f"machine: {os.cpu_count()} CPUs; suite {args.suite}")
    results: dict[str, dict[tuple[int, int], list[dict[str, Any]]]] = {
        name: {} for name, _ in trees}
    with tempfile.TemporaryDirectory() as tmp:
        for k, (jobs, repeat) in enumerate(configs * args.rounds):
            for name, tree in trees:
                # a folder per pass: a configuration listed twice runs twice, and every pass
                # counts in its configuration's medians
                r = one_pass(tree, args.suite, jobs, repeat,
                             Path(tmp) / f"{name}_{jobs}_{repeat}_{k}")
                passes = results[name].setdefault((jobs, repeat), [])
                passes.append(r)
                if args.keep:
                    args.keep.mkdir(parents=True, exist_ok=True)
                    (args.keep / f"summary_{name}_{jobs}_{repeat}_{len(passes)}.json"
                     ).write_text(json.dumps(r["summary"]), encoding="utf-8")
                steps = r["steps"] or {}
                print(f"{name:5s} ×{jobs:<2d} {r['runs']:3d} runs  wall {r['wall']:6.1f} s  "
                      f"{r['runs'] / r['wall']:5.2f} runs/s  outside runs {r['outside']:5.1f} s"
                      + (f" (checked {r['checked']:.1f}, first start {r['first']:.2f}, after "
                         f"{r['after']:.1f})" if r["checked"] is not None else "")
                      + (f"  first run began {r['to_first']:.2f} s after the launch"
                         if r["to_first"] is not None else "")
                      + f"  util {r['util']:.2f}  run walls {r['busy']:6.1f} s  "
                      + (f"CPU {r['cpu']:.1f} s ({r['cpu'] / r['runs']:.2f} s a run, "
                         f"{r['cpus']:.2f} CPUs a run)  " if r["cpu"] else "")
                      + f"{r['verdict']}", flush=True)
                if steps:
                    print("        steps (s): " + "  ".join(f"{k} {steps[k]:.1f}" for k in ORDER
                                                          if k in steps))
                cams = [r2["wall_s"] for r2 in r["summary"]["runs"]
                        if r2["scenario"] == "dock_worker_crossing"]
                if cams:
                    print(f"        dock_worker_crossing median wall "
                          f"{statistics.median(cams):.2f} s")
                if args.timeline:
                    show(r["summary"])
                if r["verdict"] != "PASS":
                    raise SystemExit(f"{name} ×{jobs}: the suite did not pass")
    for name, by_config in results.items():
        ones = [r for (jobs, _), rs in by_config.items() if jobs == 1 for r in rs]
        if not ones:
            continue
        # medians over every 1-worker pass: a single pass moves by up to a fifth between
        # passes on a shared host, and the efficiency divides by it
        one = _median(ones, "runs", "wall")
        assert one is not None  # every pass ran (and passed) at least one run
        cpu_rate = _median(ones, "cpu", "wall")
        cpu_run = _median(ones, "cpu", "runs")
        one_span = _median(ones, "runs", "span")
        for (n, repeat), rs in by_config.items():
            if n > 1:
                many = _median(rs, "runs", "wall")
                assert many is not None
                cpu = ""
                cpu_n = _median(rs, "cpu", "runs")
                if cpu_rate and cpu_run and cpu_n:
                    ceiling = min(1.0, (os.cpu_count() or 1) / (n * cpu_rate))
                    cpu = (f"; CPU ceiling {ceiling:.2f}, CPU a run ×{cpu_n / cpu_run:.2f} of "
                           "one worker's")
                span_n = _median(rs, "runs", "span")
                if one_span and span_n:  # the start-up and the end left out
                    cpu += f"; inside the runs' span {span_n / (n * one_span):.2f}"
                spread = ""
                if len(rs) > 1 or len(ones) > 1:  # each N-worker pass against each 1-worker one
                    each = [(r["runs"] / r["wall"]) / (n * o["runs"] / o["wall"])
                            for r in rs for o in ones]
                    spread = f" (pass against pass {min(each):.2f}–{max(each):.2f})"
                print(f"{name}: efficiency at {n} workers, {rs[0]['runs']} runs (repeat {repeat}) "
                      f"= {many / (n * one):.2f}{spread} (median {many:.2f} runs/s against "
                      f"{n} × {one:.3f}, medians of {len(rs)} and {len(ones)} passes)" + cpu)
    if args.json:
        args.json.write_text(json.dumps({k: {f"{j}:{rep}": [{kk: vv for kk, vv in v.items()
                                                            if kk != "summary"} for v in vs]
                                             for (j, rep), vs in d.items()}
                                         for k, d in results.items()}, indent=1))


if __name__ == "__main__":
    main()
