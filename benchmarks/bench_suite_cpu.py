"""The bundled nightly suite as CI runs it, wall and CPU time, this tree against another.

Runs ``srr suite scenarios/suites/nightly.yaml`` (local workers, one per CPU: the CI command)
with this checkout and, alternating, with the checkout at ``--other`` (e.g. an older commit
unpacked with ``git archive COMMIT | tar -x -C DIR``), ``--pairs`` times, each in a fresh
process with that tree first on ``PYTHONPATH``. Prints per pass the suite's wall time, the CPU
time (user + sys) of it and every worker, the machine's load average before and after, and
the verdict (every pass must end PASS). On the 2-core development machine::

    git archive aa98f36 | tar -x -C /tmp/before
    MUJOCO_GL=egl python benchmarks/bench_suite_cpu.py --other /tmp/before --pairs 2
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def one_pass(tree: Path, out: Path) -> tuple[float, float, str]:
    env = {**os.environ, "PYTHONPATH": str(tree), "MUJOCO_GL": os.environ.get("MUJOCO_GL",
                                                                               "egl")}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "harness.cli", "suite", "scenarios/suites/nightly.yaml",
                    "--out", str(out), "-q"], cwd=tree, env=env, capture_output=True, check=False)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    verdict = json.loads((out / "summary.json").read_text(encoding="utf-8"))["verdict"]
    return wall, cpu, verdict


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--other", type=Path, required=True, help="the other tree (e.g. before)")
    ap.add_argument("--pairs", type=int, default=2)
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} CPUs; this tree {ROOT}, other {args.other}")
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.pairs):
            for name, tree in (("other", args.other), ("this", ROOT)):
                out = Path(tmp) / f"{name}_{i}"
                load0 = os.getloadavg()[0]
                wall, cpu, verdict = one_pass(tree, out)
                print(f"  {name:5s} wall {wall:6.1f} s  CPU {cpu:6.1f} s  {verdict}  "
                      f"(load average {load0:.1f} before, {os.getloadavg()[0]:.1f} after)",
                      flush=True)
                shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
