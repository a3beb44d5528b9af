"""Robots start in free space: a spawn pose in the floor, in a shelf or a wall of the
procedural warehouse, or in another robot is refused by ``srr validate`` (and so by ``srr
run``, which makes the same checks) naming the robot's ``spawn.position``. Such a robot was
pushed out by the contact solver in the first steps (one spawned a metre below the floor rose
18 m) while every gate passed."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main
from tests.conftest import SCENARIOS

TURTLEBOT = SCENARIOS / "turtlebot3_urdf.yaml"
TWO = SCENARIOS / "two_forklifts.yaml"
WAREHOUSE = SCENARIOS / "forklift_warehouse.yaml"  # the 30 x 20 m room, default shelves


@pytest.mark.parametrize(("scenario", "overrides", "said"), [
    (TURTLEBOT, ["robots.0.spawn.position=[0,0,-1]"],
     "robots[0].spawn.position: robot turtlebot3 at (0, 0, -1) starts 1.000 m into the floor"),
    (WAREHOUSE, ["robots.0.spawn.position=[-6,-6,0]"],
     "robots[0].spawn.position: robot forklift at (-6, -6, 0) starts inside shelf 2 "
     "(world.shelves[2])"),
    (WAREHOUSE, ["robots.0.spawn.position=[-14.95,0,0]"],
     "robots[0].spawn.position: robot forklift at (-14.95, 0, 0) starts inside the west "
     "wall"),
    (TWO, ["robots.1.spawn.position=null"], None),  # filled in below from robot 0's
])
def test_a_robot_that_starts_inside_something_is_refused(
        scenario: Path, overrides: list[str], said: str | None,
        capsys: pytest.CaptureFixture[str]) -> None:
    if said is None:  # the second forklift where the first one stands
        from harness import api

        first = api.load(TWO).robots[0]
        x, y, z = first.spawn.position
        overrides = [f"robots.1.spawn.position=[{x},{y},{z}]",
                     f"robots.1.spawn.rpy_deg={list(first.spawn.rpy_deg)}"]
        said = (f"robots[1].spawn.position: robot {api.load(TWO).robots[1].name} at "
                f"({x:g}, {y:g}, {z:g}) starts inside robot {first.name}")
    code = main(["validate", str(scenario), *[a for o in overrides for a in ("--set", o)]])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err.startswith(f"srr validate: --set: {said}"), err
    assert len(err.splitlines()) == 1


def test_every_bundled_robot_starts_in_free_space(capsys: pytest.CaptureFixture[str]) -> None:
    # wheels resting on the floor touch it at 0 m: the bundled scenes pass as they are
    for scenario in (TURTLEBOT, TWO, WAREHOUSE, SCENARIOS / "dock_worker_crossing.yaml"):
        assert main(["validate", str(scenario)]) == 0, capsys.readouterr().err


def test_a_built_in_model_spawned_with_a_height_is_warned_about(
        capsys: pytest.CaptureFixture[str]) -> None:
    # it stands on the floor whatever z says: the value was silently unused
    assert main(["validate", str(WAREHOUSE), "--set",
                 "robots.forklift.spawn.position=[-12,-3,-1.0]"]) == 0
    err = capsys.readouterr().err
    assert ("warning: --set: robots[0].spawn.position: z -1 is not used: the built-in model "
            "'forklift' stands on the floor") in err
