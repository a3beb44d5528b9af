"""Fixtures of the report tests: one short failing run, shared, and a headless Chromium.

The run is the degraded-safety-monitor regression scenario cut to 13 s: the forklift starts
near the dock and the worker crosses the loading ROI early, so the run has a mute edge, an
unmute edge, under- and over-mute windows and camera frames, and it REGRESSES against a
baseline blessed from the nominal monitor on the same short scene (about 2 × 10 s of wall
time on 2 cores).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness import api

ROOT = Path(__file__).resolve().parents[2]
SLOW_REACTION = ROOT / "scenarios" / "regressions" / "dock_worker_crossing_slow_reaction.yaml"
NOMINAL = ROOT / "scenarios" / "dock_worker_crossing.yaml"
SHORT = ["robots.forklift.spawn.position=[7.0, 0.0, 0.0]",
         "routes.dock_approach.waypoints=[[7.0, 0.0], [15.0, 0.0], [21.0, 0.0]]",
         "workers.0.start_delay=7.0"]


@pytest.fixture(scope="session")
def failing_run(tmp_path_factory: pytest.TempPathFactory) -> api.RunResult:
    """The degraded monitor on the short scene, against a baseline of the nominal monitor on
    the same short scene (like for like: only the system under test differs)."""
    root = tmp_path_factory.mktemp("report")
    baselines = root / "baselines"
    nominal = api.load(NOMINAL, duration=13.0, overrides=SHORT)
    api.run_scenario(nominal, source=str(NOMINAL), out=root / "nominal_short",
                     baselines=baselines, update_baseline=True, update_reason="short scene",
                     allow_failing=True)  # 13 s: the forklift does not reach its goal
    sc = api.load(SLOW_REACTION, duration=13.0, overrides=SHORT)
    return api.run_scenario(sc, source=str(SLOW_REACTION), out=root / "slow_reaction_short",
                            baselines=baselines)


@pytest.fixture(scope="session")
def summary(failing_run: api.RunResult) -> dict:
    return json.loads((failing_run.run_dir / "summary.json").read_text())
