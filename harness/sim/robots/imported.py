"""A robot from a model file (``model: {urdf: ...}`` / ``{mjcf: ...}``) attached to the world.

How it enters the world: the file is read and checked on its own (:mod:`.model_file`), then
its single top-level body is attached with ``MjsFrame.attach_body`` to a frame at the
robot's spawn pose (position, z included, and roll/pitch/yaw), every element named
``<robot name>/<name in the file>`` — so several robots from one file coexist, and MuJoCo
names follow the built-in models' rule. A root body without joints gets a free joint
``<robot name>/root``; nothing else of the file's world body (floors, lights) is taken, and
the world's options (timestep, integrator) apply.

Prims: ``<prim>`` and ``<prim>/<link>`` for every link (body) under its own name, flat like
Isaac Sim's URDF import, and ``<prim>/<link>/<geom>`` for named geoms (an MJCF safety
indicator disk); the root link's prim is the chassis odometry reads and its name the
default base frame. Forward is +X (REP-103) unless ``odometry.robot_front`` says otherwise.

Joints by name (the ``control:`` block): a diff-drive robot's two wheel joints, or a
swivel-drive robot's drive and swivel joints; and any hinge or slide joint named in
``model.drives``, for a graph's ``ArticulationController`` to command (its ``mode``, or
velocity for a joint that turns freely and position otherwise). The file's own position and
velocity servos are commanded by their joints' names too. Each must exist (the closest names are
suggested) and fit its role: a wheel or drive joint turns freely (a URDF ``continuous``
joint, an unlimited hinge), a swivel joint is a hinge. A joint the file already puts a
position or velocity servo on is driven through it (it must be the kind the controller
commands); otherwise srr adds one from ``model.drives.<joint>``, whose unset gains scale with
the model's mass ``m``: wheels and drive joints a velocity servo with
``kv = 50/s · m · r² / n`` and ``max_force = 3 m/s² · m · r / n`` (``r`` the wheel radius,
``n`` the number of driven wheels: a velocity time constant of 20 ms and 3 m/s² of
traction), a swivel joint a position servo with ``kp = 4 N·m/rad per kg · m``, critically
damped on the joint's own inertia, and ``max_force = 2 N·m per kg · m``; a velocity servo
on a joint no controller drives the robot with gets ``kv = 50/s · I`` (``I`` the joint's own
inertia) and the same ``max_force``.

URDF geom groups follow the built-in models: visual geoms (no contacts) group 1, collision
geoms group 3 (hidden from cameras and lidars) when the model has visual geoms, else group 1;
an MJCF file's groups are its own (0-2 seen, 3 and up hidden).
``model.frictionless_links``' collision geoms touch with one contact dimension and win the
contact's parameters (priority 1), like the TurtleBot3's casters.

Every problem is a :class:`~harness.errors.ScenarioError` naming the scenario file, the
field and the model file.
"""

from __future__ import annotations

import difflib
import math
import re
import types
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco

from harness.geometry import FloatArray
from harness.scenario.schema import (
    DiffDriveControl,
    DriveSpec,
    ForkliftControl,
    ModelFile,
    RobotSpec,
)
from harness.sim.prims import PrimKind, PrimTable
from harness.sim.robots.common import COLLISION_GROUP, VISUAL_GROUP, ActuatorMode, RobotBuild
from harness.sim.robots.model_file import (
    LoadedModel,
    ModelFileError,
    file_digest,
    load_model_file,
)
from harness.sim.robots.paths import ModelPathError, ModelSource, PackagePath, resolve_uri

__all__ = ["ROBOT_FRONT", "ModelSource", "add_model_robot"]

ROBOT_FRONT = (1.0, 0.0, 0.0)
_VELOCITY_RATE = 50.0  # 1/s: velocity servo time constant 20 ms
_TRACTION_ACCEL = 3.0  # m/s^2 the default drive torque limit allows
_POSITION_STIFFNESS = 4.0  # N·m/rad per kg of robot
_POSITION_FORCE = 2.0  # N·m per kg of robot
_NAME_RE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]*$")
_SENSOR_MOUNTS = frozenset({"lidar", "imu", "camera"})  # prims harness.sim.sensors adds


