"""The ``srr`` command runs NumPy's and SciPy's OpenBLAS on one thread unless the user chose a
count, and hands the user's own choice (not srr's) to the processes it starts."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from harness.blas import one_blas_thread, users_environ

ROOT = Path(__file__).resolve().parents[1]

# srr's command, then what its runs import, then the threads of the process
_PROBE = """
import os, sys
from harness.cli import main
main(["validate", sys.argv[1]])
import numpy, scipy.optimize
print(len(os.listdir("/proc/self/task")), os.environ.get("OPENBLAS_NUM_THREADS"))
"""


def _probe(env: dict[str, str], *, srr: bool = True) -> tuple[int, str]:
    code = _PROBE if srr else _PROBE.replace('main(["validate", sys.argv[1]])', "")
    out = subprocess.run([sys.executable, "-c", code, str(ROOT / "scenarios" / "dock_empty.yaml")],
                         env=env, cwd=ROOT, capture_output=True, text=True, check=True)
    threads, value = out.stdout.split()[-2:]
    return int(threads), value


def _clean_env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items()
            if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                         "SRR_ADDED_OPENBLAS_NUM_THREADS")}


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/task").is_dir() or (os.cpu_count() or 1) < 2,
                    reason="counts a process's threads in /proc; OpenBLAS starts none on one CPU")
def test_the_srr_command_starts_no_blas_threads_unless_the_user_asks() -> None:
    env = _clean_env()
    plain, _ = _probe(env, srr=False)
    assert plain > 1  # NumPy and SciPy alone: a pool of BLAS threads
    assert _probe(env) == (1, "1")  # under srr's command: the main thread alone
    # the user's count wins
    threads, value = _probe({**env, "OPENBLAS_NUM_THREADS": "2"})
    assert value == "2" and threads > 1
    threads, value = _probe({**env, "OMP_NUM_THREADS": "2"})
    assert value == "None" and threads > 1


def test_processes_srr_starts_get_the_users_blas_setting() -> None:
    env: dict[str, str] = {"PATH": "/bin"}
    assert one_blas_thread(env) is True
    assert env["OPENBLAS_NUM_THREADS"] == "1"
    assert users_environ(env) == {"PATH": "/bin"}
    # a user's own setting is kept, and handed on as it is
    mine = {"PATH": "/bin", "OPENBLAS_NUM_THREADS": "8"}
    assert one_blas_thread(mine) is False
    assert users_environ(mine) == mine
    omp = {"OMP_NUM_THREADS": "4"}
    assert one_blas_thread(omp) is False and omp == {"OMP_NUM_THREADS": "4"}
