"""The static warehouse: floor, perimeter walls with a dock door, shelving racks, the trailer,
the lights and a sky.

Every static geom is in geom group 0 and collides with robots (the trailer's floor slab is the
one exception: it is a visual plate a few millimetres thick, the physical floor under it is the
ground plane, so vehicles roll in without a step). Prims declared here::

    /World/Warehouse                 body at the origin holding floor, walls and racks
    /World/Warehouse/Floor           the ground plane (geom)
    /World/Warehouse/Shelf_<i>       one body per rack, at its centre on the floor, yawed
    /World/Warehouse/Dock            body at the trailer's open end, +X into the trailer
    /World/Warehouse/Dock/Trailer    the trailer body (same frame as the dock)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from harness.geometry import quat_wxyz_from_yaw
from harness.scenario.schema import DockSpec, ShelfSpec, WorldSpec
from harness.sim.prims import PrimKind, PrimTable

__all__ = [
    "DOOR_HEADROOM",
    "FLOOR_MARGIN",
    "TRAILER_WALL",
    "WALL_THICKNESS",
    "add_ground",
    "add_sky",
    "add_sun",
    "add_warehouse",
    "clip_half_plane",
    "door_gaps",
    "floor_half_extent",
    "set_headlight",
    "trailer_footprint",
]

WALL_THICKNESS = 0.2
TRAILER_WALL = 0.05
DOOR_HEADROOM = 0.3  # door opening height above the trailer's roof line
_DOOR_MARGIN = 0.15  # clearance each side of the trailer in the door opening
FLOOR_MARGIN = 2.0  # ground plane beyond the walls (and a file world's geometry)

_BOX = mujoco.mjtGeom.mjGEOM_BOX
_STATIC_GROUP = 0

_RGBA_WALL = (0.82, 0.80, 0.74, 1.0)
_RGBA_LINTEL = (0.62, 0.60, 0.55, 1.0)
_RGBA_UPRIGHT = (0.10, 0.25, 0.65, 1.0)
_RGBA_BOARD = (0.95, 0.50, 0.10, 1.0)
_RGBA_TRAILER_WALL = (0.88, 0.90, 0.93, 1.0)
_RGBA_TRAILER_ROOF = (0.55, 0.57, 0.60, 1.0)
_RGBA_TRAILER_FRONT = (0.70, 0.15, 0.15, 1.0)
_RGBA_TRAILER_FLOOR = (0.40, 0.28, 0.18, 1.0)

Point = tuple[float, float]


@dataclass(frozen=True)
class _Wall:
    """A straight wall: centre line from ``a`` along unit ``u`` for ``length`` metres."""

    name: str
    a: Point
    u: Point
    length: float


def trailer_footprint(dock: DockSpec, margin: float = 0.0) -> list[Point]:
    """Outer corners (world XY) of the trailer, grown by ``margin`` on every side."""
    c, s = math.cos(math.radians(dock.yaw_deg)), math.sin(math.radians(dock.yaw_deg))
    half_w = dock.width / 2 + TRAILER_WALL + margin
    x0, x1 = -margin, dock.length + TRAILER_WALL + margin
    px, py = dock.position
    return [(px + c * x - s * y, py + s * x + c * y)
            for x, y in ((x0, -half_w), (x1, -half_w), (x1, half_w), (x0, half_w))]


def floor_half_extent(world: WorldSpec) -> tuple[float, float]:
    """Half-sizes of the ground plane: the walled area and the trailer plus a margin."""
    hx = world.size[0] / 2 + WALL_THICKNESS
    hy = world.size[1] / 2 + WALL_THICKNESS
    if world.dock.enabled:
        for x, y in trailer_footprint(world.dock):
            hx, hy = max(hx, abs(x)), max(hy, abs(y))
    return hx + FLOOR_MARGIN, hy + FLOOR_MARGIN


def _walls(world: WorldSpec) -> list[_Wall]:
    hx, hy, t = world.size[0] / 2, world.size[1] / 2, WALL_THICKNESS
    return [
        _Wall("east", (hx + t / 2, -hy - t), (0.0, 1.0), world.size[1] + 2 * t),
        _Wall("west", (-hx - t / 2, -hy - t), (0.0, 1.0), world.size[1] + 2 * t),
        _Wall("north", (-hx, hy + t / 2), (1.0, 0.0), world.size[0]),
        _Wall("south", (-hx, -hy - t / 2), (1.0, 0.0), world.size[0]),
    ]


def clip_half_plane(poly: Sequence[Point], n: Point, offset: float) -> list[Point]:
    """Keep the part of ``poly`` where ``n · p <= offset`` (Sutherland-Hodgman: exact for a
    convex ``poly``; for a concave one the kept part's area is still right, though pieces
    it cuts apart stay joined by zero-width edges)."""
    out: list[Point] = []
    for i, p in enumerate(poly):
        q = poly[(i + 1) % len(poly)]
        dp = n[0] * p[0] + n[1] * p[1] - offset
        dq = n[0] * q[0] + n[1] * q[1] - offset
        if dp <= 0:
            out.append(p)
        if (dp < 0 < dq) or (dq < 0 < dp):
            f = dp / (dp - dq)
            out.append((p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])))
    return out


def _gap_on(wall: _Wall, footprint: list[Point]) -> tuple[float, float] | None:
    """Interval along ``wall`` (metres from its start) that the trailer footprint crosses."""
    n = (-wall.u[1], wall.u[0])
    centre = n[0] * wall.a[0] + n[1] * wall.a[1]
    band = WALL_THICKNESS / 2
    poly = clip_half_plane(footprint, n, centre + band)
    poly = clip_half_plane(poly, (-n[0], -n[1]), -(centre - band))
    if len(poly) < 3:
        return None
    along = [wall.u[0] * (x - wall.a[0]) + wall.u[1] * (y - wall.a[1]) for x, y in poly]
    lo, hi = max(0.0, min(along)), min(wall.length, max(along))
    return (lo, hi) if hi > lo else None


def door_gaps(world: WorldSpec) -> dict[str, tuple[float, float]]:
    """For each wall the trailer passes through, the door interval along that wall."""
    if not world.dock.enabled:
        return {}
    footprint = trailer_footprint(world.dock, margin=_DOOR_MARGIN)
    gaps: dict[str, tuple[float, float]] = {}
    for wall in _walls(world):
        gap = _gap_on(wall, footprint)
        if gap is not None:
            gaps[wall.name] = gap
    return gaps


def _box(body: mujoco.MjsBody, name: str, pos: Sequence[float], half: Sequence[float],
         rgba: Sequence[float], *, collide: bool = True, yaw: float = 0.0) -> mujoco.MjsGeom:
    return body.add_geom(
        name=name, type=_BOX, pos=[float(v) for v in pos], size=[float(v) for v in half],
        quat=list(quat_wxyz_from_yaw(yaw)), rgba=list(rgba), group=_STATIC_GROUP,
        contype=1 if collide else 0, conaffinity=1 if collide else 0,
    )


def add_ground(spec: mujoco.MjSpec, body: mujoco.MjsBody, half: tuple[float, float],
               prefix: str) -> str:
    """A checkered ground plane of ``half`` extents (x, y) on ``body``, its texture, material
    and geom named ``<prefix>floor...``; returns the geom's name."""
    spec.add_texture(
        name=f"{prefix}floor_checker", type=mujoco.mjtTexture.mjTEXTURE_2D,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, width=512, height=512,
        rgb1=[0.62, 0.62, 0.60], rgb2=[0.42, 0.43, 0.46],
        mark=mujoco.mjtMark.mjMARK_EDGE, markrgb=[0.25, 0.25, 0.25],
    )
    material = spec.add_material(name=f"{prefix}floor", texrepeat=[0.5, 0.5], texuniform=True,
                                 reflectance=0.05)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = f"{prefix}floor_checker"
    body.add_geom(name=f"{prefix}floor", type=mujoco.mjtGeom.mjGEOM_PLANE,
                  size=[half[0], half[1], 1.0], material=f"{prefix}floor", group=_STATIC_GROUP,
                  contype=1, conaffinity=1)
    return f"{prefix}floor"


