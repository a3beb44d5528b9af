"""A robot's ``control:`` block against its compiled model: the numbers the drive controller
turns cmd_vel into wheel commands with, measured on the MuJoCo model instead of trusted.

The controllers never look at the model: the DifferentialController computes wheel rates
from ``wheel_radius`` and ``wheel_distance``, the swivel-drive IK from ``wheelbase`` and
``wheel_radius``, and sends the left wheel's rate to the first of ``joint_names``. A block
left at the TurtleBot3's defaults under a robot with bigger wheels drives it at the wrong
speed and turns it at the wrong rate, and nothing else notices. So, in the spawn state of the
compiled model (poses from ``mj_kinematics``), in the robot's base frame (the chassis
odometry reads, forward along ``odometry.robot_front`` or the model's own front, +Z up, left
= up × forward):

* **Wheel radius** of a wheel joint: the largest rolling radius of the collision geoms of the
  joint's body and the bodies welded to it (no joint between): a sphere's radius, a
  cylinder's or capsule's whose axis lies along the joint axis (within
  :data:`AXIS_TOLERANCE_DEG`), a mesh's farthest vertex from the joint axis (for a wheel
  mesh: its tyre's radius), each plus its centre's distance from the axis. Other shapes
  (boxes, ellipsoids, a cylinder across the axis) are not measured, and a wheel with no
  measured shape makes no claim.
* **Wheel distance** (differential drive): the two wheels' centres (the measured collision
  shape's centre, else the wheel body's origin; not the joints' anchors, which may lie
  anywhere along their axes) apart along the base's lateral (left) axis.
* **Wheelbase** (swivel drive): along the base's forward axis, from the drive wheel's joint
  anchor (steering at 0) to the fixed axle: the passive wheel joints (unlimited hinges, not
  the drive or swivel joint, not steered with the swivel, axis along the lateral axis, a
  measured collision shape) when they lie on one line across the robot (within
  :data:`AXLE_SPREAD`). Without such an axle (none, or wheels spread along the robot) no
  claim is made.
* **Left and right** (differential drive): the first of ``joint_names`` must be the left
  wheel, on the +left side of the second.
* **Axes**: a wheel or drive joint's axis must lie along the lateral axis (within
  :data:`AXIS_TOLERANCE_DEG`, either way round), and turn the way the controller assumes: a
  positive rate rolls a differential drive's wheel forward (axis to the left); a swivel
  drive's rolls it forward unless ``reverse_logic.flip_linear_x`` says it rolls backward.

A number off by more than :data:`TOLERANCE` of the model's, an axis off the lateral axis or
turning the other way are warnings (``file: field: message``): collision shapes are
approximations, a block may be calibrated on purpose, and the fix may lie in a model file the
user does not own. Wheels listed right before left are refused (:class:`ScenarioError`): the
block contradicts the model with no reading in which the run is right, and the fix is always
in the block. A block whose graph is off (``control.enabled: false``) drives nothing and is
not checked.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from harness.errors import ScenarioError
from harness.geometry import FloatArray, axis_label, yaw_between
from harness.scenario.schema import DiffDriveControl, ForkliftControl, RobotSpec

__all__ = [
    "AXIS_TOLERANCE_DEG",
    "AXLE_SPREAD",
    "TOLERANCE",
    "BaseAxes",
    "Wheel",
    "base_axes",
    "check_drive",
    "measure_wheel",
]

#: A block's wheel radius, wheel distance or wheelbase farther than this fraction of the
#: model's from it is warned of. The controllers' error is a ratio (speed scales with
#: model/block radius, turn rate with block/model distance or wheelbase), so the tolerance is
#: relative: 5 % lets a calibrated rolling radius (a tyre's few per cent of deflection) and
#: rounded numbers through, and catches another robot's numbers.
TOLERANCE = 0.05
#: Degrees: a wheel axis farther than this from the base's lateral axis is warned of (and a
#: cylinder farther than this from its joint's axis is not measured as a wheel).
AXIS_TOLERANCE_DEG = 5.0
#: Metres: passive wheels whose anchors lie within this of each other along the robot are
#: one axle (a swivel drive's wheelbase is measured to it).
AXLE_SPREAD = 0.01
#: Metres: two wheels closer than this across the robot are side by side, neither left.
_SIDE_BY_SIDE = 1e-3

_UP = np.array([0.0, 0.0, 1.0])
_COS_AXIS = math.cos(math.radians(AXIS_TOLERANCE_DEG))
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)
_CYLINDER = int(mujoco.mjtGeom.mjGEOM_CYLINDER)
_CAPSULE = int(mujoco.mjtGeom.mjGEOM_CAPSULE)
_MESH = int(mujoco.mjtGeom.mjGEOM_MESH)
_SHAPES = {_SPHERE: "sphere", _CYLINDER: "cylinder", _CAPSULE: "capsule", _MESH: "mesh"}
_HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class BaseAxes:
    """A robot's base frame as its drive sees it: the base body, its name (the link, for
    messages), its pose in the world and the forward and left unit vectors in it."""

    body: int
    name: str
    position: Vec3
    rotation: tuple[float, ...]  # base → world, a 3 by 3 matrix row by row
    front: Vec3
    left: Vec3

    def point(self, world: FloatArray) -> FloatArray:
        """A world point in the base frame."""
        return self.vector(world - np.asarray(self.position))

    def vector(self, world: FloatArray) -> FloatArray:
        """A world direction in the base frame."""
        return np.asarray(np.asarray(self.rotation).reshape(3, 3).T @ world, dtype=np.float64)


@dataclass(frozen=True)
class Wheel:
    """A wheel joint measured in its robot's base frame: its anchor and unit axis, and its
    rolling radius with what it was read from (None, '': no collision shape to measure), and
    its centre: the measured shape's, else its body's origin (a hinge's anchor may lie anywhere
    along its axis, so the anchor says nothing of where the wheel is across the robot)."""

    joint: str
    link: str
    anchor: Vec3
    axis: Vec3
    radius: float | None
    shape: str
    centre: Vec3

    def lateral(self, base: BaseAxes) -> float:
        """How far the wheel's centre lies to the left of the base's origin (negative:
        right)."""
        return float(np.dot(self.centre, base.left))

    def along(self, base: BaseAxes) -> float:
        """How far the anchor lies ahead of the base's origin."""
        return float(np.dot(self.anchor, base.front))

    def off_lateral_deg(self, base: BaseAxes) -> float:
        """Degrees between the axis and the lateral axis, either way round (0 … 90)."""
        return math.degrees(math.acos(min(1.0, abs(float(np.dot(self.axis, base.left))))))

    def rolls_forward(self, base: BaseAxes) -> bool:
        """Whether a positive rate rolls the wheel forward (its axis points left: the wheel
        centre moves along axis × up)."""
        return float(np.dot(self.axis, base.left)) > 0.0


