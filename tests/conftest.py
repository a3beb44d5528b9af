"""Shared fixtures: paths to the bundled scenarios and a short-run helper."""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import settings

from tests.log_sections import SECTIONS, merge
from tests.report.browser import chromium_path

# Headless rendering for the camera tests (EGL: a GPU, or Mesa's llvmpipe on CPU). MuJoCo reads
# MUJOCO_GL when it is first imported, so this must run before anything imports it.
os.environ.setdefault("MUJOCO_GL", "egl")

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"


@pytest.fixture
def scenarios_dir() -> Path:
    return SCENARIOS


ModuleTmp = Callable[[str], Path]


@pytest.fixture(scope="module")
def module_tmp(request: pytest.FixtureRequest,
               tmp_path_factory: pytest.TempPathFactory) -> Iterator[ModuleTmp]:
    """``tmp_path_factory.mktemp`` for a module's fixtures, whose folders are removed when the
    module ends unless one of its tests failed (as ``tmp_path_retention_policy = "failed"``
    does for a test's own ``tmp_path``): a module's runs are not left on the disk for the rest
    of the session."""
    made: list[Path] = []
    failed_before = request.session.testsfailed

    def make(name: str) -> Path:
        made.append(tmp_path_factory.mktemp(name))
        return made[-1]

    yield make
    if request.session.testsfailed == failed_before:
        for path in made:
            shutil.rmtree(path, ignore_errors=True)


@pytest.fixture(scope="session")
def chromium() -> str:
    path = chromium_path()
    if path is None:
        pytest.skip("headless Chromium not installed (/usr/bin/chromium missing): "
                    "apt-get install -y chromium, or set SRR_CHROMIUM")
    return path


# Hypothesis profiles: "ci" (the default) is derandomized, so a CI run is reproducible, and
# small enough for the fast tier; "nightly" (HYPOTHESIS_PROFILE=nightly, the nightly workflow)
# draws many more, new examples every night. Tests that set max_examples themselves keep it.
settings.register_profile("ci", derandomize=True, database=None, deadline=None,
                          max_examples=20, print_blob=True)
settings.register_profile("nightly", max_examples=1000, deadline=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


# The sections of tests/log_sections.py: from xdist workers to the controller, then printed.
_WORKER_KEY = "srr_log_sections"


def pytest_sessionfinish(session: pytest.Session) -> None:
    output = getattr(session.config, "workeroutput", None)  # set in an xdist worker only
    if output is not None:
        output[_WORKER_KEY] = {title: list(lines) for title, lines in SECTIONS.items()}


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node: Any, error: object) -> None:
    merge(getattr(node, "workeroutput", {}).get(_WORKER_KEY, {}))


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    for title, lines in SECTIONS.items():
        terminalreporter.section(title)
        for line in lines:
            terminalreporter.write_line(line)
