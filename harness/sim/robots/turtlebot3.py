"""TurtleBot3 Waffle Pi (dimensions from its URDF), forward along +X.

Links are flat children of the robot prim, like Isaac Sim's URDF import::

    <prim>, <prim>/base_footprint      free joint, origin on the floor
    <prim>/base_link                   fixed, 0.010 m above base_footprint
    <prim>/wheel_left_link, <prim>/wheel_right_link     hinges wheel_left_joint/_right_joint
    <prim>/caster_back_left_link, <prim>/caster_back_right_link
    <prim>/imu_link, <prim>/base_scan, <prim>/camera_link

The wheel hinges turn about +Y, so a positive rate (rad/s) rolls the robot forward (+X). The
casters are frictionless spheres (higher contact priority than the floor).
"""

from __future__ import annotations

import types

import mujoco

from harness.errors import SimulationError
from harness.geometry import FloatArray
from harness.scenario.schema import BUILTIN_JOINTS, DiffDriveControl, RobotSpec
from harness.sim.prims import PrimKind, PrimTable
from harness.sim.robots.common import (
    BOX,
    CYLINDER,
    Q_CYLINDER_ALONG_Y,
    SPHERE,
    ActuatorMode,
    RobotBuild,
    add_collision_geom,
    add_visual_geom,
    set_inertial,
)

__all__ = ["BASE_LINK_HEIGHT", "ROBOT_FRONT", "add_turtlebot3"]

ROBOT_FRONT = (1.0, 0.0, 0.0)
BASE_LINK_HEIGHT = 0.010
_WHEEL_RADIUS = 0.033
_WHEEL_WIDTH = 0.018
_WHEEL_Y = 0.144
_WHEEL_Z = 0.023
_BOX_HALF = (0.281 / 2, 0.306 / 2, 0.141 / 2)
_BOX_CENTRE = (-0.064, 0.0, 0.047)
_FLOOR_CLEARANCE = 0.005
_BASE_MASS = 1.55
_WHEEL_MASS = 0.05
_LIDAR_MASS = 0.114
_CASTER_MASS = 0.005
_CASTER_RADIUS = 0.006
_WHEEL_KV = 0.2
_WHEEL_ARMATURE = 0.001
_WHEEL_TORQUE = 1.0

_RGBA_BODY = (0.25, 0.25, 0.28, 1.0)
_RGBA_PLATE = (0.55, 0.55, 0.58, 1.0)
_RGBA_TYRE = (0.05, 0.05, 0.05, 1.0)
_RGBA_LIDAR = (0.10, 0.10, 0.12, 1.0)
_RGBA_HIDDEN = (0.5, 0.5, 0.5, 0.3)


_FIXED_LINKS = {
    "caster_back_left_link": (-0.177, 0.064, -0.004),
    "caster_back_right_link": (-0.177, -0.064, -0.004),
    "imu_link": (-0.032, 0.0, 0.068),
    "base_scan": (-0.064, 0.0, 0.122),
    "camera_link": (0.073, -0.011, 0.084),
}