def _vec3(v: FloatArray) -> Vec3:
    return float(v[0]), float(v[1]), float(v[2])


def base_axes(model: mujoco.MjModel, data: mujoco.MjData, body: int, front: Sequence[float],
              prefix: str) -> BaseAxes:
    """The base frame of the robot whose chassis is ``body`` and whose forward axis is
    ``front`` (in that frame; only its horizontal part counts, turned into a yaw as odometry
    turns it: :func:`~harness.geometry.yaw_between`; the scenario's checks refuse a front
    with no horizontal part). ``prefix``: the robot's MuJoCo name prefix, left off the name."""
    yaw = yaw_between(front)
    ahead = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body {body}"
    return BaseAxes(body, name.removeprefix(prefix), _vec3(data.xpos[body]),
                    tuple(float(v) for v in data.xmat[body]), _vec3(ahead),
                    _vec3(np.cross(_UP, ahead)))


def _welded(model: mujoco.MjModel, body: int) -> list[int]:
    """``body`` and every body welded to it (descendants with no joint between)."""
    out, todo = [], [body]
    while todo:
        b = todo.pop()
        out.append(b)
        todo += [int(c) for c in np.flatnonzero(model.body_parentid == b)
                 if c != b and int(model.body_jntnum[c]) == 0]
    return out


