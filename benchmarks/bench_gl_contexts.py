"""OpenGL context creation, one process against many at once (is it the driver's?).

Starts N fresh processes at once (``--procs 1,4,16``); each imports MuJoCo, then makes and
frees one OpenGL context (``mujoco.GLContext``, the backend ``MUJOCO_GL`` selects, as a run's
renderer does) once every one is imported, and prints how long that took. Prints per N the
median and the slowest.

    MUJOCO_GL=egl python benchmarks/bench_gl_contexts.py --procs 1,16
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys

CHILD = """
import sys, time, mujoco
print("ready", flush=True)
sys.stdin.readline()
t0 = time.monotonic()
gl = mujoco.GLContext(64, 64); gl.make_current(); gl.free()
print(time.monotonic() - t0, flush=True)
"""


def once(n: int) -> list[float]:
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    procs = [subprocess.Popen([sys.executable, "-c", CHILD], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True, env=env) for _ in range(n)]
    for p in procs:  # every one imported before any starts: the go is (nearly) at once
        assert p.stdout is not None
        p.stdout.readline()
    for p in procs:
        assert p.stdin is not None
        p.stdin.write("go\n")
        p.stdin.flush()
    return [float(p.communicate()[0].strip().splitlines()[-1]) for p in procs]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--procs", default="1,16")
    args = ap.parse_args()
    for n in (int(x) for x in args.procs.split(",")):
        t = once(n)
        print(f"{n:3d} at once: context made in median {statistics.median(t):.3f} s, "
              f"slowest {max(t):.3f} s", flush=True)


if __name__ == "__main__":
    main()
