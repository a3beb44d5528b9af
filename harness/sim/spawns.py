"""Robots must start in free space: checked on the built world, before the first step.

A robot whose spawn pose puts it into the floor, into something fixed in the scene (a shelf,
a wall, the trailer, a world file's static geometry) or into another robot is pushed out by
the contact solver in the first steps: it jumps, spins or flies off (one spawned a metre
below the floor rose 18 m), and every gate can still pass. So the contacts of the spawn state
(after ``mj_forward``) are read: a robot's geom deeper than :data:`SPAWN_DEPTH` into one of
those refuses the scenario, naming ``robots[i].spawn.position`` and what it is inside.
Contacts with bodies that move (pallets, workers) are the scene's business, not a bad spawn.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping

import mujoco

from harness.errors import ScenarioError
from harness.scenario.schema import Scenario

__all__ = ["SPAWN_DEPTH", "check_spawns", "robot_spawn"]

#: Metres: a robot's geom deeper than this into the floor, a fixed geom or another robot at
#: its spawn pose is refused. Wheels resting on the floor touch it at 0.
SPAWN_DEPTH = 0.01

_PLANE = int(mujoco.mjtGeom.mjGEOM_PLANE)
_SHELF = re.compile(r"^warehouse/shelf_(\d+)/")
_WALL = re.compile(r"^warehouse/wall_([a-z]+)_")


def check_spawns(model: mujoco.MjModel, data: mujoco.MjData, owner: Mapping[int, str],
                 robot_field: Callable[[str], tuple[str, str, tuple[float, ...]]],
                 describe: Callable[[str], str | None] | None = None) -> None:
    """Refuse the robot that starts deepest inside the floor, a fixed geom or another robot
    (:class:`ScenarioError`). ``owner``: body id → robot name for every robot's bodies, in
    the scenario's order of robots;
    ``robot_field(name)``: (file, field, spawn position) to name in the error;
    ``describe(geom name)``: what to call a fixed geom (None: by its name)."""
    order = {name: i for i, name in enumerate(dict.fromkeys(owner.values()))}
    deepest: dict[tuple[str, int | str], float] = {}
    for c in data.contact[:data.ncon]:
        if c.dist >= -SPAWN_DEPTH:
            continue
        g1, g2 = int(c.geom1), int(c.geom2)
        r1, r2 = owner.get(int(model.geom_bodyid[g1])), owner.get(int(model.geom_bodyid[g2]))
        if r1 is not None and r2 is not None:
            if r1 != r2:  # the later robot of the pair (in the scenario) is the one to move
                first, later = sorted((r1, r2), key=order.__getitem__)
                key: tuple[str, int | str] = (later, first)
                deepest[key] = min(deepest.get(key, 0.0), float(c.dist))
            continue
        for mine, geom in ((r1, g2), (r2, g1)):
            if mine is not None and _fixed(model, geom):
                key = (mine, geom)
                deepest[key] = min(deepest.get(key, 0.0), float(c.dist))
    if not deepest:
        return
    (robot, other), dist = min(deepest.items(), key=lambda kv: kv[1])
    file, field, pos = robot_field(robot)
    where = f"robot {robot} at ({pos[0]:g}, {pos[1]:g}, {pos[2]:g})"
    if isinstance(other, str):
        what = f"starts inside robot {other} ({-dist:.3f} m deep): move one of them"
    elif int(model.geom_type[other]) == _PLANE:
        what = (f"starts {-dist:.3f} m into the floor: raise spawn.position's z, or give the "
                "model a root link at floor height (base_footprint)")
    else:
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, other) or f"geom {other}"
        shown = (describe(name) if describe is not None else None) or _procedural(name)
        what = f"starts inside {shown} ({-dist:.3f} m deep): move it to free floor"
    raise ScenarioError(file, field, f"{where} {what}")


def _fixed(model: mujoco.MjModel, geom: int) -> bool:
    """Whether ``geom`` is part of the fixed scene: its body is welded to the world and no
    mocap body (a worker) moves it."""
    body = int(model.geom_bodyid[geom])
    return int(model.body_weldid[body]) == 0 and int(model.body_mocapid[body]) < 0


def _procedural(name: str) -> str:
    """What to call a geom of the procedural warehouse in an error."""
    shelf = _SHELF.match(name)
    if shelf is not None:
        return f"shelf {shelf.group(1)} (world.shelves[{shelf.group(1)}])"
    wall = _WALL.match(name)
    if wall is not None:
        return f"the {wall.group(1)} wall"
    if name.startswith("warehouse/trailer/"):
        return "the trailer (world.dock)"
    return repr(name)


def robot_spawn(scenario: Scenario,
                source: str) -> Callable[[str], tuple[str, str, tuple[float, ...]]]:
    """``robot_field`` for :func:`check_spawns` from a scenario: the file and field of the
    named robot's ``spawn.position`` and the position."""
    def field(robot: str) -> tuple[str, str, tuple[float, ...]]:
        i = scenario.robot_index(robot)
        where = f"robots[{i}].spawn.position"
        return (scenario.file_for(where, source), where,
                tuple(float(v) for v in scenario.robots[i].spawn.position))
    return field
