"""Print what the rclpy conformance tests checked, so a CI log shows they did not check nothing."""

from __future__ import annotations

import pytest

from tests.conformance.summary import LINES


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    if LINES:
        terminalreporter.section("ROS 2 conformance (real rclpy)")
        for line in LINES:
            terminalreporter.write_line(line)