@dataclass(frozen=True)
class _Role:
    """A joint the controller commands: which field names it and what it must be."""

    joint: str
    field: str
    mode: ActuatorMode
    spins: bool


def _suggest(name: str, options: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, list(options), n=3, cutoff=0.5)
    if close:
        return " (did you mean " + " or ".join(repr(c) for c in close) + "?)"
    shown = ", ".join(list(options)[:12]) + (", ..." if len(options) > 12 else "")
    return f" (it has: {shown or 'none'})"


def _roles(control: ForkliftControl | DiffDriveControl, shown: str,
           src: ModelSource) -> list[_Role]:
    if isinstance(control, DiffDriveControl):
        if len(control.joint_names) != 2:
            raise src.error("control.joint_names", f"a differential drive needs two wheel "
                            f"joints of {shown} (left, right), got {len(control.joint_names)}")
        roles = [_Role(j, f"control.joint_names[{k}]", ActuatorMode.VELOCITY, True)
                 for k, j in enumerate(control.joint_names)]
    else:
        roles = [_Role(control.drive_joint, "control.drive_joint", ActuatorMode.VELOCITY, True),
                 _Role(control.swivel_joint, "control.swivel_joint", ActuatorMode.POSITION,
                       False)]
    if roles[0].joint == roles[1].joint:
        raise src.error(roles[1].field, f"{roles[1].joint!r} is also {roles[0].field}: the "
                        "controller needs two different joints")
    return roles


def _check_roles(roles: Sequence[_Role], loaded: LoadedModel, shown: str,
                 src: ModelSource) -> None:
    for role in roles:
        info = loaded.joints.get(role.joint)
        if info is None:
            raise src.error(role.field, f"{shown} has no joint {role.joint!r}"
                            f"{_suggest(role.joint, list(loaded.joints))}")
        if role.spins and not info.spins:
            raise src.error(role.field, f"joint {role.joint!r} of {shown} is {info.described}: a "
                            "wheel must turn freely (a continuous joint, an unlimited hinge)")
        if not role.spins and info.kind != "hinge":
            raise src.error(role.field, f"joint {role.joint!r} of {shown} is {info.described}: "
                            "a swivel must be a revolute joint (a hinge)")
        act = loaded.actuators.get(role.joint)
        if act is None:
            continue
        name, mode = act
        if mode is None:
            raise src.error(role.field, f"joint {role.joint!r} of {shown} has actuator {name!r}, "
                            "which is neither a position nor a velocity servo")
        if mode is not role.mode:
            raise src.error(role.field, f"joint {role.joint!r} of {shown} has a {mode.value} "
                            f"servo ({name!r}); the controller commands it by "
                            f"{role.mode.value}")


def _drive_modes(roles: Sequence[_Role], loaded: LoadedModel, model: ModelFile, shown: str,
                 src: ModelSource) -> dict[str, ActuatorMode]:
    """The servo srr adds per joint: the role's for a controlled joint without an actuator,
    and for every other joint in ``model.drives`` its ``mode`` (default: velocity for a joint
    that turns freely, position otherwise)."""
    modes = {r.joint: r.mode for r in roles if r.joint not in loaded.actuators}
    for joint, drive in model.drives.items():
        field = f"model.drives.{joint}"
        info = loaded.joints.get(joint)
        if info is None:
            raise src.error(field, f"{shown} has no joint {joint!r}"
                            f"{_suggest(joint, list(loaded.joints))}")
        if info.kind not in ("hinge", "slide"):
            raise src.error(field, f"joint {joint!r} of {shown} is {info.described}: only a "
                            "hinge or a slide joint can be driven")
        act = loaded.actuators.get(joint)
        if act is not None:
            raise src.error(field, f"joint {joint!r} already has actuator {act[0]!r} in "
                            f"{shown}; set its gains there")
        wanted = ActuatorMode(drive.mode) if drive.mode is not None else None
        role = modes.get(joint)
        if role is not None and wanted is not None and wanted is not role:
            raise src.error(f"{field}.mode", f"the control block commands joint {joint!r} by "
                            f"{role.value}, not {wanted.value}")
        modes[joint] = role or wanted or (ActuatorMode.VELOCITY if info.spins
                                          else ActuatorMode.POSITION)
    return modes