def _rolling_radius(model: mujoco.MjModel, data: mujoco.MjData, geom: int,
                    anchor: FloatArray, axis: FloatArray) -> float | None:
    """The farthest reach of ``geom`` from the line through ``anchor`` along ``axis`` (world
    frame), for the shapes that roll round it; None for the others."""
    def radial(points: FloatArray) -> FloatArray:
        rel = points - anchor
        return np.asarray(np.linalg.norm(rel - np.outer(rel @ axis, axis), axis=1))

    kind = int(model.geom_type[geom])
    centre = data.geom_xpos[geom]
    if kind == _SPHERE:
        return float(radial(centre[None, :])[0] + model.geom_size[geom][0])
    if kind in (_CYLINDER, _CAPSULE):
        along = data.geom_xmat[geom].reshape(3, 3)[:, 2]
        if abs(float(np.dot(along, axis))) < _COS_AXIS:
            return None  # a cylinder across the axle rolls on its rim, not its round face
        return float(radial(centre[None, :])[0] + model.geom_size[geom][0])
    if kind == _MESH:
        mesh = int(model.geom_dataid[geom])
        start, n = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        verts = model.mesh_vert[start:start + n] @ data.geom_xmat[geom].reshape(3, 3).T + centre
        return float(radial(verts).max()) if n else None
    return None


def measure_wheel(model: mujoco.MjModel, data: mujoco.MjData, joint: int, base: BaseAxes,
                  prefix: str) -> Wheel:
    """The wheel on joint ``joint`` in ``base``'s frame (``data``: poses after
    ``mj_kinematics``). ``prefix``: the robot's MuJoCo name prefix, left off names."""
    body = int(model.jnt_bodyid[joint])
    anchor, axis = data.xanchor[joint], data.xaxis[joint]
    best: tuple[float, int] | None = None
    for b in _welded(model, body):
        for g in range(int(model.body_geomadr[b]), int(model.body_geomadr[b])
                       + int(model.body_geomnum[b])):
            if not (model.geom_contype[g] or model.geom_conaffinity[g]):
                continue  # seen, never touched: not what the wheel rolls on
            r = _rolling_radius(model, data, g, anchor, axis)
            if r is not None and (best is None or r > best[0]):
                best = (r, g)

    def name(kind: mujoco.mjtObj, i: int) -> str:
        return (mujoco.mj_id2name(model, kind, i) or f"#{i}").removeprefix(prefix)

    shape, centre = "", data.xpos[body]
    if best is not None:
        g = best[1]
        shape = (f"collision {_SHAPES[int(model.geom_type[g])]} of link "
                 f"{name(mujoco.mjtObj.mjOBJ_BODY, int(model.geom_bodyid[g]))}")
        centre = data.geom_xpos[g]
    return Wheel(name(mujoco.mjtObj.mjOBJ_JOINT, joint), name(mujoco.mjtObj.mjOBJ_BODY, body),
                 _vec3(base.point(anchor)), _vec3(base.vector(axis)),
                 None if best is None else best[0], shape, _vec3(base.point(centre)))


def _off(block: float, model: float) -> bool:
    return abs(block - model) > TOLERANCE * model


def _given(control: DiffDriveControl | ForkliftControl, name: str) -> str:
    """``control``'s value of ``name`` in metres, said to be the default where it is."""
    value = getattr(control, name)
    default = {f.name: f.default for f in dataclasses.fields(control)}[name]
    return f"{value:g} m" + (" (the default)" if value == default else "")


def _times(ratio: float) -> str:
    return f"{ratio:.2f}×"


