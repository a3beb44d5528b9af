"""What a robot builder hands back to the world, and helpers shared by the builders.

MuJoCo names must be unique model-wide, so every body, joint, geom, site and actuator of a
robot is named ``<robot name>/<plain name>``. The public API speaks plain joint names scoped by
the robot's prim; :class:`RobotBuild` carries the plain → MuJoCo mapping.

Geom groups: static world 0, robot geoms that cameras and lidars see 1, hidden robot collision
shapes (sphere wheels, stabilisers) 3.
"""

from __future__ import annotations

import enum
import math
import types
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import mujoco

__all__ = [
    "BOX",
    "COLLISION_GROUP",
    "CYLINDER",
    "Q_CYLINDER_ALONG_Y",
    "SPHERE",
    "VISUAL_GROUP",
    "ActuatorMode",
    "RobotBuild",
    "add_collision_geom",
    "add_visual_geom",
    "set_inertial",
]

VISUAL_GROUP = 1
COLLISION_GROUP = 3

BOX = mujoco.mjtGeom.mjGEOM_BOX
CYLINDER = mujoco.mjtGeom.mjGEOM_CYLINDER
SPHERE = mujoco.mjtGeom.mjGEOM_SPHERE
# Turns a cylinder's axis (its local z) onto the body's y axis: the axle of a wheel.
Q_CYLINDER_ALONG_Y = (math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0)

Vec3 = tuple[float, float, float]


class ActuatorMode(enum.Enum):
    """Which entry of an articulation command an actuator takes."""

    POSITION = "position"
    VELOCITY = "velocity"


@dataclass(frozen=True)
class RobotBuild:
    """A robot added to a spec (MuJoCo names; ids are resolved after compilation).

    ``joints``: plain joint name → MuJoCo joint name (hinge and slide joints, model order).
    ``actuators``: plain joint name → (MuJoCo actuator name, mode).
    ``links``: link name → (prim path, MuJoCo body name); sensors mount on links.
    ``assets``: files the robot's meshes and textures are read from, by the names the spec
    uses (robots from model files; the world's spec compiles from memory).
    ``file_digest``: for a robot from a model file, the SHA-256 of the file and of every
    mesh and texture it uses, so a changed model makes a run another configuration.
    ``warnings``: ``file: field: message`` lines about the robot's model that do not stop
    the run (``srr validate`` prints them; a run's summary keeps them).
    """

    name: str
    model: str
    prim: str
    root_body: str
    base_prim: str
    robot_front: Vec3
    default_base_frame: str
    joints: Mapping[str, str]
    actuators: Mapping[str, tuple[str, ActuatorMode]]
    links: Mapping[str, tuple[str, str]]
    assets: Mapping[str, bytes] = field(default_factory=lambda: types.MappingProxyType({}))
    file_digest: str | None = None
    warnings: tuple[str, ...] = ()


def add_visual_geom(body: mujoco.MjsBody, name: str, gtype: mujoco.mjtGeom,
                    size: Sequence[float], pos: Sequence[float], rgba: Sequence[float],
                    quat: Sequence[float] = (1.0, 0.0, 0.0, 0.0)) -> mujoco.MjsGeom:
    """A geom that is seen (cameras, lidar) but never collides and has no mass."""
    return body.add_geom(name=name, type=gtype, size=list(size), pos=list(pos), quat=list(quat),
                         rgba=list(rgba), contype=0, conaffinity=0, group=VISUAL_GROUP,
                         density=0.0, mass=0.0)


def add_collision_geom(body: mujoco.MjsBody, name: str, gtype: mujoco.mjtGeom,
                       size: Sequence[float], pos: Sequence[float], rgba: Sequence[float], *,
                       group: int = COLLISION_GROUP, friction: Sequence[float] | None = None,
                       priority: int = 0, condim: int = 3,
                       quat: Sequence[float] = (1.0, 0.0, 0.0, 0.0)) -> mujoco.MjsGeom:
    """A geom that collides with the world and other robots (mass comes from body inertials)."""
    geom = body.add_geom(name=name, type=gtype, size=list(size), pos=list(pos), quat=list(quat),
                         rgba=list(rgba), contype=1, conaffinity=1, group=group,
                         priority=priority, condim=condim, density=0.0, mass=0.0)
    if friction is not None:
        geom.friction = list(friction)
    return geom


def set_inertial(body: mujoco.MjsBody, mass: float, inertia: Sequence[float],
                 ipos: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
    """Explicit mass, principal inertia (body axes) and centre of mass of ``body``.

    ``ipos`` must always be set: an unset spec ``ipos`` is not the body origin.
    """
    body.explicitinertial = True
    body.mass = float(mass)
    body.inertia = [float(v) for v in inertia]
    body.ipos = [float(v) for v in ipos]
    body.iquat = [1.0, 0.0, 0.0, 0.0]
