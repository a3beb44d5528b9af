"""Where things may stand in the procedural warehouse: a scene's robots, workers, cameras,
shelves and dock inside it, checked before the world is built.

The warehouse's floor is the walled room (``world.size``, centred on the origin) and, with
``world.dock.enabled``, the trailer backed up to it (:func:`~harness.sim.warehouse.
trailer_footprint`). A robot's spawn position, every waypoint of a robot's or a worker's
route and a fixed camera's position must lie on it, and no waypoint of a route may lie inside
a shelf's footprint (a robot would drive into the rack, a worker walk through it); a shelf's
footprint must lie in the room;
the trailer's open end must be in the room or on its wall (so that the trailer meets a wall
and gets a door).
The defaults of ``world.shelves`` and ``world.dock`` are laid out for the default 30 x 20 m
room, so a smaller ``world.size`` that keeps them is refused here, naming them.

A world from a file (``world.model``) grows the scene to hold its geometry, so with a file
only the warehouse's own shelves and dock are checked (``mode: extend``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from harness.errors import ScenarioError
from harness.scenario import Scenario, WorldSpec
from harness.sim.warehouse import WALL_THICKNESS, trailer_footprint

__all__ = ["check_layout"]

Point = tuple[float, float]
_EPS = 1e-6


def _in_room(world: WorldSpec, p: Sequence[float], grow: float = 0.0) -> bool:
    hx, hy = world.size[0] / 2 + grow + _EPS, world.size[1] / 2 + grow + _EPS
    return abs(p[0]) <= hx and abs(p[1]) <= hy


def _in_polygon(p: Sequence[float], poly: Sequence[Point]) -> bool:
    """Inside or on the edge of the convex polygon ``poly`` (counter-clockwise)."""
    for (x0, y0), (x1, y1) in zip(poly, [*poly[1:], poly[0]], strict=True):
        if (x1 - x0) * (p[1] - y0) - (y1 - y0) * (p[0] - x0) < -_EPS:
            return False
    return True


def _on_floor(world: WorldSpec, p: Sequence[float]) -> bool:
    if _in_room(world, p, WALL_THICKNESS):
        return True
    return world.dock.enabled and _in_polygon(p, trailer_footprint(world.dock))


def _room(world: WorldSpec) -> str:
    w, h = world.size
    return f"the {w:g} x {h:g} m room (world.size)"


def _where(world: WorldSpec) -> str:
    return f"outside {_room(world)}" + (" and the trailer" if world.dock.enabled else "")


def _shelf_corners(position: Point, size: Sequence[float], yaw_deg: float) -> list[Point]:
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    hl, hd = size[0] / 2, size[1] / 2
    return [(position[0] + c * x - s * y, position[1] + s * x + c * y)
            for x, y in ((-hl, -hd), (hl, -hd), (hl, hd), (-hl, hd))]


def _in_shelf(world: WorldSpec, p: Sequence[float]) -> str | None:
    """The first shelf (described, with its field) whose footprint holds ``p``, or None."""
    for i, shelf in enumerate(world.shelves):
        corners = _shelf_corners(shelf.position, shelf.size, shelf.yaw_deg)
        if _in_polygon(p, corners):
            return (f"inside the shelf at ({shelf.position[0]:g}, {shelf.position[1]:g}) "
                    f"(world.shelves[{i}])")
    return None


def check_layout(scenario: Scenario, source: str = "<scenario>") -> None:
    """Refuse (:class:`ScenarioError`, naming the file and the field) anything of the
    procedural warehouse's scene that lies outside it (see the module docstring)."""
    world = scenario.world
    if not world.procedural:
        return

    def fail(field: str, message: str) -> None:
        raise ScenarioError(scenario.file_for(field, source), field, message)

    default = WorldSpec()
    for i, shelf in enumerate(world.shelves):
        bad = [p for p in _shelf_corners(shelf.position, shelf.size, shelf.yaw_deg)
               if not _in_room(world, p)]
        if bad:
            what = ("a default shelf (laid out for the 30 x 20 m room): set world.shelves "
                    "for this room, or [] for none" if world.shelves == default.shelves
                    else "move it or make the room larger")
            fail(f"world.shelves[{i}]", f"the shelf at ({shelf.position[0]:g}, "
                 f"{shelf.position[1]:g}) reaches outside {_room(world)} at "
                 f"({bad[0][0]:.2f}, {bad[0][1]:.2f}); {what}")
    dock = world.dock
    if dock.enabled and not _in_room(world, dock.position, WALL_THICKNESS):
        what = ("the default dock (laid out for the 30 x 20 m room): set world.dock.position "
                "on this room's wall, or world.dock.enabled: false"
                if dock == default.dock else "put it on a wall of the room")
        fail("world.dock.position", f"the trailer's open end ({dock.position[0]:g}, "
             f"{dock.position[1]:g}) is outside {_room(world)}, so the trailer meets no wall; "
             f"{what}")
    if world.model is not None:
        return
    for i, robot in enumerate(scenario.robots):
        p = robot.spawn.position
        if robot.enabled and not _on_floor(world, p):
            fail(f"robots[{i}].spawn.position", f"({p[0]:g}, {p[1]:g}) is {_where(world)}")
    for i, worker in enumerate(scenario.workers):
        for j, (x, y) in enumerate(worker.route):
            if worker.enabled and not _on_floor(world, (x, y)):
                fail(f"workers[{i}].route[{j}]", f"({x:g}, {y:g}) is {_where(world)}")
            inside = _in_shelf(world, (x, y)) if worker.enabled else None
            if inside is not None:
                fail(f"workers[{i}].route[{j}]", f"({x:g}, {y:g}) is {inside}: the worker "
                     "would walk through the rack; move the waypoint to free floor")
    for name, route in scenario.routes.items():
        for j, (x, y) in enumerate(route.waypoints):
            if not _on_floor(world, (x, y)):
                fail(f"routes.{name}.waypoints[{j}]", f"({x:g}, {y:g}) is {_where(world)}")
            inside = _in_shelf(world, (x, y))
            if inside is not None:
                fail(f"routes.{name}.waypoints[{j}]", f"({x:g}, {y:g}) is {inside}: a robot "
                     "following the route would drive into the rack; move the waypoint to "
                     "free floor")
    for i, cam in enumerate(scenario.cameras):
        p = cam.spawn.position
        if cam.enabled and not _on_floor(world, p):
            fail(f"cameras[{i}].spawn.position", f"({p[0]:g}, {p[1]:g}) is {_where(world)}")
