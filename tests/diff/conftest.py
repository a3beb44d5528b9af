"""Real runs for the diff tests, made once per session (a few seconds each on 2 cores).

* ``same_a`` / ``same_b``: forklift_warehouse, 2 s, the same seed: identical recordings.
* ``seed_7`` / ``seed_8``: the same scene with a walking worker whose speed varies with the
  seed (``variation``): only ``/gt/character_0/tf`` differs.
* ``short``: forklift_warehouse cut to 1.5 s: fewer messages on every topic.
* ``slower``: forklift_warehouse, 2 s, its route follower driving at 1.0 m/s instead of 1.5.
* ``scan_1`` / ``scan_2``: turtlebot3_room, 1 s, seeds 1 and 2: the lidar noise differs.
* ``dock_11`` / ``dock_12``: dock_worker_crossing cut to 6 s (forklift near the dock, the
  worker crossing early at a seed-dependent speed): cameras, perception, safety, both differ.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from harness import api

ROOT = Path(__file__).resolve().parents[2]
FORKLIFT = ROOT / "scenarios" / "forklift_warehouse.yaml"
TURTLEBOT = ROOT / "scenarios" / "turtlebot3_room.yaml"
DOCK = ROOT / "scenarios" / "dock_worker_crossing.yaml"
WORKER = "workers=[{route: [[0.0, 3.0], [6.0, 3.0]], speed: 1.0, variation: 0.3}]"
DOCK_SHORT = ["robots.forklift.spawn.position=[7.0, 0.0, 0.0]",
              "routes.dock_approach.waypoints=[[7.0, 0.0], [15.0, 0.0], [21.0, 0.0]]",
              "workers.0.start_delay=0.5", "workers.0.variation=0.3"]


class Runs:
    def __init__(self, root: Path) -> None:
        self.root = root
        self._made: dict[str, Path] = {}

    def get(self, name: str) -> Path:
        if name not in self._made:
            self._made[name] = self._make(name)
        return self._made[name]

    def _make(self, name: str) -> Path:
        specs = {
            "same_a": (FORKLIFT, 2.0, None, []),
            "same_b": (FORKLIFT, 2.0, None, []),
            "seed_7": (FORKLIFT, 2.0, 7, [WORKER]),
            "seed_8": (FORKLIFT, 2.0, 8, [WORKER]),
            "short": (FORKLIFT, 1.5, None, []),
            "slower": (FORKLIFT, 2.0, None,
                       ["systems_under_test.route_follower.params.speed=1.0"]),
            "scan_1": (TURTLEBOT, 1.0, 1, []),
            "scan_2": (TURTLEBOT, 1.0, 2, []),
            "dock_11": (DOCK, 6.0, 11, DOCK_SHORT),
            "dock_12": (DOCK, 6.0, 12, DOCK_SHORT),
        }
        path, duration, seed, overrides = specs[name]
        sc = api.load(path, duration=duration, seed=seed, overrides=overrides)
        return api.run_scenario(sc, source=str(path), out=self.root / name).run_dir


@pytest.fixture(scope="session")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Runs:
    return Runs(tmp_path_factory.mktemp("diff-runs"))
