"""What a machine gives N identical processes at once, without srr: the bound on any suite's
efficiency there.

Each process runs the same fixed work — a pure-Python loop (``spin``: what a tick loop's
interpreter does) or NumPy copies of 64 MiB arrays (``mem``: what recording camera images
does) — first alone, then N at once; the per-process speed is the time alone over the mean
time at once. A suite of runs like these can reach at most about that efficiency at N workers
(runs/s at N ÷ (N × runs/s at 1)), whatever its scheduler does.

    python benchmarks/bench_host_scale.py --procs 4,8,16
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import statistics
import time
from collections.abc import Callable


def spin(n: int) -> float:
    t0 = time.perf_counter()
    x = 0
    for i in range(n):
        x += i * i % 7
    return time.perf_counter() - t0


def mem(n: int) -> float:
    import numpy as np

    a = np.ones(64 * 1024 * 1024 // 8)
    b = np.empty_like(a)
    t0 = time.perf_counter()
    for _ in range(n):
        np.copyto(b, a)
        a += 1.0
    return time.perf_counter() - t0


def mean_time(fn: Callable[[int], float], n: int, procs: int) -> float:
    with mp.get_context("fork").Pool(procs) as pool:
        times = pool.map(fn, [n] * procs)
    return sum(times) / len(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--procs", default="4,8,16", help="process counts, comma-separated")
    ap.add_argument("--rounds", type=int, default=3, help="alone / at once pairs (median)")
    args = ap.parse_args()
    for fn, n in ((spin, 6_000_000), (mem, 40)):
        for k in (int(p) for p in args.procs.split(",")):
            alone, at_once = [], []
            for _ in range(args.rounds):  # alternating, so both see the same machine state
                alone.append(mean_time(fn, n, 1))
                at_once.append(mean_time(fn, n, k))
            a, b = statistics.median(alone), statistics.median(at_once)
            print(f"{fn.__name__}: alone {a:.2f} s; {k} at once {b:.2f} s each; "
                  f"per-process speed {a / b:.2f}")


if __name__ == "__main__":
    main()