def _add_floor(spec: mujoco.MjSpec, body: mujoco.MjsBody, world: WorldSpec,
               prims: PrimTable) -> None:
    name = add_ground(spec, body, floor_half_extent(world), "warehouse/")
    prims.declare("/World/Warehouse/Floor", PrimKind.GEOM, name)


def _add_walls(body: mujoco.MjsBody, world: WorldSpec) -> None:
    h = world.wall_height
    door_top = min(h, world.dock.height + DOOR_HEADROOM)
    gaps = door_gaps(world)
    for wall in _walls(world):
        gap = gaps.get(wall.name)
        pieces = [(0.0, wall.length)] if gap is None else [(0.0, gap[0]), (gap[1], wall.length)]
        yaw = math.atan2(wall.u[1], wall.u[0])
        for k, (s0, s1) in enumerate(pieces):
            if s1 - s0 < 1e-3:
                continue
            mid = (s0 + s1) / 2
            pos = (wall.a[0] + wall.u[0] * mid, wall.a[1] + wall.u[1] * mid, h / 2)
            _box(body, f"warehouse/wall_{wall.name}_{k}", pos,
                 ((s1 - s0) / 2, WALL_THICKNESS / 2, h / 2), _RGBA_WALL, yaw=yaw)
        if gap is not None and h - door_top > 0.05:
            mid = (gap[0] + gap[1]) / 2
            pos = (wall.a[0] + wall.u[0] * mid, wall.a[1] + wall.u[1] * mid, (h + door_top) / 2)
            _box(body, f"warehouse/wall_{wall.name}_lintel", pos,
                 ((gap[1] - gap[0]) / 2, WALL_THICKNESS / 2, (h - door_top) / 2),
                 _RGBA_LINTEL, yaw=yaw)