class _Findings:
    """The warnings about one robot's control block, collected, and where its fields are."""

    def __init__(self, field: str, file_for: Callable[[str], str]) -> None:
        self.field = field  # robots[i]
        self.file_for = file_for
        self.lines: list[str] = []

    def where(self, sub: str) -> tuple[str, str]:
        field = f"{self.field}.control.{sub}"
        return self.file_for(field), field

    def warn(self, sub: str, message: str) -> None:
        self.lines.append(str(ScenarioError(*self.where(sub), message)))

    def error(self, sub: str, message: str) -> ScenarioError:
        return ScenarioError(*self.where(sub), message)


def _radius(out: _Findings, control: DiffDriveControl | ForkliftControl,
            wheels: Sequence[Wheel]) -> None:
    """One warning for the first wheel whose radius is off the block's."""
    for w in wheels:
        if w.radius is not None and _off(control.wheel_radius, w.radius):
            out.warn("wheel_radius", f"{_given(control, 'wheel_radius')}, but the model's "
                     f"{w.joint} wheel is {w.radius:.3f} m ({w.shape}), so the robot drives "
                     f"and turns at {_times(w.radius / control.wheel_radius)} what cmd_vel "
                     "asks for")
            return


def _axis(out: _Findings, sub: str, w: Wheel, base: BaseAxes) -> bool:
    """A warning if ``w``'s axis is off the lateral axis; returns whether it is along it."""
    off = w.off_lateral_deg(base)
    if off <= AXIS_TOLERANCE_DEG:
        return True
    out.warn(sub, f"joint {w.joint!r} turns about {axis_label(w.axis, upper=True)} in "
             f"{base.name}'s frame, {off:.1f}° off the robot's lateral axis "
             f"({_lateral(base)}): a wheel's axle must run across the robot, or it does not "
             "roll where cmd_vel asks")
    return False


def _lateral(base: BaseAxes) -> str:
    """The base's left and forward axes, for messages (``left +Y, forward +X``)."""
    return (f"left {axis_label(base.left, upper=True)}, "
            f"forward {axis_label(base.front, upper=True)}")


def _turns(given: float, measured: float) -> str:
    """What a block's wheel distance or wheelbase ``given`` against the model's ``measured``
    does to the turn rate (the rate scales with their ratio), for a warning; nothing when the
    model's is about zero."""
    if measured < _SIDE_BY_SIDE:
        return ""
    return f", which alone makes the robot turn at {_times(given / measured)} the rate " \
        "cmd_vel asks for"


def _check_diff(out: _Findings, control: DiffDriveControl, wheels: Sequence[Wheel],
                base: BaseAxes) -> None:
    first, second = wheels
    y0, y1 = first.lateral(base), second.lateral(base)
    if y0 < y1 - _SIDE_BY_SIDE:
        def side(w: Wheel, y: float) -> str:
            return f"{w.joint} is {abs(y):.3f} m {'left' if y >= 0 else 'right'}"
        raise out.error("joint_names", f"[{first.joint}, {second.joint}] names the right "
                        f"wheel first: {side(first, y0)} and {side(second, y1)} of "
                        f"{base.name}'s origin ({_lateral(base)}); the controller drives the "
                        "first joint as the left wheel, so the robot would turn against "
                        f"cmd_vel: write [{second.joint}, {first.joint}]")
    _radius(out, control, wheels)
    apart = abs(y0 - y1)
    if _off(control.wheel_distance, apart):
        turns = _turns(control.wheel_distance, apart)
        out.warn("wheel_distance", f"{_given(control, 'wheel_distance')}, but the model's "
                 f"wheels {first.joint} and {second.joint} are {apart:.3f} m apart (their "
                 f"centres, across the robot){turns}")
    for k, w in enumerate(wheels):
        sub = f"joint_names[{k}]"
        if _axis(out, sub, w, base) and not w.rolls_forward(base):
            out.warn(sub, f"joint {w.joint!r} turns about {axis_label(w.axis, upper=True)} in "
                     f"{base.name}'s frame, the robot's right ({_lateral(base)}), so a "
                     "positive wheel rate rolls it backward; the controller needs both "
                     "wheels to roll forward on positive rates: turn the joint's axis round "
                     "in the model")


