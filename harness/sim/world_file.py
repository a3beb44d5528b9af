"""A world from a model file (``world.model: {mjcf: ...}`` / ``{urdf: ...}``) in the scene.

How it enters the world: the file is read as a robot's model file is
(:func:`~harness.sim.robots.model_file.read_model_file`: MuJoCo's own parser, ``package://``
and relative asset paths, assets in memory) and the whole of its world body — static geoms,
bodies, lights, cameras, sites — is attached (``MjSpec.attach``) to a frame at
``world.model.pose``, every MuJoCo name prefixed ``world-file/`` (a prefix no robot name can
make, so names never clash). Its materials, textures, meshes and default classes come along;
its options, size, visual and statistic blocks and its keyframes do not (the scenario's
physics apply).

* ``mode: replace``: the file is the whole world. srr adds a ground plane (the warehouse's
  checkered floor, sized to the file's geometry plus a margin) when the file has no plane
  geom, a sun when it has no light, and its sky when it has no sky box.
* ``mode: extend``: the procedural warehouse as the scenario describes it, plus the file's
  contents except its plane geoms (the warehouse has a floor).
* Bodies with joints are simulated as passive objects (robots can push them; gravity acts);
  they are not static, so the map does not draw them. A file with actuators is refused:
  nothing in a scenario would command them.
* URDF: links joined by fixed joints are bodies welded to the world (static). Visual geoms
  go to the static world's group 0, collision geoms to the hidden group 3 when the file has
  visual geoms. An MJCF file's groups are its own (0-2 seen by cameras and lidars).

Prims: ``<world.model.prim>/<body>`` (default ``/World/Environment/<body>``) for each named
body, ``<prim>/<body>/<geom>`` for a named geom of a body and ``<prim>/<geom>`` for a named
geom of the file's world body, when the name can be a prim (letters, digits, ``_ . -``) and
the path is free (a body wins over a geom).

Map: every static geom of the file (its body welded to the world) that robots can meet — its
lowest point below ``MAP_BAND[1]`` and its highest above ``MAP_BAND[0]``, seen (group 0-2) or
colliding — has a :class:`~harness.sim.footprints.Footprint` (a URDF link's visual and
collision shapes, the same outline at the same heights, have one), computed from the file
compiled on its own at its pose before the world is built (the same geometry the world then
has).

Errors are :class:`~harness.errors.ScenarioError` naming the scenario file, the field
(``world.model.mjcf``) and the world file.
"""

from __future__ import annotations

import re
import types
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from harness.scenario.schema import WorldModel
from harness.sim.footprints import Footprint, geom_footprint, geom_points
from harness.sim.mjquat import quat_wxyz_from_rpy_deg_mj
from harness.sim.prims import PrimKind, PrimTable
from harness.sim.robots.common import COLLISION_GROUP
from harness.sim.robots.model_file import ModelFileError, one_line, read_model_file
from harness.sim.robots.paths import ModelPathError, ModelSource, PackagePath, resolve_uri

__all__ = ["MAP_BAND", "PREFIX", "LoadedWorld", "add_world_file",
           "load_world_file", "map_json"]

PREFIX = "world-file/"
#: Heights (m, world Z) a static geom must reach into to be drawn on the map: above a floor
#: slab, below ceilings and lamps.
MAP_BAND = (0.01, 2.5)
_STATIC_GROUP = 0
_NAME_RE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]*$")
_PLANE = mujoco.mjtGeom.mjGEOM_PLANE


@dataclass(frozen=True)
class LoadedWorld:
    """A world file read, checked and measured, ready to attach once (:func:`add_world_file`).

    ``geoms``: every geom's MuJoCo name in the scene (prefixed; unnamed geoms get a name) →
    how the map and errors call it (its name in the file, or ``<body>#<k>``). ``static``: the
    static ones. ``footprints``: the static geoms' outlines on the map (world XY).
    ``bounds``: (x min, x max, y min, y max, z max) of all its geoms but planes, world frame,
    or None when it has none."""

    model: WorldModel
    path: Path
    spec: mujoco.MjSpec
    assets: Mapping[str, bytes]
    geoms: Mapping[str, str]
    static: frozenset[str]
    footprints: tuple[Footprint, ...]
    bounds: tuple[float, float, float, float, float] | None
    has_floor: bool
    has_light: bool
    has_sky: bool

    @property
    def shown(self) -> str:
        return str(self.path)

    def describe_static(self, geom: str) -> str | None:
        """How an error calls the scene's geom ``geom`` when it is one of this file's static
        ones (``'pillar' of worlds/hall.xml``), else None."""
        return f"{self.geoms.get(geom, geom)!r} of {self.shown}" if geom in self.static else None


