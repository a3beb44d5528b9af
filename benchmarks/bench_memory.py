"""Memory benchmark: peak resident memory of a 4-camera run against its length.

Runs the camera rig of ``bench_cameras.py`` (``--cameras`` cameras at ``--width`` x
``--height``, ``--fps``, rgb + depth; shadows off) for each of ``--durations`` simulated
seconds, each as a whole ``srr run`` (tick loop, recorder, scoring, summary, report) in a fresh
process, and reports each run's peak resident set (``ru_maxrss`` of that process), its wall
time and bag size, and the ratio of the longest run's peak to the shortest's (target: within
10 %). Each run directory is deleted once measured.

The bag grows with the run: 4 x 640x480 rgb + depth at 30 Hz is 258 MB per simulated second
(155 GB for 600 s), so the default is the rig at 640x480 and 2 Hz (10.3 GB for 600 s); the
images are full-size, only fewer. On the 2-core development machine::

    MUJOCO_GL=egl python benchmarks/bench_memory.py --durations 60,600
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MUJOCO_GL", "egl")


def child(args: argparse.Namespace, duration: float, out: Path) -> None:
    """One run in this process; prints its figures as one JSON line."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import bench_cameras

    from harness import api

    ns = argparse.Namespace(cameras=args.cameras, width=args.width, height=args.height,
                            fps=args.fps, outputs=["rgb", "depth"], duration=duration)
    sc = bench_cameras.load(ns, {"shadows": False})
    page = os.sysconf("SC_PAGE_SIZE")
    rss: list[float] = []  # resident MiB at each tenth of the tick loop

    def progress(k: int, n: int) -> None:
        if k * 10 // n != (k - 1) * 10 // n:
            with open("/proc/self/statm") as f:
                rss.append(int(f.read().split()[1]) * page / 2**20)

    t0 = time.perf_counter()
    res = api.run_scenario(sc, source=str(bench_cameras.SCENARIO), out=out,
                           progress=progress if sys.platform == "linux" else None)
    wall = time.perf_counter() - t0
    bag = sum(p.stat().st_size for p in (out / "bag").rglob("*") if p.is_file())
    frames = sum(v["count"] for t, v in res.summary["topics"].items() if t.endswith("_rgb"))
    print(json.dumps({"duration": duration, "wall_s": wall, "verdict": res.verdict,
                      "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      "bag_bytes": bag, "frames": frames,
                      "rss_mib_each_tenth_of_loop": [round(v, 1) for v in rss]}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cameras", type=int, default=4)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("--fps", type=float, default=2.0)
    ap.add_argument("--durations", type=lambda s: [float(v) for v in s.split(",")],
                    default=[60.0, 600.0], help="comma-separated simulated seconds")
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    ap.add_argument("--child", type=float, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child is not None:
        child(args, args.child, args.out)
        return
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"python {platform.python_version()}, MUJOCO_GL={os.environ.get('MUJOCO_GL')}")
    print(f"rig: {args.cameras} cameras {args.width}x{args.height} rgb + depth at "
          f"{args.fps:g} Hz, shadows off; each duration a whole srr run in its own process")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for d in args.durations:
            out = Path(tmp) / f"run_{d:g}"
            cmd = [sys.executable, __file__, "--child", str(d), "--out", str(out),
                   "--cameras", str(args.cameras), "--width", str(args.width),
                   "--height", str(args.height), "--fps", str(args.fps)]
            done = subprocess.run(cmd, check=True, capture_output=True, text=True)
            row = json.loads(done.stdout.strip().splitlines()[-1])
            shutil.rmtree(out, ignore_errors=True)
            rows.append(row)
            print(f"  {d:7g} s simulated: peak {row['peak_mib']:7.1f} MiB, wall "
                  f"{row['wall_s']:6.1f} s, {row['frames']} camera frames, "
                  f"bag {row['bag_bytes'] / 1e9:.2f} GB, {row['verdict']}")
    short, long_ = rows[0], rows[-1]
    ratio = long_["peak_mib"] / short["peak_mib"]
    for row in rows:
        if row.get("rss_mib_each_tenth_of_loop"):
            print(f"  {row['duration']:7g} s: resident MiB at each tenth of the tick loop: "
                  + ", ".join(f"{v:.0f}" for v in row["rss_mib_each_tenth_of_loop"]))
    print(f"peak {long_['duration']:g} s ÷ {short['duration']:g} s: {ratio:.3f} "
          f"(target <= 1.10)")
    if args.json is not None:
        args.json.write_text(json.dumps({"rows": rows, "ratio": ratio}, indent=2))


if __name__ == "__main__":
    main()