def _axle(model: mujoco.MjModel, data: mujoco.MjData, joints: Mapping[str, int],
          control: ForkliftControl, base: BaseAxes, prefix: str) -> list[Wheel]:
    """The passive wheels of the fixed axle (see the module's docstring), or none."""
    swivel = joints.get(control.swivel_joint)
    steered = (set() if swivel is None else
               {b for b in range(model.nbody)
                if _descends(model, b, int(model.jnt_bodyid[swivel]))})
    wheels = []
    for name, j in joints.items():
        if name in (control.drive_joint, control.swivel_joint) \
                or int(model.jnt_type[j]) != _HINGE or model.jnt_limited[j] \
                or int(model.jnt_bodyid[j]) in steered:
            continue
        w = measure_wheel(model, data, j, base, prefix)
        if w.radius is not None and w.off_lateral_deg(base) <= AXIS_TOLERANCE_DEG:
            wheels.append(w)
    spots = [w.along(base) for w in wheels]
    return wheels if wheels and max(spots) - min(spots) <= AXLE_SPREAD else []


def _descends(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    while True:
        if body == ancestor:
            return True
        if body == 0:
            return False
        body = int(model.body_parentid[body])


def _check_swivel(out: _Findings, model: mujoco.MjModel, data: mujoco.MjData,
                  joints: Mapping[str, int], control: ForkliftControl, drive: Wheel,
                  base: BaseAxes, prefix: str) -> None:
    _radius(out, control, [drive])
    axle = _axle(model, data, joints, control, base, prefix)
    if axle:
        base_m = abs(drive.along(base) - float(np.mean([w.along(base) for w in axle])))
        if _off(control.wheelbase, base_m):
            names = " and ".join(w.joint for w in axle)
            turns = _turns(control.wheelbase, base_m)
            out.warn("wheelbase", f"{_given(control, 'wheelbase')}, but the model's drive "
                     f"wheel {drive.joint} is {base_m:.3f} m from the axle of {names} "
                     f"(along the robot){turns}")
    if _axis(out, "drive_joint", drive, base):
        flip = control.reverse_logic.flip_linear_x
        if drive.rolls_forward(base) == flip:
            way = "forward" if flip else "backward"
            out.warn("reverse_logic.flip_linear_x",
                     f"{str(flip).lower()}, but joint {drive.joint!r} turns about "
                     f"{axis_label(drive.axis, upper=True)} in {base.name}'s frame "
                     f"({_lateral(base)}), "
                     f"so a positive wheel rate rolls the robot {way} and a positive "
                     f"cmd_vel.linear.x drives it backward: set it to {str(not flip).lower()}")


def check_drive(model: mujoco.MjModel, data: mujoco.MjData, robot: RobotSpec, field: str,
                file_for: Callable[[str], str], joints: Mapping[str, int], base: BaseAxes
                ) -> tuple[str, ...]:
    """The warnings about ``robot``'s control block (``field``: ``robots[i]``; ``file_for``
    a field path's file) measured against its model: ``joints`` plain name → MuJoCo joint
    id, ``base`` its base frame; ``data`` holds the spawn state's poses (``mj_kinematics``).
    Raises :class:`ScenarioError` for wheels listed right before left."""
    control = robot.control_spec
    if not control.enabled:
        return ()
    prefix = f"{robot.name}/"
    out = _Findings(field, file_for)
    if isinstance(control, DiffDriveControl):
        ids = [joints.get(j) for j in control.joint_names]
        if len(ids) == 2 and None not in ids:
            _check_diff(out, control, [measure_wheel(model, data, j, base, prefix)
                                       for j in ids if j is not None], base)
    elif control.drive_joint in joints:
        drive = measure_wheel(model, data, joints[control.drive_joint], base, prefix)
        _check_swivel(out, model, data, joints, control, drive, base, prefix)
    return tuple(out.lines)
