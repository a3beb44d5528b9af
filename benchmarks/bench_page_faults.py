"""Page faults of recording raw camera images: srr's whole run against the render-only loop.

The scene is ``bench_cameras.py``'s (``--cameras`` cameras at ``--width`` x ``--height`` and
``--fps``, publishing ``--outputs``, shadows off). The render-only loop (draws and read-backs
into the same buffers) runs once to warm up, then once measured; then ``api.run_scenario``
runs the scene (no report videos). Each prints camera sets per second and, from
``getrusage`` (every thread of this process), minor page faults and CPU milliseconds per
camera set. The srr figure includes the run's fixed costs (building the scene, scoring): run
two durations and take the difference to get the loop's own::

    MUJOCO_GL=egl python benchmarks/bench_page_faults.py --duration 3
    MUJOCO_GL=egl python benchmarks/bench_page_faults.py --duration 12

``GLIBC_TUNABLES=glibc.malloc.mmap_threshold=...`` and the like change how the allocator
returns memory to the system; run with and without to see whether fresh pages cost.
"""

from __future__ import annotations

import argparse
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_cameras as bc  # first: it sets MUJOCO_GL and puts the project on the path

from harness import api


def _usage() -> tuple[int, float]:
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_minflt, ru.ru_utime + ru.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    bc.scene_args(ap, cameras=4, width=640, height=480, duration=5.0)
    args = ap.parse_args()
    sc = bc.load(args, bc.CONFIGS["off"])
    bc.render_only(sc)  # warm-up: contexts, buffers, caches
    f0, c0 = _usage()
    wall, frames = bc.render_only(sc)
    f1, c1 = _usage()
    sets = frames / args.cameras
    print(f"render-only: {sets / wall:.1f} sets/s, {(f1 - f0) / sets:.0f} minor faults a set, "
          f"{(c1 - c0) / sets * 1e3:.2f} CPU ms a set")
    out = Path(tempfile.mkdtemp())
    try:
        f0, c0 = _usage()
        t0 = time.perf_counter()
        api.run_scenario(sc, source=str(bc.SCENARIO), out=out / "run", video=False)
        wall = time.perf_counter() - t0
        f1, c1 = _usage()
    finally:
        shutil.rmtree(out, ignore_errors=True)
    print(f"srr run ({sets:.0f} sets, fixed costs included): {sets / wall:.1f} sets/s, "
          f"{f1 - f0} minor faults ({(f1 - f0) / sets:.0f} a set), "
          f"{(c1 - c0) / sets * 1e3:.2f} CPU ms a set")


if __name__ == "__main__":
    main()