def _check_links(robot: RobotSpec, loaded: LoadedModel, shown: str, src: ModelSource) -> None:
    for link in loaded.links:
        if not _NAME_RE.match(link):
            raise src.error(f"model.{loaded.kind}", f"{shown}: link name {link!r} cannot name a "
                            "prim or a TF frame (letters, digits, '_', '.', '-')")
    model = robot.model_file
    assert model is not None
    wanted = [(f"model.frictionless_links[{k}]", link)
              for k, link in enumerate(model.frictionless_links)]
    sensors = robot.sensors
    for kind, block in (("camera", sensors.camera), ("lidar", sensors.lidar),
                        ("imu", sensors.imu)):
        if block is not None and block.enabled and block.site is None:
            wanted.append((f"sensors.{kind}.link", block.link))
    for field, link in wanted:
        if link not in loaded.links:
            raise src.error(field, f"{shown} has no link {link!r}"
                            f"{_suggest(link, loaded.links)}")
    sites = [site.name for site in loaded.spec.sites]
    for kind, block in (("camera", sensors.camera), ("lidar", sensors.lidar),
                        ("imu", sensors.imu)):
        if block is not None and block.enabled and block.site is not None \
                and block.site not in sites:
            raise src.error(f"sensors.{kind}.site", f"{shown} has no site {block.site!r}"
                            f"{_suggest(block.site, sites)}")


def _drive_settings(joint: str, mode: ActuatorMode, drive: DriveSpec, loaded: LoadedModel,
                    wheel: tuple[float, int] | None) -> tuple[float, float, float]:
    """(gain, damping, max force) of the servo srr adds on ``joint``. ``wheel``: (radius,
    number of driven wheels) for a joint the controller drives the robot with."""
    m = loaded.mass
    inertia = loaded.joint_inertia.get(joint, 0.0) + (drive.armature or 0.0)
    if mode is ActuatorMode.VELOCITY:
        if wheel is not None:
            radius, n_wheels = wheel
            kv = drive.kv or _VELOCITY_RATE * m * radius**2 / n_wheels
            force = drive.max_force or _TRACTION_ACCEL * m * radius / n_wheels
        else:
            kv = drive.kv or _VELOCITY_RATE * max(inertia, 1e-6)
            force = drive.max_force or _POSITION_FORCE * m
        return kv, 0.0, force
    kp = drive.kp or _POSITION_STIFFNESS * m
    kv = drive.kv or 2.0 * math.sqrt(kp * max(inertia, 1e-6))
    return kp, kv, drive.max_force or _POSITION_FORCE * m


def _style_geoms(body: mujoco.MjsBody, frictionless: set[str], n: str, urdf: bool) -> None:
    """URDF geom groups (an MJCF file's own groups are kept) and frictionless links."""
    geoms = [(b, g) for b in (body, *body.find_all(mujoco.mjtObj.mjOBJ_BODY))
             for g in b.geoms]
    has_visual = any(g.contype == 0 and g.conaffinity == 0 for _, g in geoms)
    for b, g in geoms:
        collides = g.contype != 0 or g.conaffinity != 0
        if urdf:
            g.group = VISUAL_GROUP if not collides or not has_visual else COLLISION_GROUP
        if collides and b.name.removeprefix(f"{n}/") in frictionless:
            g.condim = 1
            g.priority = 1


def _declare_named_geoms(root: mujoco.MjsBody, prim: str, n: str, prims: PrimTable) -> None:
    """``<prim>/<link>/<geom>`` for every named geom (a safety indicator disk, say); the
    names sensor mounts take are left to them."""
    for body in (root, *root.find_all(mujoco.mjtObj.mjOBJ_BODY)):
        link = body.name.removeprefix(f"{n}/")
        for geom in body.geoms:
            plain = geom.name.removeprefix(f"{n}/") if geom.name else ""
            if plain and _NAME_RE.match(plain) and plain not in _SENSOR_MOUNTS:
                prims.declare(f"{prim}/{link}/{plain}", PrimKind.GEOM, geom.name)


