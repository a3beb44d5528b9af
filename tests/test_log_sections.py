"""The sections tests add to the end of the log reach it from xdist workers too."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

PROBE = Path(__file__).with_name("log_sections_probe.py")
ROOT = PROBE.parents[1]


@pytest.mark.slow
@pytest.mark.parametrize(("workers", "expected"), [
    ([], ["the same line from every worker", "a line from the main process"]),
    # --dist each: the probe runs in both workers; the line they share is said once
    (["-n", "2", "--dist", "each"],
     ["the same line from every worker", "a line from gw0", "a line from gw1"]),
], ids=["one-process", "two-workers"])
def test_the_lines_tests_add_are_printed_after_the_run(workers: list[str],
                                                       expected: list[str]) -> None:
    # not what this test's own process was told if it runs in an xdist worker itself
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_XDIST")}
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           *workers, str(PROBE)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    lines = proc.stdout.splitlines()
    (title,) = [i for i, line in enumerate(lines) if "probe section" in line]
    assert lines[title].startswith("=")
    said = lines[title + 1:title + 1 + len(expected) + 1]
    assert sorted(said[:len(expected)]) == sorted(expected), said
    assert " passed in " in said[-1], said  # -q: the count follows, with no other line
