"""A counterbalance forklift with a rear swivel drive wheel, forward along its body -X.

Kinematics (``control`` block): the two passive front wheels sit on the axle at body
``x = -wheelbase/2``, the swivel wheel at ``x = +wheelbase/2``, so the front axle → rear wheel
distance is ``wheelbase``. The swivel hinge axis is body -Z and the drive hinge axis is the
swivel's +Y. With the seed's swivel-drive IK (``reverse_logic`` flips on) a positive
``cmd_vel.linear.x`` gives a negative drive rate and the forklift moves along body -X; a
positive ``angular.z`` gives a positive swivel command, which turns the rear wheel so that the
forklift yaws counter-clockwise seen from above.

Wheels collide as spheres (clean rolling, and a swivel that can turn in place); visible
cylinders are drawn over them. Two frictionless stabiliser spheres under the rear corners sit
2 cm above the floor and only touch it if the chassis rolls, like the rear axle stops of a real
forklift. Prims::

    <prim>, <prim>/body                         chassis (free joint), origin on the floor
                                                midway between the axles
    <prim>/front_left_wheel, .../front_right_wheel, .../back_wheel_swivel, .../back_wheel
    safety_indicator.indicator_prim or <prim>/body/body/safety_indicator   the indicator disk
"""

from __future__ import annotations

import math
import types

import mujoco

from harness.errors import SimulationError
from harness.geometry import FloatArray
from harness.scenario.schema import BUILTIN_JOINTS, ForkliftControl, RobotSpec
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

__all__ = [
    "CHASSIS_MASS",
    "FRONT_LEFT_JOINT",
    "FRONT_RIGHT_JOINT",
    "INDICATOR_RGBA",
    "ROBOT_FRONT",
    "add_forklift",
    "indicator_prim",
]

ROBOT_FRONT = (-1.0, 0.0, 0.0)
INDICATOR_RGBA = (1.0, 0.3, 0.0, 1.0)
CHASSIS_MASS = 1400.0
_WHEEL_MASS = 30.0
_SWIVEL_MASS = 15.0
_CHASSIS_LENGTH = 2.2
_CHASSIS_WIDTH = 1.1
_TRACK = 0.9
_WHEEL_WIDTH = 0.14
_CLEARANCE = 0.1
_FRAME_TOP = 1.1
_GUARD_TOP = 2.1

# Drives: stiff enough to hold the steering angle within a few degrees while rolling, and a
# drive torque that gives ~1.5 m/s^2 at full load; armature keeps them stable at 240 Hz.
_SWIVEL_KP = 5000.0
_SWIVEL_ARMATURE = 2.0
_SWIVEL_FORCE = 3000.0
_DRIVE_KV = 1500.0
_DRIVE_ARMATURE = 5.0
_DRIVE_ACCEL = 1.5  # m/s^2 the drive torque limit allows for the whole vehicle
_FRONT_WHEEL_DAMPING = 0.5

_RGBA_BODY = (1.0, 0.75, 0.05, 1.0)
_RGBA_DARK = (0.15, 0.15, 0.17, 1.0)
_RGBA_MAST = (0.35, 0.36, 0.38, 1.0)
_RGBA_FORK = (0.20, 0.20, 0.22, 1.0)
_RGBA_TYRE = (0.05, 0.05, 0.05, 1.0)
_RGBA_HIDDEN = (0.5, 0.5, 0.5, 0.3)


FRONT_LEFT_JOINT, FRONT_RIGHT_JOINT = BUILTIN_JOINTS["forklift"]


def indicator_prim(robot: RobotSpec) -> str:
    """Prim path of the safety indicator disk (the seed's default unless configured)."""
    return robot.safety_indicator.indicator_prim or f"{robot.prim}/body/body/safety_indicator"


def _box_inertia(mass: float, lx: float, ly: float, lz: float) -> list[float]:
    return [mass / 12 * (ly**2 + lz**2), mass / 12 * (lx**2 + lz**2), mass / 12 * (lx**2 + ly**2)]


def _wheel_inertia(mass: float, radius: float, width: float) -> list[float]:
    side = mass / 12 * (3 * radius**2 + width**2)
    return [side, mass / 2 * radius**2, side]


def _add_wheel_shapes(body: mujoco.MjsBody, name: str, radius: float) -> None:
    add_collision_geom(body, f"{name}/collision", SPHERE, [radius, 0, 0], [0, 0, 0], _RGBA_HIDDEN)
    add_visual_geom(body, f"{name}/tyre", CYLINDER, [radius, _WHEEL_WIDTH / 2, 0], [0, 0, 0],
                    _RGBA_TYRE, quat=Q_CYLINDER_ALONG_Y)
    add_visual_geom(body, f"{name}/hub", CYLINDER, [radius * 0.5, _WHEEL_WIDTH / 2 + 0.005, 0],
                    [0, 0, 0], _RGBA_MAST, quat=Q_CYLINDER_ALONG_Y)