def add_model_robot(spec: mujoco.MjSpec, robot: RobotSpec,
                    control: ForkliftControl | DiffDriveControl,
                    pos: tuple[float, float, float], quat: FloatArray, prims: PrimTable,
                    src: ModelSource) -> RobotBuild:
    """Read ``robot.model``'s file, check it against the robot entry and attach it at
    ``pos``/``quat`` (its root link's frame)."""
    model = robot.model_file
    assert model is not None
    packages = PackagePath.of(src.base_dir, model.package_paths, src.environ)
    try:
        path = resolve_uri(model.path, src.base_dir, packages)
    except ModelPathError as err:
        raise src.error(f"model.{model.kind}", str(err)) from err
    shown = str(path)
    try:
        loaded = load_model_file(path, model.kind, packages, model.xacro_args)
    except ModelFileError as err:
        raise src.error(f"model.{err.field or model.kind}", f"{shown}: {err}") from err
    # A robot whose control graph is off is parked: its joints need no role and no drive.
    roles = _roles(control, shown, src) if control.enabled else []
    _check_roles(roles, loaded, shown, src)
    drive_modes = _drive_modes(roles, loaded, model, shown, src)
    _check_links(robot, loaded, shown, src)

    n, prim = robot.name, robot.prim
    frame = spec.worldbody.add_frame(pos=list(pos), quat=[float(q) for q in quat])
    root = frame.attach_body(loaded.spec.worldbody.first_body(), f"{n}/", "")
    if not list(root.joints):
        root.add_freejoint(name=f"{n}/root")
    _style_geoms(root, set(model.frictionless_links), n, loaded.kind == "urdf")

    links: dict[str, tuple[str, str]] = {}
    prims.declare(prim, PrimKind.BODY, f"{n}/{loaded.root}")
    for link in loaded.links:
        links[link] = (prims.declare(f"{prim}/{link}", PrimKind.BODY, f"{n}/{link}"),
                       f"{n}/{link}")
    _declare_named_geoms(root, prim, n, prims)
    joints = {j: f"{n}/{j}" for j, info in loaded.joints.items()
              if info.kind in ("hinge", "slide")}

    # The file's own position and velocity servos, each on its joint, and srr's servos.
    actuators = {j: (f"{n}/{a}", mode) for j, (a, mode) in loaded.actuators.items()
                 if mode is not None}
    n_wheels = max(1, sum(r.mode is ActuatorMode.VELOCITY for r in roles))
    wheels = {r.joint for r in roles if r.spins}
    for joint, mode in drive_modes.items():
        drive = model.drives.get(joint, DriveSpec())
        gain, damping, force = _drive_settings(
            joint, mode, drive, loaded,
            (control.wheel_radius, n_wheels) if joint in wheels else None)
        if drive.armature is not None:
            spec.joint(f"{n}/{joint}").armature = drive.armature
        act = spec.add_actuator(name=f"{n}/{joint}/srr_drive", target=f"{n}/{joint}",
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        if mode is ActuatorMode.VELOCITY:
            act.set_to_velocity(kv=gain)
        else:
            act.set_to_position(kp=gain, kv=damping)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-force, force]
        actuators[joint] = (f"{n}/{joint}/srr_drive", mode)

    return RobotBuild(
        name=n, model=robot.model_name, prim=prim, root_body=f"{n}/{loaded.root}",
        base_prim=f"{prim}/{loaded.root}", robot_front=ROBOT_FRONT,
        default_base_frame=loaded.root, joints=types.MappingProxyType(joints),
        actuators=types.MappingProxyType(actuators), links=types.MappingProxyType(links),
        assets=loaded.assets, file_digest=file_digest(path, loaded.assets, loaded.xacro),
        warnings=tuple(src.warning(f"model.{model.kind}", f"{shown}: {w}")
                       for w in loaded.warnings))
