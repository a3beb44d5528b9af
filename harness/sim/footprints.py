"""Footprints of geoms: the 2-D outline a geom covers on the floor, for the report's map.

A footprint is the convex hull (:class:`scipy.spatial.ConvexHull`, Qhull) of the geom's shape
projected onto the world's XY plane, counter-clockwise, with the lowest and highest world Z
the shape reaches. Curved shapes are bounded by polygons that contain them, so the outline
never cuts into the geom:

* box: its eight corners (exact);
* sphere, capsule: disks of the radius around the projected centre (the two end centres of a
  capsule), each as a circumscribed ``SEGMENTS``-gon;
* cylinder: its two rim circles as circumscribed ``SEGMENTS``-gons, in 3-D, projected;
* mesh: every vertex of the mesh as compiled (scaled, in the geom's frame);
* ellipsoid, height field, SDF and anything else: the corners of MuJoCo's bounding box of
  the geom in its own frame (``geom_aabb``), a bound that contains the shape;
* plane: none (infinite; the caller skips ground planes).

A shape whose projection has no area (a flat mesh seen edge-on) gets its bounding rectangle
in XY, at least ``MIN_WIDTH`` wide. Pure functions of a compiled model and its data.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from harness.geometry import FloatArray, rotate_rows

__all__ = ["MIN_WIDTH", "SEGMENTS", "Footprint", "geom_footprint", "geom_points"]

SEGMENTS = 32
MIN_WIDTH = 0.01  # m: the narrowest footprint drawn (a degenerate outline is grown to it)

_G = mujoco.mjtGeom
# Unit circle as a circumscribed polygon: its edges touch the circle, so it contains it.
_RING = np.array([(math.cos(a), math.sin(a)) for a in
                  np.arange(SEGMENTS) * 2 * math.pi / SEGMENTS]) / math.cos(math.pi / SEGMENTS)
_CORNERS = np.array([(sx, sy, sz) for sx in (-1.0, 1.0) for sy in (-1.0, 1.0)
                     for sz in (-1.0, 1.0)])


@dataclass(frozen=True)
class Footprint:
    """The outline of ``name`` on the floor: a convex polygon in world XY (metres,
    counter-clockwise) and the lowest and highest world Z of the shape."""

    name: str
    points: tuple[tuple[float, float], ...]
    z_min: float
    z_max: float


def _disk(centre: FloatArray, radius: float) -> FloatArray:
    """Points (z = centre's) of a circumscribed polygon around a horizontal disk."""
    pts = np.empty((SEGMENTS, 3))
    pts[:, :2] = centre[:2] + radius * _RING
    pts[:, 2] = centre[2]
    return pts


def _up(dz: float) -> FloatArray:
    return np.array([0.0, 0.0, dz])


def geom_points(model: mujoco.MjModel, data: mujoco.MjData, geom: int) -> FloatArray | None:
    """World points whose XY hull contains the geom's projection and whose Z range is the
    geom's (see the module docstring); None for a plane."""
    kind = int(model.geom_type[geom])
    pos = np.asarray(data.geom_xpos[geom], dtype=np.float64)
    rot = np.asarray(data.geom_xmat[geom], dtype=np.float64).reshape(3, 3)
    size = model.geom_size[geom]
    local: FloatArray
    if kind == _G.mjGEOM_PLANE:
        return None
    if kind == _G.mjGEOM_SPHERE:
        r = float(size[0])
        return np.vstack([_disk(pos, r), pos + _up(-r), pos + _up(r)])
    if kind == _G.mjGEOM_CAPSULE:
        r, half = float(size[0]), float(size[1])
        ends = [pos + rot[:, 2] * half, pos - rot[:, 2] * half]
        return np.vstack([_disk(e, r) for e in ends]
                         + [e + _up(s * r) for e in ends for s in (-1.0, 1.0)])
    if kind == _G.mjGEOM_BOX:
        local = _CORNERS * size
    elif kind == _G.mjGEOM_CYLINDER:
        r, half = float(size[0]), float(size[1])
        rim = np.zeros((SEGMENTS, 3))
        rim[:, :2] = r * _RING
        local = np.vstack([rim + _up(-half), rim + _up(half)])
    elif kind == _G.mjGEOM_MESH and int(model.geom_dataid[geom]) >= 0:
        mesh = int(model.geom_dataid[geom])
        adr, num = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        local = np.asarray(model.mesh_vert[adr:adr + num], dtype=np.float64)
    else:
        aabb = np.asarray(model.geom_aabb[geom], dtype=np.float64)
        local = aabb[:3] + _CORNERS * aabb[3:]
    out: FloatArray = pos + rotate_rows(local, rot)
    return out


def _outline(xy: FloatArray) -> FloatArray:
    """Convex hull of 2-D points, counter-clockwise; a degenerate set: its bounding box."""
    # imported here: SciPy's spatial package takes long to import and only scenes with a
    # world file (sim.world_file) draw footprints
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(xy)
        return np.asarray(xy[hull.vertices], dtype=np.float64)
    except (QhullError, ValueError):
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        mid, half = (lo + hi) / 2, np.maximum((hi - lo) / 2, MIN_WIDTH / 2)
        box: FloatArray = mid + half * np.array([(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0),
                                                  (-1.0, 1.0)])
        return box


def geom_footprint(model: mujoco.MjModel, data: mujoco.MjData, geom: int,
                   name: str) -> Footprint | None:
    """The footprint of ``geom`` (poses as in ``data``), called ``name``; None for a plane."""
    pts = geom_points(model, data, geom)
    if pts is None:
        return None
    outline = _outline(pts[:, :2])
    return Footprint(name, tuple((float(x), float(y)) for x, y in outline),
                     float(pts[:, 2].min()), float(pts[:, 2].max()))
