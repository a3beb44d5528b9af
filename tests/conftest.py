"""Shared fixtures: paths to the bundled scenarios and a short-run helper."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.report.browser import chromium_path

# Headless rendering for the camera tests (EGL: a GPU, or Mesa's llvmpipe on CPU). MuJoCo reads
# MUJOCO_GL when it is first imported, so this must run before anything imports it.
os.environ.setdefault("MUJOCO_GL", "egl")

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"


@pytest.fixture
def scenarios_dir() -> Path:
    return SCENARIOS


@pytest.fixture(scope="session")
def chromium() -> str:
    path = chromium_path()
    if path is None:
        pytest.skip("headless Chromium not installed (/usr/bin/chromium missing): "
                    "apt-get install -y chromium, or set SRR_CHROMIUM")
    return path
