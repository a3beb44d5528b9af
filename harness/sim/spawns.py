"""Robots must start in free space: checked on the built world, before the first step.

A robot whose spawn pose puts it into the floor, into something fixed in the scene (a shelf,
a wall, the trailer, a world file's static geometry) or into another robot is pushed out by
the contact solver in the first steps: it jumps, spins or flies off (one spawned a metre
below the floor rose 18 m), and every gate can still pass. So the contacts of the spawn state
(after ``mj_forward``) are read: a robot's geom deeper than :data:`SPAWN_DEPTH` into one of
those refuses the scenario, naming ``robots[i].spawn.position`` and what it is inside.
Contacts with bodies that move (pallets, workers) are the scene's business, not a bad spawn.

A fixed camera (``cameras:``) whose position lies inside a robot's geometry at its spawn pose
or inside fixed geometry (a shelf, a wall, the trailer, the floor, a world file's static
geometry) renders only the inside of it: its perception scores drop to nothing and no
message says why. :func:`camera_warnings` warns about it (a warning: a camera in a glass box
is conceivable). It tests the camera's point against every geom a camera renders (groups
below :data:`~harness.sim.robots.common.COLLISION_GROUP`, not transparent) of a robot or the
fixed scene, in the spawn state: exactly for MuJoCo's primitive shapes, and for a mesh by
casting rays (``mj_rayMesh``) both ways along each axis and counting the triangles each
crosses: from a point inside a closed mesh every ray crosses an odd number, from a point in a
hollow (a room of a building mesh) or outside an even number. All six must be odd (a ray
through an edge, counted twice, or a mesh that is not closed makes a point inside missed
rather than a point outside flagged). Contacts
cannot tell this (a camera is no geom), and adding a probe geom would change the model.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence

import mujoco
import numpy as np

from harness.errors import ScenarioError
from harness.scenario.schema import Scenario
from harness.sim.robots.common import COLLISION_GROUP

__all__ = ["SPAWN_DEPTH", "camera_warnings", "check_spawns", "fixed_cameras", "robot_spawn"]

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


_G = mujoco.mjtGeom
_AXES = np.vstack([np.eye(3), -np.eye(3)])
#: Metres a ray goes on past a mesh triangle it hit before it is cast again, and the most
#: triangles counted along one ray.
_STEP, _MAX_CROSSINGS = 1e-6, 1000


def _inside_geom(model: mujoco.MjModel, data: mujoco.MjData, geom: int,
                 point: np.ndarray) -> bool:
    """Whether ``point`` (world) lies strictly inside ``geom`` in ``data``'s state."""
    kind, size = int(model.geom_type[geom]), model.geom_size[geom]
    x, y, z = data.geom_xmat[geom].reshape(3, 3).T @ (point - data.geom_xpos[geom])
    if kind == _G.mjGEOM_SPHERE:
        return bool(x * x + y * y + z * z < size[0] ** 2)
    if kind == _G.mjGEOM_CAPSULE:
        dz = max(abs(z) - size[1], 0.0)
        return bool(x * x + y * y + dz * dz < size[0] ** 2)
    if kind == _G.mjGEOM_ELLIPSOID:
        return bool((x / size[0]) ** 2 + (y / size[1]) ** 2 + (z / size[2]) ** 2 < 1)
    if kind == _G.mjGEOM_CYLINDER:
        return bool(x * x + y * y < size[0] ** 2 and abs(z) < size[1])
    if kind == _G.mjGEOM_BOX:
        return bool(abs(x) < size[0] and abs(y) < size[1] and abs(z) < size[2])
    if kind == _G.mjGEOM_PLANE:  # below it, within its drawn extent (0: unbounded)
        return bool(z < 0 and (size[0] <= 0 or abs(x) < size[0])
                    and (size[1] <= 0 or abs(y) < size[1]))
    if kind == _G.mjGEOM_MESH:
        return all(_crossings(model, data, geom, point, axis) % 2 == 1 for axis in _AXES)
    return False  # a height field, an SDF: not tested


def _crossings(model: mujoco.MjModel, data: mujoco.MjData, geom: int, point: np.ndarray,
               axis: np.ndarray) -> int:
    """How many of mesh ``geom``'s triangles the ray from ``point`` along ``axis`` crosses
    (each hit, then on from just past it; at most :data:`_MAX_CROSSINGS`)."""
    start, n = point.astype(np.float64), 0
    while n < _MAX_CROSSINGS:
        d = mujoco.mj_rayMesh(model, data, geom, start, axis)
        if d < 0:
            break
        n += 1
        start = start + axis * (d + _STEP)
    return n


def camera_warnings(model: mujoco.MjModel, data: mujoco.MjData, owner: Mapping[int, str],
                    cameras: Sequence[tuple[str, str, tuple[float, ...]]],
                    describe: Callable[[str], str | None] | None = None) -> tuple[str, ...]:
    """One warning per fixed camera whose position is inside a robot at its spawn pose or
    inside fixed geometry (see the module docstring). ``cameras``: (file, field, position)
    of each enabled fixed camera; ``owner`` and ``describe`` as for :func:`check_spawns`;
    ``data`` in the spawn state (after ``mj_forward``)."""
    seen = [g for g in range(model.ngeom)
            if int(model.geom_group[g]) < COLLISION_GROUP and model.geom_rgba[g][3] > 0
            and (int(model.geom_bodyid[g]) in owner or _fixed(model, g))]
    out = []
    for file, field, pos in cameras:
        point = np.asarray(pos, dtype=np.float64)
        for g in seen:
            if not _inside_geom(model, data, g, point):
                continue
            robot = owner.get(int(model.geom_bodyid[g]))
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom {g}"
            if robot is not None:
                what = f"robot {robot} at its spawn pose (its geom {name!r})"
            elif int(model.geom_type[g]) == _PLANE:
                what = "the floor"
            else:
                what = (describe(name) if describe is not None else None) or _procedural(name)
            out.append(f"{file}: {field}: ({', '.join(f'{v:g}' for v in pos)}) is inside "
                       f"{what}: the camera sees only the inside of it; move the camera")
            break
    return tuple(out)


def fixed_cameras(scenario: Scenario,
                  source: str) -> tuple[tuple[str, str, tuple[float, ...]], ...]:
    """``cameras`` for :func:`camera_warnings` from a scenario: the file, the field and the
    position of every enabled fixed camera's ``spawn.position``."""
    return tuple((scenario.file_for(f"cameras[{i}].spawn.position", source),
                  f"cameras[{i}].spawn.position", tuple(float(v) for v in cam.spawn.position))
                 for i, cam in enumerate(scenario.cameras) if cam.enabled)


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
