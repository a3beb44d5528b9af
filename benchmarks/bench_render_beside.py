"""The render-only limit alone and beside one process that writes, copies or spins.

Which kind of work beside the renderer slows its draw? ``bench_cameras.py``'s render-only loop
(``--cameras`` cameras at ``--width`` x ``--height``, rgb + depth, shadows off, ``--duration``
simulated seconds) is timed alone, then beside one background process doing one of:

* ``write``: ``os.write`` of 8.6 MB buffers (a 4 × 640×480 rgb + depth camera set) to a file
  in ``--dir`` (truncated every 1 GB), as a recorder's writer does, unthrottled;
* ``copy``: NumPy copies of the same buffers in memory (the same bytes, no system calls);
* ``spin``: a pure-Python loop (CPU only).

Conditions alternate over ``--rounds``; each prints camera sets per second and the background
process's bytes per second. ``--dir`` selects the file system the writes go to (``/tmp``,
``/dev/shm``, a disk), so a sandboxed kernel's write path can be told from memory traffic::

    MUJOCO_GL=egl python benchmarks/bench_render_beside.py --dir /tmp --rounds 2
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_cameras as bc  # first: it sets MUJOCO_GL and puts the project on the path

SET_BYTES = 4 * 640 * 480 * (3 + 4)


def _background(kind: str, directory: str, stop: mp.synchronize.Event, rate: mp.Value) -> None:
    import numpy as np

    buf = np.random.default_rng(0).integers(0, 255, SET_BYTES, dtype=np.uint8)
    out = np.empty_like(buf)
    done, t0 = 0, time.perf_counter()
    if kind == "write":
        path = Path(directory) / f"beside-{os.getpid()}.bin"
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        try:
            while not stop.is_set():
                os.write(fd, buf)
                done += SET_BYTES
                if done % (1 << 30) < SET_BYTES:
                    os.ftruncate(fd, 0)
                    os.lseek(fd, 0, os.SEEK_SET)
        finally:
            os.close(fd)
            path.unlink()
    elif kind == "copy":
        while not stop.is_set():
            np.copyto(out, buf)
            done += SET_BYTES
    else:
        n = 0
        while not stop.is_set():
            for _ in range(10_000):
                n += 1
    rate.value = done / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    bc.scene_args(ap, cameras=4, width=640, height=480, duration=20.0)
    ap.add_argument("--dir", default="/tmp", help="where 'write' writes (default /tmp)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--kinds", default="alone,write,copy,spin")
    args = ap.parse_args()
    sc = bc.load(args, bc.CONFIGS["off"])
    bc.render_only(sc)  # warm-up
    ctx = mp.get_context("spawn")
    for r in range(args.rounds):
        for kind in args.kinds.split(","):
            proc = None
            stop, rate = ctx.Event(), ctx.Value("d", 0.0)
            if kind != "alone":
                proc = ctx.Process(target=_background, args=(kind, args.dir, stop, rate))
                proc.start()
                time.sleep(1.0)  # started and at full speed
            wall, frames = bc.render_only(sc)
            if proc is not None:
                stop.set()
                proc.join()
            print(f"round {r + 1} {kind:6s}: render-only {frames / args.cameras / wall:6.1f} "
                  f"sets/s" + (f", beside {rate.value / 1e9:.2f} GB/s" if kind in
                               ("write", "copy") else ""), flush=True)


if __name__ == "__main__":
    main()
