#!/usr/bin/env bash
# Issue 13's camera figures in one command, for the GPU machine (run from anywhere):
#
#   MUJOCO_GL=egl benchmarks/gpu_rig.sh [all|cameras|memory]      (default: all, ~7 min on an H100)
#
# cameras: 4 x 640x480 rgb + depth at 30 Hz, 20 s simulated, best of 3, for shadows off, on
#          (1024² map) and on with a 4096² map: the render-only limit (sets/s), srr's loop
#          throughput and its ratio to the limit (target >= 0.85), srr's RTF for the whole run
#          (target >= 4 with shadows off), the bare loop and srr / bare.
# memory:  peak resident memory of a whole 4-camera srr run of 60 s and of 600 s simulated
#          (640x480 rgb + depth at 2 Hz: the 30 Hz bag of 600 s would be 155 GB), and their
#          ratio (target <= 1.10).
# Disk: at most ~11 GB at a time (each run's bag is deleted once measured). Figures also go to
# $OUT (default: ./gpu_rig_out) as JSON. PYTHON selects the interpreter (default: python).
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
      --duration 20 --outputs rgb,depth --repeats 3 --configs off,on,on4096 \
      --json "$OUT/cameras.json"
fi
if [[ "$what" == all || "$what" == memory ]]; then
  echo "== memory: peak resident memory, 60 s against 600 s"
  "$PY" benchmarks/bench_memory.py --cameras 4 --width 640 --height 480 --fps 2 \
      --durations 60,600 --json "$OUT/memory.json"
fi