def _add_chassis_shapes(body: mujoco.MjsBody, n: str, length: float, robot: RobotSpec,
                        prims: PrimTable) -> None:
    half_l, half_w = length / 2, _CHASSIS_WIDTH / 2
    frame_h = _FRAME_TOP - _CLEARANCE
    add_collision_geom(body, f"{n}/chassis", BOX, [half_l, half_w, frame_h / 2],
                       [0, 0, _CLEARANCE + frame_h / 2], _RGBA_BODY, group=1)
    add_visual_geom(body, f"{n}/counterweight", BOX, [0.2, half_w + 0.01, 0.4],
                    [half_l - 0.18, 0, 0.75], _RGBA_DARK)
    add_visual_geom(body, f"{n}/seat", BOX, [0.25, 0.25, 0.08], [0.25, 0, _FRAME_TOP + 0.08],
                    _RGBA_DARK)
    # Overhead guard: four posts and a roof.
    post_h = (_GUARD_TOP - _FRAME_TOP) / 2
    for i, x in enumerate((-half_l + 0.45, 0.55)):
        for j, y in enumerate((-half_w + 0.05, half_w - 0.05)):
            add_visual_geom(body, f"{n}/guard_post_{i}_{j}", BOX, [0.03, 0.03, post_h],
                            [x, y, _FRAME_TOP + post_h], _RGBA_DARK)
    add_visual_geom(body, f"{n}/guard_roof", BOX, [0.55, half_w, 0.03],
                    [(-half_l + 0.45 + 0.55) / 2, 0, _GUARD_TOP + 0.03], _RGBA_DARK)
    # Mast, carriage and forks ahead of the front (-X) end.
    mast_x = -half_l - 0.06
    for j, y in enumerate((-0.35, 0.35)):
        add_visual_geom(body, f"{n}/mast_{j}", BOX, [0.05, 0.04, 1.1], [mast_x, y, 1.15],
                        _RGBA_MAST)
    add_visual_geom(body, f"{n}/mast_cross", BOX, [0.05, 0.39, 0.04], [mast_x, 0, 2.2],
                    _RGBA_MAST)
    add_visual_geom(body, f"{n}/carriage", BOX, [0.03, 0.45, 0.25], [mast_x - 0.09, 0, 0.35],
                    _RGBA_FORK)
    for j, y in enumerate((-0.3, 0.3)):
        add_visual_geom(body, f"{n}/fork_{j}", BOX, [0.55, 0.05, 0.02],
                        [mast_x - 0.12 - 0.55, y, 0.07], _RGBA_FORK)
    # Safety indicator: a thin disk on the guard roof, seen from overhead cameras.
    add_visual_geom(body, f"{n}/safety_indicator", CYLINDER, [0.18, 0.015, 0],
                    [(-half_l + 0.45 + 0.55) / 2, 0, _GUARD_TOP + 0.075], INDICATOR_RGBA)
    prims.declare(indicator_prim(robot), PrimKind.GEOM, f"{n}/safety_indicator")