def _style_urdf(spec: mujoco.MjSpec) -> None:
    """URDF visual geoms into the static world's group; collision geoms hidden beside them."""
    geoms = list(spec.geoms)
    has_visual = any(g.contype == 0 and g.conaffinity == 0 for g in geoms)
    for g in geoms:
        collides = g.contype != 0 or g.conaffinity != 0
        g.group = _STATIC_GROUP if not collides or not has_visual else COLLISION_GROUP


def _name_geoms(spec: mujoco.MjSpec) -> dict[str, str]:
    """Give unnamed geoms a name (``srr_geom_<k>``); file name → label for the map."""
    taken = {g.name for g in spec.geoms if g.name}
    labels: dict[str, str] = {}
    counts: dict[str, int] = {}
    for k, g in enumerate(spec.geoms):
        if g.name:
            labels[g.name] = g.name
            continue
        name = f"srr_geom_{k}"
        while name in taken:
            name += "_"
        taken.add(name)
        g.name = name
        owner = g.parent.name if g.parent is not None and g.parent.name else "world"
        counts[owner] = counts.get(owner, 0) + 1
        labels[name] = f"{owner}#{counts[owner]}"
    return labels


def _pose(model: WorldModel) -> tuple[list[float], list[float]]:
    return ([float(v) for v in model.pose.position],
            [float(q) for q in quat_wxyz_from_rpy_deg_mj(model.pose.rpy_deg)])


def _measure(spec: mujoco.MjSpec, assets: Mapping[str, bytes], model: WorldModel,
             labels: Mapping[str, str], src: ModelSource, shown: str,
             ) -> tuple[frozenset[str], tuple[Footprint, ...],
                        tuple[float, float, float, float, float] | None]:
    """Compile a copy of the file alone at its pose: static geoms, footprints, bounds."""
    wrapper = mujoco.MjSpec()
    pos, quat = _pose(model)
    wrapper.attach(spec.copy(), prefix=PREFIX, frame=wrapper.worldbody.add_frame(pos=pos,
                                                                                  quat=quat))
    wrapper.assets = dict(assets)
    try:
        compiled = wrapper.compile()
    except ValueError as err:
        raise src.error(f"model.{model.kind}", f"{shown}: MuJoCo cannot build it: "
                        f"{one_line(err)}") from err
    data = mujoco.MjData(compiled)
    mujoco.mj_kinematics(compiled, data)
    static: set[str] = set()
    footprints: list[Footprint] = []
    seen_shapes: set[tuple[tuple[tuple[float, float], ...], float, float]] = set()
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for g in range(compiled.ngeom):
        name = mujoco.mj_id2name(compiled, mujoco.mjtObj.mjOBJ_GEOM, g) or ""
        plain = name.removeprefix(PREFIX)
        pts = geom_points(compiled, data, g)
        if pts is not None:
            lo, hi = np.minimum(lo, pts.min(axis=0)), np.maximum(hi, pts.max(axis=0))
        if int(compiled.body_weldid[compiled.geom_bodyid[g]]) != 0:
            continue
        static.add(name)
        seen = int(compiled.geom_group[g]) < COLLISION_GROUP  # 3 and up: hidden
        collides = bool(compiled.geom_contype[g] or compiled.geom_conaffinity[g])
        if pts is None or not (seen or collides):
            continue
        fp = geom_footprint(compiled, data, g, labels.get(plain, plain))
        if fp is None or fp.z_max <= MAP_BAND[0] or fp.z_min >= MAP_BAND[1]:
            continue
        key = (tuple((round(x, 4), round(y, 4)) for x, y in fp.points),
               round(fp.z_min, 4), round(fp.z_max, 4))
        if key not in seen_shapes:  # a URDF link's visual and collision shapes: one
            seen_shapes.add(key)
            footprints.append(fp)
    bounds = None if not np.isfinite(lo).all() else (
        float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]), float(hi[2]))
    return frozenset(static), tuple(footprints), bounds


