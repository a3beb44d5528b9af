"""Lines that tests add to the end of the pytest log, each under a section title, so a CI log
shows what they checked (the rclpy conformance runs, where tf2_msgs came from).

A test calls :func:`add`; ``tests/conftest.py`` prints the sections after the run. Under
pytest-xdist the tests run in worker processes: each worker hands its lines to the controller
as it ends (``workeroutput``), and the controller :func:`merge` s them before printing."""

from __future__ import annotations

__all__ = ["SECTIONS", "add", "merge"]

SECTIONS: dict[str, list[str]] = {}


def add(section: str, line: str) -> None:
    """Adds ``line`` under ``section`` (sections print in the order they were first used)."""
    SECTIONS.setdefault(section, []).append(line)


def merge(received: dict[str, list[str]]) -> None:
    """Adds a worker's sections to this process's. A line already here is not added again: a
    module's fixture runs in each worker that got some of its tests, and says the same."""
    for title, lines in received.items():
        known = SECTIONS.setdefault(title, [])
        known.extend(line for line in lines if line not in known)
