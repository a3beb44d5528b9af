"""A recording does not depend on which BLAS kernel the CPU gets.

OpenBLAS (NumPy's ``@``, ``dot`` and the vector ``linalg.norm``) picks its kernel by CPU: a
2-element dot product is a fused multiply-add on AVX-512 kernels and not on AVX2 ones, and a
3x3 product differs between AVX2 and older kernels. Before srr wrote those sums out, the bundled
route follower's ``/cmd_vel`` and the perception stack's ``/perception/tracks`` differed in
their last bits between machines, so a baseline blessed on one machine never matched a run on
another. ``OPENBLAS_CORETYPE`` picks the kernel a machine of another kind would get, in a
process of its own; only kernels this CPU can execute are tried.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from harness.geometry import dot_floats, rotate_rows

ROOT = Path(__file__).resolve().parents[2]

# OpenBLAS kernels and the CPU flags each needs
_NEEDS = {
    "Prescott": {"pni"},  # SSE3
    "Haswell": {"avx2", "fma"},
    "SkylakeX": {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"},
}


def _cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    for line in text.splitlines():
        if line.startswith("flags"):
            return set(line.split(":", 1)[1].split())
    return set()


def _kernels(*names: str) -> tuple[str, ...]:
    flags = _cpu_flags()
    missing = [n for n in names if not _NEEDS[n] <= flags]
    if missing:
        pytest.skip(f"this CPU cannot run OpenBLAS's {', '.join(missing)} kernel")
    return names


def _env(kernel: str) -> dict[str, str]:
    return {**os.environ, "OPENBLAS_CORETYPE": kernel, "PYTHONPATH": str(ROOT)}


_PRODUCTS = """
import hashlib, sys
import numpy as np
from harness.geometry import dot_floats, rotate_rows
rng = np.random.default_rng(3)
v, rot = rng.uniform(-50, 50, (2000, 3)), rng.uniform(-1, 1, (3, 3))
pairs = rng.uniform(-50, 50, (2000, 4)).tolist()
dots = np.array([np.array(p[:2]) @ np.array(p[2:]) for p in pairs])
blas = (v @ rot.T).tobytes() + dots.tobytes()
ours = rotate_rows(v, rot).tobytes() + np.array([dot_floats(p[:2], p[2:]) for p in pairs]).tobytes()
print(hashlib.sha256(blas).hexdigest(), hashlib.sha256(ours).hexdigest())
"""


def _products(kernel: str) -> tuple[str, str]:
    out = subprocess.run([sys.executable, "-c", _PRODUCTS], env=_env(kernel), cwd=ROOT,
                         capture_output=True, text=True, check=True)
    blas, ours = out.stdout.split()
    return blas, ours


def test_the_sums_are_written_out_in_a_fixed_order() -> None:
    rng = np.random.default_rng(5)
    v, rot = rng.uniform(-9, 9, (50, 3)), rng.uniform(-1, 1, (3, 3))
    got = rotate_rows(v, rot)
    for n in range(len(v)):
        x, y, z = v[n].tolist()
        for i in range(3):
            a, b, c = rot[i].tolist()
            assert got[n, i] == x * a + y * b + z * c  # left to right, no fused multiply-add
    assert dot_floats((1.5, -2.0), (4.0, 0.25)) == 5.5
    assert math.copysign(1.0, dot_floats((-0.0,), (1.0,))) == -1.0  # one product: sign kept
    with pytest.raises(ValueError):
        dot_floats((1.0, 2.0), (1.0,))


@pytest.mark.parametrize("kernels", [("Prescott", "Haswell"), ("Haswell", "SkylakeX")])
def test_products_are_the_same_under_every_blas_kernel(kernels: tuple[str, str]) -> None:
    first, second = (_products(k) for k in _kernels(*kernels))
    assert first[1] == second[1]  # srr's sums
    assert first[0] != second[0]  # what BLAS gives for the same products: why srr has its own


@pytest.mark.slow
@pytest.mark.parametrize(("scenario", "seconds", "kernels"), [
    ("dock_nominal", 2.0, ("Prescott", "Haswell")),       # /perception/tracks differed at 0.8 s
    ("diffbot_urdf", 7.0, ("Haswell", "SkylakeX")),       # /cmd_vel differed at 6.1 s
])
def test_a_run_records_the_same_bytes_under_every_blas_kernel(
        tmp_path: Path, scenario: str, seconds: float, kernels: tuple[str, str]) -> None:
    digests = []
    for kernel in _kernels(*kernels):
        out = tmp_path / kernel
        subprocess.run([sys.executable, "-c", "import sys; from harness.cli import main; "
                        "sys.exit(main(sys.argv[1:]))", "run", f"scenarios/{scenario}.yaml",
                        "--duration", str(seconds), "--out", str(out), "-q", "--no-video"],
                       env=_env(kernel), cwd=ROOT, capture_output=True, text=True)
        topics = json.loads((out / "summary.json").read_text())["topics"]
        digests.append({t: row["sha256"] for t, row in topics.items()})
    assert digests[0] == digests[1]
