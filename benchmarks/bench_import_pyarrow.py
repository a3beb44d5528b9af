"""Whether pyarrow slows the import of pandas that a suite's start pays (pandas 3 imports
pyarrow when it is installed, for its string columns).

    python benchmarks/bench_import_pyarrow.py --rounds 5

Each round times, in fresh interpreters one after the other: ``import pandas``; the same with
``pyarrow`` made unimportable (a finder that refuses it); ``import pyarrow`` alone; and
``import scipy.optimize`` after pandas (the assignment solver scoring needs). The first round
warms the file cache; compare within a round.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

_TIMED = ("import time; {pre}t = time.perf_counter(); import {module}; "
          "print(time.perf_counter() - t)")
_BLOCK = (
    "import sys\n"
    "class _NoPyarrow:\n"
    "    def find_spec(self, name, path=None, target=None):\n"
    "        if name == 'pyarrow' or name.startswith('pyarrow.'):\n"
    "            raise ImportError(name)\n"
    "sys.meta_path.insert(0, _NoPyarrow())\n")
CASES = {
    "pandas": _TIMED.format(pre="", module="pandas"),
    "pandas, pyarrow kept out": _BLOCK + _TIMED.format(pre="", module="pandas"),
    "pyarrow alone": _TIMED.format(pre="", module="pyarrow"),
    "scipy.optimize after pandas": _TIMED.format(pre="import pandas; ", module="scipy.optimize"),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    times: dict[str, list[float]] = {name: [] for name in CASES}
    for _ in range(args.rounds):
        for name, code in CASES.items():
            out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                 check=True)
            times[name].append(float(out.stdout.strip()))
    for name, values in times.items():
        print(f"{name:30s} " + ", ".join(f"{v:.2f}" for v in sorted(values)) + " s")


if __name__ == "__main__":
    main()
