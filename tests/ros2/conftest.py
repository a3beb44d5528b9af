"""Say in the CI log whether tf2_msgs was built for this session or found in the cache."""

from __future__ import annotations

import pytest

LINES: list[str] = []


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    if LINES:
        terminalreporter.section("tf2_msgs for the ROS 2 wheels")
        for line in LINES:
            terminalreporter.write_line(line)
