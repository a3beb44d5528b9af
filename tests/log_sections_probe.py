"""Run only by tests/test_log_sections.py, named on the command line (pytest collects a file
it is given even though the name does not start with ``test_``)."""

from __future__ import annotations

import os

from tests.log_sections import add


def test_adds_a_line() -> None:
    add("probe section", "the same line from every worker")
    add("probe section", f"a line from {os.environ.get('PYTEST_XDIST_WORKER', 'the main process')}")
