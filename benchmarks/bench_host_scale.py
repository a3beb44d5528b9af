"""What a machine gives N identical processes at once, without srr: the bound on any suite's
efficiency there.

Each process runs the same fixed work — a pure-Python loop (``spin``: what a tick loop's
interpreter does), NumPy copies of 64 MiB arrays (``mem``: what recording camera images
does), or MuJoCo drawing and reading back one 640×480 camera's colour and depth in an
OpenGL context of its own (``render``: what a camera run's renderer does; the context is
made before the timing starts) — first alone, then N at once; the per-process speed is the
time alone over the mean time at once. A suite of runs like these can reach at most about
that efficiency at N workers (runs/s at N ÷ (N × runs/s at 1)), whatever its scheduler does.

    python benchmarks/bench_host_scale.py --procs 4,8,16
    MUJOCO_GL=egl python benchmarks/bench_host_scale.py --procs 16 --work render
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import statistics
import time
from collections.abc import Callable
from typing import Any


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


#: A floor, a box and a camera: what ``render`` draws.
SCENE = """<mujoco><visual><global offwidth="640" offheight="480"/></visual><worldbody>
<light pos="0 0 4" dir="0 0 -1"/><geom type="plane" size="6 6 .1" rgba=".6 .6 .6 1"/>
<body pos="0 0 .5"><geom type="box" size=".4 .3 .5" rgba=".9 .4 .1 1"/></body>
<camera name="cam" pos="3 -3 2.5" xyaxes="1 1 0 -.4 .4 1"/></worldbody></mujoco>"""


def render(n: int) -> float:
    import mujoco

    model = mujoco.MjModel.from_xml_string(SCENE)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    renderer = mujoco.Renderer(model, 480, 640)  # its OpenGL context, made here, untimed
    renderer.update_scene(data, camera="cam")
    renderer.render()
    if _START is not None:  # every process has its context: they draw at the same time
        _START.wait()
    t0 = time.perf_counter()
    for _ in range(n):
        renderer.update_scene(data, camera="cam")
        renderer.render()
        renderer.enable_depth_rendering()
        renderer.render()
        renderer.disable_depth_rendering()
    elapsed = time.perf_counter() - t0
    renderer.close()
    return elapsed


WORK: dict[str, tuple[Callable[[int], float], int]] = {
    "spin": (spin, 6_000_000), "mem": (mem, 40), "render": (render, 300)}


_START: Any = None  # a barrier the processes of one ``render`` pass wait at


def mean_time(fn: Callable[[int], float], n: int, procs: int) -> float:
    global _START
    ctx = mp.get_context("fork")
    _START = ctx.Barrier(procs)  # inherited by the pool's processes, forked next
    with ctx.Pool(procs) as pool:
        times = pool.map(fn, [n] * procs)
    return sum(times) / len(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--procs", default="4,8,16", help="process counts, comma-separated")
    ap.add_argument("--rounds", type=int, default=3, help="alone / at once pairs (median)")
    ap.add_argument("--work", default="spin,mem",
                    help=f"kinds of work, comma-separated, of {', '.join(WORK)}")
    args = ap.parse_args()
    work = args.work.split(",")
    if unknown := [w for w in work if w not in WORK]:
        ap.error(f"--work: unknown {', '.join(unknown)} (known: {', '.join(WORK)})")
    for fn, n in (WORK[w] for w in work):
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
