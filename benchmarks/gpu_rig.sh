#!/usr/bin/env bash
# Issue 13's camera figures in one command, for the GPU machine (run from anywhere):
#
#   MUJOCO_GL=egl benchmarks/gpu_rig.sh [all|cameras|memory|suite]  (default: all, ~7 min on an H100)
#
# cameras: 4 x 640x480 rgb + depth at 30 Hz, best of 2: shadows off for 60 s simulated (so that
#          the whole run's fixed costs, ~1 s, weigh little in its RTF), then shadows on (1024²
#          map) and on with a 4096² map for 20 s each: the render-only limit (sets/s), srr's loop
#          throughput and its ratio to the limit (target >= 0.85), srr's RTF for the whole run
#          (target >= 4 with shadows off), where the loop waited, and (shadows off) the bare loop
#          and srr / bare.
# memory:  peak resident memory of a whole 4-camera srr run of 60 s and of 600 s simulated
#          (640x480 rgb + depth at 2 Hz: the 30 Hz bag of 600 s would be 155 GB), and their
#          ratio (target <= 1.10).
# suite:   the nightly suite on 1 worker (23 runs) and on 16 (--repeat 6: 59 runs): runs/s, time
#          outside the runs, utilization, summed steps, efficiency (target >= 0.8), and
#          OpenGL context creation, 1 / 4 / 16 processes at once (~2 min; not part of "all").
# Under a 10-minute limit per command run "cameras" and "memory" separately. Disk: at most
# ~16 GB at a time (each run's bag is deleted once measured). Figures also go to $OUT (default:
# ./gpu_rig_out) as JSON. PYTHON selects the interpreter (default: python).
set -euo pipefail
cd "$(dirname "$0")/.."
export MUJOCO_GL="${MUJOCO_GL:-egl}"
PY="${PYTHON:-python}"
OUT="${OUT:-gpu_rig_out}"
what="${1:-all}"
mkdir -p "$OUT"
echo "== $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD 2>/dev/null || echo '?')"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
"$PY" -c 'import mujoco, numpy; print("mujoco", mujoco.__version__, "numpy", numpy.__version__)'
if [[ "$what" == all || "$what" == cameras ]]; then
  echo "== cameras: srr against the render-only limit"
  "$PY" benchmarks/bench_cameras.py --cameras 4 --width 640 --height 480 --fps 30 \
      --duration 60 --outputs rgb,depth --repeats 2 --configs off --json "$OUT/cameras_off.json"
  "$PY" benchmarks/bench_cameras.py --cameras 4 --width 640 --height 480 --fps 30 \
      --duration 20 --outputs rgb,depth --repeats 2 --configs on,on4096 --skip-bare \
      --json "$OUT/cameras_shadows.json"
fi
if [[ "$what" == suite ]]; then
  echo "== suite: 1 and 16 workers"
  "$PY" benchmarks/bench_gl_contexts.py --procs 1,4,16
  "$PY" benchmarks/bench_suite_scale.py --configs 1:2,16:6 --json "$OUT/suite.json"
fi
if [[ "$what" == all || "$what" == memory ]]; then
  echo "== memory: peak resident memory, 60 s against 600 s"
  "$PY" benchmarks/bench_memory.py --cameras 4 --width 640 --height 480 --fps 2 \
      --durations 60,600 --json "$OUT/memory.json"
fi