def _add_shelf(parent: mujoco.MjsBody, index: int, shelf: ShelfSpec, prims: PrimTable) -> None:
    """A rack: uprights at most ~2.7 m apart front and back, plus boards every ~0.8 m."""
    name = f"warehouse/shelf_{index}"
    body = parent.add_body(name=name, pos=[shelf.position[0], shelf.position[1], 0.0],
                           quat=list(quat_wxyz_from_yaw(math.radians(shelf.yaw_deg))))
    prims.declare(f"/World/Warehouse/Shelf_{index}", PrimKind.BODY, name)
    length, depth, height = shelf.size
    post = min(0.08, length / 4, depth / 4)
    bays = max(1, math.ceil(length / 2.7))
    xs = np.linspace(-length / 2 + post / 2, length / 2 - post / 2, bays + 1)
    for i, x in enumerate(xs):
        for j, y in enumerate((-depth / 2 + post / 2, depth / 2 - post / 2)):
            _box(body, f"{name}/upright_{i}_{j}", (float(x), y, height / 2),
                 (post / 2, post / 2, height / 2), _RGBA_UPRIGHT)
    levels = max(2, int(height // 0.8) + 1)
    board = min(0.04, height / 20)
    for k, z in enumerate(np.linspace(0.15, height - board / 2, levels)):
        _box(body, f"{name}/board_{k}", (0.0, 0.0, float(z)),
             (length / 2, depth / 2, board / 2), _RGBA_BOARD)


def _add_trailer(parent: mujoco.MjsBody, dock: DockSpec, prims: PrimTable) -> None:
    """Trailer with its open end at ``dock.position``; local +X runs into it."""
    dock_body = parent.add_body(name="warehouse/dock", pos=[dock.position[0], dock.position[1], 0],
                                quat=list(quat_wxyz_from_yaw(math.radians(dock.yaw_deg))))
    prims.declare("/World/Warehouse/Dock", PrimKind.BODY, "warehouse/dock")
    body = dock_body.add_body(name="warehouse/trailer")
    prims.declare("/World/Warehouse/Dock/Trailer", PrimKind.BODY, "warehouse/trailer")
    length, half_w, height, t = dock.length, dock.width / 2, dock.height, TRAILER_WALL
    _box(body, "warehouse/trailer/floor", (length / 2, 0.0, 0.004), (length / 2, half_w, 0.004),
         _RGBA_TRAILER_FLOOR, collide=False)
    for side, sign in (("left", 1.0), ("right", -1.0)):
        _box(body, f"warehouse/trailer/wall_{side}",
             (length / 2, sign * (half_w + t / 2), height / 2),
             (length / 2, t / 2, height / 2), _RGBA_TRAILER_WALL)
    _box(body, "warehouse/trailer/front", (length + t / 2, 0.0, height / 2),
         (t / 2, half_w + t, height / 2), _RGBA_TRAILER_FRONT)
    _box(body, "warehouse/trailer/roof", ((length + t) / 2, 0.0, height + t / 2),
         ((length + t) / 2, half_w + t, t / 2), _RGBA_TRAILER_ROOF)
    body.add_light(name="warehouse/trailer/light", type=mujoco.mjtLightType.mjLIGHT_SPOT,
                   pos=[length / 2, 0.0, height - 0.1], dir=[0.0, 0.0, -1.0], cutoff=80.0,
                   exponent=1.0, diffuse=[0.5, 0.5, 0.5], specular=[0.1, 0.1, 0.1],
                   castshadow=False)


def add_sky(spec: mujoco.MjSpec, prefix: str) -> None:
    """A gradient sky box, texture ``<prefix>sky``."""
    spec.add_texture(name=f"{prefix}sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, width=256, height=256,
                     rgb1=[0.55, 0.65, 0.80], rgb2=[0.15, 0.17, 0.22])


def set_headlight(spec: mujoco.MjSpec) -> None:
    """The viewer's headlight, dimmed so the scene's own lights shape it."""
    spec.visual.headlight.ambient = [0.25, 0.25, 0.25]
    spec.visual.headlight.diffuse = [0.35, 0.35, 0.35]
    spec.visual.headlight.specular = [0.05, 0.05, 0.05]


def add_sun(spec: mujoco.MjSpec, top: float, prefix: str) -> None:
    """A shadow-casting directional light ``<prefix>sun`` 10 m above ``top``."""
    spec.worldbody.add_light(
        name=f"{prefix}sun", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
        pos=[0.0, 0.0, top + 10.0], dir=[0.3, 0.2, -1.0], diffuse=[0.45, 0.45, 0.42],
        specular=[0.1, 0.1, 0.1], castshadow=True)


def _add_lights(spec: mujoco.MjSpec, world: WorldSpec) -> None:
    add_sky(spec, "warehouse/")
    set_headlight(spec)
    top = world.wall_height
    add_sun(spec, top, "warehouse/")
    qx, qy = world.size[0] / 4, world.size[1] / 4
    for i, (x, y) in enumerate(((qx, qy), (-qx, qy), (-qx, -qy), (qx, -qy))):
        spec.worldbody.add_light(
            name=f"warehouse/spot_{i}", type=mujoco.mjtLightType.mjLIGHT_SPOT,
            pos=[x, y, top - 0.1], dir=[0.0, 0.0, -1.0], cutoff=75.0, exponent=2.0,
            diffuse=[0.3, 0.3, 0.3], specular=[0.05, 0.05, 0.05], castshadow=False)


def add_warehouse(spec: mujoco.MjSpec, world: WorldSpec, prims: PrimTable) -> None:
    """Add the whole static scene described by ``world`` to ``spec``."""
    body = spec.worldbody.add_body(name="warehouse")
    prims.declare("/World/Warehouse", PrimKind.BODY, "warehouse")
    _add_floor(spec, body, world, prims)
    _add_walls(body, world)
    for i, shelf in enumerate(world.shelves):
        _add_shelf(body, i, shelf, prims)
    if world.dock.enabled:
        _add_trailer(body, world.dock, prims)
    _add_lights(spec, world)
