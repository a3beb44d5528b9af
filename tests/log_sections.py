"""Lines that tests add to the end of the pytest log, each under a section title, so a CI log
shows what they checked (the rclpy conformance runs, where tf2_msgs came from).

A test calls :func:`add`; ``tests/conftest.py`` prints the sections after the run. Under
pytest-xdist the tests run in worker processes: each worker hands its lines to the controller
as it ends (``workeroutput``), and the controller prints them all."""

from __future__ import annotations

__all__ = ["SECTIONS", "add"]

SECTIONS: dict[str, list[str]] = {}


def add(section: str, line: str) -> None:
    """Adds ``line`` under ``section`` (sections print in the order they were first used)."""
    SECTIONS.setdefault(section, []).append(line)
