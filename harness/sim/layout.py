"""Where things may stand in the procedural warehouse: a scene's robots, workers, cameras,
shelves and dock inside it, checked before the world is built.

The warehouse's floor is the walled room (``world.size``, centred on the origin) and, with
``world.dock.enabled``, the trailer backed up to it (:func:`~harness.sim.warehouse.
trailer_footprint`). A robot's spawn position, every waypoint of a robot's or a worker's
route and a fixed camera's position must lie on it, and no waypoint of a route may lie inside
a shelf's footprint (a robot would drive into the rack, a worker walk through it); a shelf's
footprint must lie in the room;
the trailer's open end must be in the room or on its wall (so that the trailer meets a wall
and gets a door). A zone (``zones.loading_roi``, a polygon ``scoring.perception.area``) must
overlap the floor by some area: one wholly outside it holds no robot or worker, so the safety
score and every ``in_zone(...)`` spec over it hold without ever being tested. The trailer
tripwire counts by the side of the infinite line through ``a`` and ``b``
(:mod:`harness.metrics.safety`), so that line must cross the floor; where its segment lies
does not matter.
The defaults of ``world.shelves`` and ``world.dock`` are laid out for the default 30 x 20 m
room, so a smaller ``world.size`` that keeps them is refused here, naming them.

A world from a file (``world.model``) grows the scene to hold its geometry, so with a file
only the warehouse's own shelves and dock are checked (``mode: extend``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from harness.errors import ScenarioError
from harness.geometry import cross_2d, signed_area
from harness.scenario import Scenario, WorldSpec
from harness.sim.warehouse import WALL_THICKNESS, clip_half_plane, trailer_footprint

__all__ = ["check_layout"]

Point = tuple[float, float]
_EPS = 1e-6


def _in_room(world: WorldSpec, p: Sequence[float], grow: float = 0.0) -> bool:
    hx, hy = world.size[0] / 2 + grow + _EPS, world.size[1] / 2 + grow + _EPS
    return abs(p[0]) <= hx and abs(p[1]) <= hy


def _in_polygon(p: Sequence[float], poly: Sequence[Point]) -> bool:
    """Inside or on the edge of the convex polygon ``poly`` (counter-clockwise)."""
    return all(cross_2d(a, b, p) >= -_EPS
               for a, b in zip(poly, [*poly[1:], poly[0]], strict=True))


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


def _clip(poly: Sequence[Point], convex: Sequence[Point]) -> list[Point]:
    """The part of ``poly`` inside the convex polygon ``convex`` (counter-clockwise)."""
    out = list(poly)
    for (x0, y0), (x1, y1) in zip(convex, [*convex[1:], convex[0]], strict=True):
        n = (y1 - y0, x0 - x1)  # outward normal of a counter-clockwise edge
        out = clip_half_plane(out, n, n[0] * x0 + n[1] * y0) if out else out
    return out


def _area(poly: Sequence[Point]) -> float:
    return abs(signed_area(poly))


def _floors(world: WorldSpec) -> list[list[Point]]:
    """The floor as convex polygons (counter-clockwise): the room inside its walls and,
    with the dock, the trailer."""
    hx, hy = world.size[0] / 2, world.size[1] / 2
    out = [[(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]]
    if world.dock.enabled:
        out.append(trailer_footprint(world.dock))
    return out


def _extent(points: Sequence[Sequence[float]]) -> str:
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return f"x {min(xs):g}..{max(xs):g}, y {min(ys):g}..{max(ys):g}"


def _room_extent(world: WorldSpec) -> str:
    hx, hy = world.size[0] / 2, world.size[1] / 2
    dock = " and the trailer (world.dock)" if world.dock.enabled else ""
    return f"the {world.size[0]:g} x {world.size[1]:g} m room (world.size: x {-hx:g}..{hx:g}, " \
        f"y {-hy:g}..{hy:g}){dock}"


def _off_floor(world: WorldSpec, polygon: Sequence[Sequence[float]]) -> bool:
    """Whether ``polygon`` (three points or more) overlaps no floor by any area."""
    ring = [(float(x), float(y)) for x, y in polygon]
    return all(_area(_clip(ring, floor)) <= _EPS for floor in _floors(world))


def _line_misses_floor(world: WorldSpec, a: Sequence[float], b: Sequence[float]) -> bool:
    """Whether the infinite line through ``a`` and ``b`` leaves the whole floor (the room and
    the trailer together) on one side of it (touching a corner counts as one side). A line
    along the wall between the room and the trailer splits the floor: room on one side,
    trailer on the other."""
    sides = [cross_2d(a, b, p) for floor in _floors(world) for p in floor]
    return not (max(sides) > _EPS and min(sides) < -_EPS)


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
    zones = [("zones.loading_roi", scenario.zones.loading_roi,
              "no robot or worker can be in it, so the safety score and any in_zone spec "
              "over it are never tested")]
    perception = scenario.scoring.perception
    if perception is not None and perception.enabled:
        zones.append(("scoring.perception.area", perception.area,
                      "no worker or track can be in it, so perception scores nothing"))
    for field, polygon, why in zones:
        if len(polygon) >= 3 and _off_floor(world, polygon):
            fail(field, f"the polygon ({_extent(polygon)}) does not overlap the floor of "
                 f"{_room_extent(world)}: {why}; move it onto the floor")
    wire = scenario.zones.trailer_tripwire
    if wire is not None and wire.a != wire.b and _line_misses_floor(world, wire.a, wire.b):
        fail("zones.trailer_tripwire", f"the line through a {list(wire.a)} and b "
             f"{list(wire.b)} does not cross the floor of {_room_extent(world)}: every "
             "point of the floor is on one side of it, so the forklift is always or never "
             "inside the trailer; move it across the trailer's entrance")