def add_forklift(spec: mujoco.MjSpec, robot: RobotSpec, control: ForkliftControl,
                 pos: tuple[float, float, float], quat: FloatArray,
                 prims: PrimTable) -> RobotBuild:
    """Add a forklift whose chassis origin (on the floor) is at ``pos`` with ``quat``."""
    n, prim = robot.name, robot.prim
    radius, wheelbase = control.wheel_radius, control.wheelbase
    max_steer = math.radians(control.max_steer_deg)
    plain_joints = [FRONT_LEFT_JOINT, FRONT_RIGHT_JOINT, control.swivel_joint, control.drive_joint]
    if len(set(plain_joints)) != len(plain_joints):
        raise SimulationError(
            f"robots.{n}.control: joint names {plain_joints} must be distinct")
    length = max(_CHASSIS_LENGTH, wheelbase + 2 * radius + 0.3)

    chassis = spec.worldbody.add_body(name=f"{n}/body", pos=list(pos), quat=list(quat))
    chassis.add_freejoint(name=f"{n}/root")
    set_inertial(chassis, CHASSIS_MASS, _box_inertia(CHASSIS_MASS, length, _CHASSIS_WIDTH, 1.0),
                 ipos=(0.05, 0.0, 0.45))
    prims.declare(prim, PrimKind.BODY, f"{n}/body")
    prims.declare(f"{prim}/body", PrimKind.BODY, f"{n}/body")
    _add_chassis_shapes(chassis, n, length, robot, prims)
    for j, y in enumerate((-(_TRACK / 2 - 0.03), _TRACK / 2 - 0.03)):
        add_collision_geom(chassis, f"{n}/stabiliser_{j}", SPHERE, [0.05, 0, 0],
                           [wheelbase / 2, y, 0.07], _RGBA_HIDDEN, priority=1, condim=1)

    links: dict[str, tuple[str, str]] = {
        "body": (f"{prim}/body", f"{n}/body"),
        "base_link": (f"{prim}/body", f"{n}/body"),
    }
    joints: dict[str, str] = {}
    for link, joint, y in (("front_left_wheel", FRONT_LEFT_JOINT, _TRACK / 2),
                           ("front_right_wheel", FRONT_RIGHT_JOINT, -_TRACK / 2)):
        wheel = chassis.add_body(name=f"{n}/{link}", pos=[-wheelbase / 2, y, radius])
        set_inertial(wheel, _WHEEL_MASS, _wheel_inertia(_WHEEL_MASS, radius, _WHEEL_WIDTH))
        wheel.add_joint(name=f"{n}/{joint}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0],
                        damping=_FRONT_WHEEL_DAMPING)
        _add_wheel_shapes(wheel, f"{n}/{link}", radius)
        joints[joint] = f"{n}/{joint}"
        links[link] = (f"{prim}/{link}", f"{n}/{link}")
        prims.declare(f"{prim}/{link}", PrimKind.BODY, f"{n}/{link}")

    swivel = chassis.add_body(name=f"{n}/back_wheel_swivel", pos=[wheelbase / 2, 0, radius])
    set_inertial(swivel, _SWIVEL_MASS, (0.3, 0.3, 0.3))
    swivel.add_joint(name=f"{n}/{control.swivel_joint}", type=mujoco.mjtJoint.mjJNT_HINGE,
                     axis=[0, 0, -1], armature=_SWIVEL_ARMATURE,
                     limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                     range=[-max_steer - math.radians(3), max_steer + math.radians(3)])
    for j, y in enumerate((-_WHEEL_WIDTH / 2 - 0.03, _WHEEL_WIDTH / 2 + 0.03)):
        add_visual_geom(swivel, f"{n}/back_wheel_fork_{j}", BOX, [0.05, 0.015, radius * 0.6],
                        [0, y, radius * 0.5], _RGBA_MAST)
    prims.declare(f"{prim}/back_wheel_swivel", PrimKind.BODY, f"{n}/back_wheel_swivel")
    links["back_wheel_swivel"] = (f"{prim}/back_wheel_swivel", f"{n}/back_wheel_swivel")

    drive = swivel.add_body(name=f"{n}/back_wheel")
    set_inertial(drive, _WHEEL_MASS, _wheel_inertia(_WHEEL_MASS, radius, _WHEEL_WIDTH))
    drive.add_joint(name=f"{n}/{control.drive_joint}", type=mujoco.mjtJoint.mjJNT_HINGE,
                    axis=[0, 1, 0], armature=_DRIVE_ARMATURE)
    _add_wheel_shapes(drive, f"{n}/back_wheel", radius)
    prims.declare(f"{prim}/back_wheel", PrimKind.BODY, f"{n}/back_wheel")
    links["back_wheel"] = (f"{prim}/back_wheel", f"{n}/back_wheel")
    joints[control.swivel_joint] = f"{n}/{control.swivel_joint}"
    joints[control.drive_joint] = f"{n}/{control.drive_joint}"
    spec.add_exclude(name=f"{n}/exclude_chassis_back_wheel", bodyname1=f"{n}/body",
                     bodyname2=f"{n}/back_wheel")

    total_mass = CHASSIS_MASS + 3 * _WHEEL_MASS + _SWIVEL_MASS
    inertia_swivel = _SWIVEL_ARMATURE + 0.3 + _WHEEL_MASS * radius**2 / 2
    steer = spec.add_actuator(name=f"{n}/{control.swivel_joint}",
                              target=f"{n}/{control.swivel_joint}",
                              trntype=mujoco.mjtTrn.mjTRN_JOINT)
    steer.set_to_position(kp=_SWIVEL_KP, kv=2.0 * math.sqrt(_SWIVEL_KP * inertia_swivel))
    steer.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    steer.ctrlrange = [-max_steer, max_steer]
    steer.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    steer.forcerange = [-_SWIVEL_FORCE, _SWIVEL_FORCE]
    torque = _DRIVE_ACCEL * total_mass * radius
    motor = spec.add_actuator(name=f"{n}/{control.drive_joint}",
                              target=f"{n}/{control.drive_joint}",
                              trntype=mujoco.mjtTrn.mjTRN_JOINT)
    motor.set_to_velocity(kv=_DRIVE_KV)
    motor.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    motor.forcerange = [-torque, torque]

    return RobotBuild(
        name=n, model="forklift", prim=prim, root_body=f"{n}/body", base_prim=f"{prim}/body",
        robot_front=ROBOT_FRONT, default_base_frame="base_link",
        joints=types.MappingProxyType(joints),
        actuators=types.MappingProxyType({
            control.swivel_joint: (f"{n}/{control.swivel_joint}", ActuatorMode.POSITION),
            control.drive_joint: (f"{n}/{control.drive_joint}", ActuatorMode.VELOCITY),
        }),
        links=types.MappingProxyType(links),
    )
