"""Where ``srr suite``'s own start-up goes, before its first run: importing srr, importing what
a run needs after its loop (shared with the hosts), forking the hosts, checking the suite.

    MUJOCO_GL=egl python benchmarks/bench_suite_start.py scenarios/suites/nightly.yaml --hosts 16

Each phase is timed once, in order, in this process (run it a few times: the first pass warms
the file cache). The hosts are stopped at the end; they run nothing.
"""

from __future__ import annotations

import argparse
import time


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("suite", help="a suite file")
    ap.add_argument("--hosts", type=int, default=16, help="hosts to fork (default 16)")
    args = ap.parse_args()
    t0 = time.monotonic()
    import harness.api as api
    import harness.cli  # noqa: F401 - what `srr suite` imports
    from harness.run.record import import_after_the_loop
    from harness.suite import host

    t1 = time.monotonic()
    import_after_the_loop()
    t2 = time.monotonic()
    try:
        host.start_early(args.hosts)
        t3 = time.monotonic()
        plan = api.plan_suite([args.suite], on_render=host.warm_early)
        t4 = time.monotonic()
    finally:
        host.stop_early()
    print(f"import srr {t1 - t0:.3f} s, after-the-loop modules {t2 - t1:.3f} s, "
          f"{args.hosts} hosts forked {t3 - t2:.3f} s, "
          f"checking {len(plan.runs)} runs {t4 - t3:.3f} s")


if __name__ == "__main__":
    main()