def add_turtlebot3(spec: mujoco.MjSpec, robot: RobotSpec, control: DiffDriveControl,
                   pos: tuple[float, float, float], quat: FloatArray,
                   prims: PrimTable) -> RobotBuild:
    """Add a TurtleBot3 Waffle Pi whose base_footprint (on the floor) is at ``pos``/``quat``."""
    n, prim = robot.name, robot.prim
    wheel_joints = BUILTIN_JOINTS["turtlebot3_waffle_pi"]
    unknown = [j for j in control.joint_names if j not in wheel_joints]
    if unknown:
        raise SimulationError(
            f"robots.{n}.control.joint_names: {unknown} are not joints of "
            f"turtlebot3_waffle_pi (it has {list(wheel_joints)})")

    footprint = spec.worldbody.add_body(name=f"{n}/base_footprint", pos=list(pos),
                                        quat=list(quat))
    footprint.add_freejoint(name=f"{n}/root")
    prims.declare(prim, PrimKind.BODY, f"{n}/base_footprint")
    prims.declare(f"{prim}/base_footprint", PrimKind.BODY, f"{n}/base_footprint")
    links: dict[str, tuple[str, str]] = {
        "base_footprint": (f"{prim}/base_footprint", f"{n}/base_footprint")}

    base = footprint.add_body(name=f"{n}/base_link", pos=[0, 0, BASE_LINK_HEIGHT])
    set_inertial(base, _BASE_MASS,
                 (_BASE_MASS / 3 * (_BOX_HALF[1] ** 2 + _BOX_HALF[2] ** 2),
                  _BASE_MASS / 3 * (_BOX_HALF[0] ** 2 + _BOX_HALF[2] ** 2),
                  _BASE_MASS / 3 * (_BOX_HALF[0] ** 2 + _BOX_HALF[1] ** 2)),
                 ipos=_BOX_CENTRE)
    # The URDF's collision box reaches 13.5 mm below the floor; ours keeps its footprint and
    # top but stops 5 mm above the floor, and the full box is drawn as a visual.
    bottom = -BASE_LINK_HEIGHT + _FLOOR_CLEARANCE
    top = _BOX_CENTRE[2] + _BOX_HALF[2]
    add_collision_geom(base, f"{n}/base_link/collision", BOX,
                       (_BOX_HALF[0], _BOX_HALF[1], (top - bottom) / 2),
                       (_BOX_CENTRE[0], 0.0, (top + bottom) / 2), _RGBA_HIDDEN)
    add_visual_geom(base, f"{n}/base_link/shell", BOX, _BOX_HALF, _BOX_CENTRE, _RGBA_BODY)
    for k, z in enumerate((0.045, 0.085)):
        add_visual_geom(base, f"{n}/base_link/plate_{k}", BOX,
                        (_BOX_HALF[0] + 0.002, _BOX_HALF[1] + 0.002, 0.002),
                        (_BOX_CENTRE[0], 0.0, z), _RGBA_PLATE)
    prims.declare(f"{prim}/base_link", PrimKind.BODY, f"{n}/base_link")
    links["base_link"] = (f"{prim}/base_link", f"{n}/base_link")

    joints: dict[str, str] = {}
    actuators: dict[str, tuple[str, ActuatorMode]] = {}
    for link, joint, y in (("wheel_left_link", "wheel_left_joint", _WHEEL_Y),
                           ("wheel_right_link", "wheel_right_joint", -_WHEEL_Y)):
        wheel = base.add_body(name=f"{n}/{link}", pos=[0.0, y, _WHEEL_Z])
        side = _WHEEL_MASS / 12 * (3 * _WHEEL_RADIUS**2 + _WHEEL_WIDTH**2)
        set_inertial(wheel, _WHEEL_MASS, (side, _WHEEL_MASS / 2 * _WHEEL_RADIUS**2, side))
        wheel.add_joint(name=f"{n}/{joint}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0],
                        armature=_WHEEL_ARMATURE)
        add_collision_geom(wheel, f"{n}/{link}/collision", SPHERE, (_WHEEL_RADIUS, 0, 0),
                           (0, 0, 0), _RGBA_HIDDEN)
        add_visual_geom(wheel, f"{n}/{link}/tyre", CYLINDER, (_WHEEL_RADIUS, _WHEEL_WIDTH / 2, 0),
                        (0, 0, 0), _RGBA_TYRE, quat=Q_CYLINDER_ALONG_Y)
        act = spec.add_actuator(name=f"{n}/{joint}", target=f"{n}/{joint}",
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_velocity(kv=_WHEEL_KV)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-_WHEEL_TORQUE, _WHEEL_TORQUE]
        joints[joint] = f"{n}/{joint}"
        actuators[joint] = (f"{n}/{joint}", ActuatorMode.VELOCITY)
        prims.declare(f"{prim}/{link}", PrimKind.BODY, f"{n}/{link}")
        links[link] = (f"{prim}/{link}", f"{n}/{link}")

    for link, offset in _FIXED_LINKS.items():
        body = base.add_body(name=f"{n}/{link}", pos=list(offset))
        if link.startswith("caster"):
            set_inertial(body, _CASTER_MASS, (1e-7, 1e-7, 1e-7))
            add_collision_geom(body, f"{n}/{link}/collision", SPHERE, (_CASTER_RADIUS, 0, 0),
                               (0, 0, 0), _RGBA_HIDDEN, priority=1, condim=1)
        elif link == "base_scan":
            set_inertial(body, _LIDAR_MASS, (5e-5, 5e-5, 7e-5))
            add_visual_geom(body, f"{n}/{link}/housing", CYLINDER, (0.035, 0.0165, 0),
                            (0.0, 0.0, -0.004), _RGBA_LIDAR)
        prims.declare(f"{prim}/{link}", PrimKind.BODY, f"{n}/{link}")
        links[link] = (f"{prim}/{link}", f"{n}/{link}")

    return RobotBuild(
        name=n, model="turtlebot3_waffle_pi", prim=prim, root_body=f"{n}/base_footprint",
        base_prim=f"{prim}/base_footprint", robot_front=ROBOT_FRONT,
        default_base_frame="base_footprint", joints=types.MappingProxyType(joints),
        actuators=types.MappingProxyType(actuators), links=types.MappingProxyType(links),
    )