def load_world_file(model: WorldModel, src: ModelSource) -> LoadedWorld:
    """Read ``model``'s file, check it, and measure it at its pose (see the module)."""
    field = f"model.{model.kind}"
    packages = PackagePath.of(src.base_dir, model.package_paths, src.environ)
    try:
        path = resolve_uri(model.path, src.base_dir, packages)
    except ModelPathError as err:
        raise src.error(field, str(err)) from err
    shown = str(path)
    try:
        parsed = read_model_file(path, model.kind, packages)
    except ModelFileError as err:
        raise src.error(field, f"{shown}: {err}") from err
    spec = parsed.spec
    actuators = [a.name or f"#{i}" for i, a in enumerate(spec.actuators)]
    if actuators:
        raise src.error(field, f"{shown} has actuators ({', '.join(actuators[:4])}): nothing "
                        "in a scenario commands a world's joints; remove them, or make the "
                        "moving part a robot")
    for key in list(spec.keys):
        spec.delete(key)
    if model.kind == "urdf":
        _style_urdf(spec)
    if model.mode == "extend":
        for g in [g for g in spec.geoms if g.type == _PLANE]:
            spec.delete(g)
    has_floor = any(g.type == _PLANE for g in spec.geoms)
    has_light = bool(list(spec.lights))
    has_sky = any(t.type == mujoco.mjtTexture.mjTEXTURE_SKYBOX for t in spec.textures)
    labels = _name_geoms(spec)
    static, footprints, bounds = _measure(spec, parsed.assets, model, labels, src, shown)
    geoms = {f"{PREFIX}{name}": label for name, label in labels.items()}
    return LoadedWorld(model=model, path=path, spec=spec, assets=parsed.assets,
                       geoms=types.MappingProxyType(geoms), static=static,
                       footprints=footprints, bounds=bounds, has_floor=has_floor,
                       has_light=has_light, has_sky=has_sky)


def add_world_file(spec: mujoco.MjSpec, loaded: LoadedWorld, prims: PrimTable) -> None:
    """Attach ``loaded``'s world body to ``spec`` at its pose and declare its prims. Once per
    :class:`LoadedWorld` (MuJoCo attaches a spec by reference)."""
    pos, quat = _pose(loaded.model)
    root = loaded.model.prim.rstrip("/")
    bodies = [b.name for b in loaded.spec.bodies if b.name and b.name != "world"]
    named = [(g.parent.name if g.parent is not None else "", g.name) for g in loaded.spec.geoms
             if loaded.geoms.get(PREFIX + g.name) == g.name]  # named in the file
    spec.attach(loaded.spec, prefix=PREFIX,
                frame=spec.worldbody.add_frame(pos=pos, quat=quat))
    for body in bodies:
        if _NAME_RE.match(body):
            prims.declare(f"{root}/{body}", PrimKind.BODY, PREFIX + body)
    for owner, geom in named:
        if not _NAME_RE.match(geom):
            continue
        in_body = owner and owner != "world" and _NAME_RE.match(owner)
        path = f"{root}/{owner}/{geom}" if in_body else f"{root}/{geom}"
        if path not in prims:
            prims.declare(path, PrimKind.GEOM, PREFIX + geom)


def map_json(loaded: LoadedWorld) -> dict[str, Any]:
    """What ``summary.json`` keeps of the world file for the report's map (``world_map``):
    the file, the mode and each footprint's name, outline and Z range (metres, 0.1 mm)."""
    return {
        "file": loaded.shown,
        "mode": loaded.model.mode,
        "footprints": [{"name": fp.name,
                        "points": [[round(x, 4), round(y, 4)] for x, y in fp.points],
                        "z": [round(fp.z_min, 4), round(fp.z_max, 4)]}
                       for fp in loaded.footprints],
    }
