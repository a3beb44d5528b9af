"""The simulated world: a MuJoCo model built from a :class:`~harness.scenario.schema.Scenario`.

``World.build(scenario)`` assembles an ``MjSpec`` (the warehouse and/or a world file, enabled
robots, enabled fixed cameras, robot-mounted sensor attach points, workers on foot), compiles
it and resolves every prim path to a MuJoCo object. A world file (``world.model``,
:mod:`harness.sim.world_file`) is read and checked before anything else, and after compiling
no robot may start inside one of its static geoms; each robot's ``control:`` block is
measured against its compiled model (:mod:`harness.sim.kinematics`). Everything the rest of
srr needs is addressed by prim path (``/World/...``) or by robot name; MuJoCo names stay
internal.

Conventions:

* Physics: ``timestep = 1 / (tick_hz * substeps)``; single-threaded and deterministic — the
  same scenario and the same command sequence give bit-identical states.
* Built-in ground robots are spawned with their root frame on the floor (the spawn's z is
  ignored) and the spawn's roll/pitch/yaw (degrees, extrinsic X-Y-Z); a robot from a model
  file has its root link's frame at the spawn pose, z included (:mod:`harness.sim.robots`).
* Every robot is an articulation: its root link's prim (and the robot prim) is the
  articulation root, and :meth:`World.articulation_links` lists its links' parent → child
  prims, for transform-tree publishers given the root.
* Poses are world-frame positions and quaternions ``(w, x, y, z)``. Camera prims use Isaac's
  world axes convention (+X forward, +Z up); see :mod:`harness.sim.cameras`.
* After :meth:`World.step` poses, velocities and position/velocity sensors (IMU orientation
  and gyro) belong to the new state; acceleration sensors (the IMU accelerometer) and contact
  forces are those of the last substep (one physics step, e.g. 1/240 s, old).
* MuJoCo's own warnings go to the ``harness.sim`` logger, never to MuJoCo's default
  ``MUJOCO_LOG.TXT`` in the current directory or to stdout; the one that comes with a
  divergence ("Nan, Inf or huge value in QACC at DOF 3") ends the :class:`SimulationError`
  instead.
"""

from __future__ import annotations

import logging
import math
import os
import re
import types
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import mujoco
import numpy as np

from harness.errors import ScenarioError, SimulationError
from harness.geometry import FloatArray
from harness.scenario.schema import Scenario, WorldSpec
from harness.sim.cameras import add_fixed_camera, world_convention_quat
from harness.sim.footprints import Footprint
from harness.sim.kinematics import base_axes, check_drive
from harness.sim.layout import check_layout
from harness.sim.lidar import check_lidars
from harness.sim.mjquat import quat_wxyz_from_mat_mj, quat_wxyz_from_rpy_deg_mj
from harness.sim.prims import PrimKind, PrimRef, PrimTable
from harness.sim.render import apply_render_settings
from harness.sim.robots import ActuatorMode, ModelSource, RobotBuild, add_robot
from harness.sim.robots.model_file import file_digest
from harness.sim.sensors import MountedSensors, add_robot_sensors
from harness.sim.spawns import camera_warnings, check_spawns, fixed_cameras, robot_spawn
from harness.sim.warehouse import (
    FLOOR_MARGIN,
    add_ground,
    add_sky,
    add_sun,
    add_warehouse,
    floor_half_extent,
    set_headlight,
)
from harness.sim.workers import Worker, WorkerDriver, add_workers, plan_workers
from harness.sim.world_file import LoadedWorld, add_world_file, load_world_file

__all__ = ["ImuReading", "JointRef", "RobotInfo", "World"]

_XBODY = mujoco.mjtObj.mjOBJ_XBODY
_log = logging.getLogger("harness.sim")
_BADQPOS = int(mujoco.mjtWarning.mjWARN_BADQPOS)
_BADQACC = int(mujoco.mjtWarning.mjWARN_BADQACC)
assert _BADQACC - _BADQPOS == 2  # qpos, qvel, qacc: one slice of data.warning
# MuJoCo's words for a non-finite or huge qpos, qvel or qacc: the step's divergence check
# raises on that state, naming the last such warning (this process's; steps are synchronous)
_DIVERGENCE_TEXT = "Nan, Inf or huge value"
_last_divergence: list[str] = []


def _mujoco_warning(text: str) -> None:
    """MuJoCo's warning handler while srr runs (see the module's notes)."""
    if text.startswith(_DIVERGENCE_TEXT):
        _last_divergence[:] = [text]
    else:
        _log.warning("MuJoCo: %s", text)

_INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
}
_NEAR_CLIP_M = 0.03
_GROUND_PREFIX = "srr-ground/"  # srr's ground, sky and sun under a world file ('-': no robot)
_MIN_GROUND = 5.0  # m: the smallest half extent of the ground srr adds under a world file
_MIN_TOP = 1.0  # m
_MIN_OFFSCREEN = (640, 480)

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class JointRef:
    """A robot joint: plain name, MuJoCo ids/addresses and its actuator (``-1``: passive)."""

    name: str
    joint_id: int
    qposadr: int
    dofadr: int
    actuator_id: int
    mode: ActuatorMode | None


@dataclass(frozen=True)
class RobotInfo:
    """Everything the world knows about one robot, resolved to MuJoCo ids."""

    name: str
    model: str
    prim: str
    base_prim: str
    robot_front: Vec3
    default_base_frame: str
    root_body_id: int
    body_ids: tuple[int, ...]
    joints: Mapping[str, JointRef]
    links: Mapping[str, str]
    sensors: Mapping[str, str]
    imu_sensors: Mapping[str, tuple[int, int]]
    # (parent link prim, child link prim) of every link but the root, in model order
    link_tree: tuple[tuple[str, str], ...] = ()


class ImuReading(NamedTuple):
    """IMU sample in the IMU site frame: orientation (w, x, y, z) of the site in the world,
    angular velocity (rad/s) and specific force (m/s^2, +9.81 on +Z when level and still)."""

    orientation: FloatArray
    angular_velocity: FloatArray
    linear_acceleration: FloatArray


def _scene_extent(world: WorldSpec, loaded: LoadedWorld | None) -> tuple[float, float, float]:
    """Half extents (x, y) of the ground and the height of the scene: the warehouse's, grown
    to hold a world file's geometry (plus a margin on the ground)."""
    hx = hy = top = 0.0
    if world.procedural:
        (hx, hy), top = floor_half_extent(world), world.wall_height
    if loaded is not None:
        x0, x1, y0, y1, z1 = loaded.bounds or (0.0, 0.0, 0.0, 0.0, 0.0)
        hx = max(hx, max(abs(x0), abs(x1)) + FLOOR_MARGIN, _MIN_GROUND)
        hy = max(hy, max(abs(y0), abs(y1)) + FLOOR_MARGIN, _MIN_GROUND)
        top = max(top, z1, _MIN_TOP)
    return hx, hy, top


def _configure(spec: mujoco.MjSpec, scenario: Scenario,
               extent3: tuple[float, float, float]) -> None:
    physics = scenario.physics
    spec.modelname = "srr"
    spec.compiler.degree = False
    spec.compiler.autolimits = True
    spec.option.timestep = 1.0 / (physics.tick_hz * physics.substeps)
    spec.option.integrator = _INTEGRATORS[physics.integrator]
    spec.option.iterations = physics.solver_iterations
    hx, hy, top = extent3
    extent = 2.0 * max(hx, hy, top)
    spec.stat.extent = extent
    spec.stat.center = [0.0, 0.0, top / 2]
    spec.visual.map.znear = _NEAR_CLIP_M / extent
    spec.visual.map.zfar = 3.0
    widths = [_MIN_OFFSCREEN[0]] + [c.resolution[0] for c in scenario.cameras]
    heights = [_MIN_OFFSCREEN[1]] + [c.resolution[1] for c in scenario.cameras]
    for robot in scenario.robots:
        cam = robot.sensors.camera
        if cam is not None:
            widths.append(cam.resolution[0])
            heights.append(cam.resolution[1])
    spec.visual.global_.offwidth = max(widths)
    spec.visual.global_.offheight = max(heights)


def _resolve_robot(model: mujoco.MjModel, build: RobotBuild,
                   sensors: MountedSensors) -> RobotInfo:
    def lookup(objtype: mujoco.mjtObj, name: str) -> int:
        idx = int(mujoco.mj_name2id(model, objtype, name))
        if idx < 0:
            raise SimulationError(f"robot {build.name}: {name!r} missing from the compiled model")
        return idx

    root = lookup(mujoco.mjtObj.mjOBJ_BODY, build.root_body)
    body_ids = tuple(int(b) for b in np.flatnonzero(model.body_rootid == root))
    refs: list[JointRef] = []
    for plain, mj_name in build.joints.items():
        jid = lookup(mujoco.mjtObj.mjOBJ_JOINT, mj_name)
        act, mode = -1, None
        if plain in build.actuators:
            act_name, mode = build.actuators[plain]
            act = lookup(mujoco.mjtObj.mjOBJ_ACTUATOR, act_name)
        refs.append(JointRef(plain, jid, int(model.jnt_qposadr[jid]), int(model.jnt_dofadr[jid]),
                             act, mode))
    refs.sort(key=lambda r: r.joint_id)
    body_prim: dict[int, str] = {}
    for link_prim, body_name in build.links.values():
        body_prim.setdefault(lookup(mujoco.mjtObj.mjOBJ_BODY, body_name), link_prim)
    tree = tuple((body_prim[int(model.body_parentid[b])], body_prim[b]) for b in body_ids
                 if b != root and b in body_prim and int(model.body_parentid[b]) in body_prim)
    imu: dict[str, tuple[int, int]] = {}
    for kind, name in sensors.imu_sensors.items():
        sid = lookup(mujoco.mjtObj.mjOBJ_SENSOR, name)
        imu[kind] = (int(model.sensor_adr[sid]), int(model.sensor_dim[sid]))
    return RobotInfo(
        name=build.name, model=build.model, prim=build.prim, base_prim=build.base_prim,
        robot_front=build.robot_front, default_base_frame=build.default_base_frame,
        root_body_id=root, body_ids=body_ids,
        joints=types.MappingProxyType({r.name: r for r in refs}),
        links=types.MappingProxyType({k: v[0] for k, v in build.links.items()}),
        sensors=sensors.prims, imu_sensors=types.MappingProxyType(imu), link_tree=tree,
    )


def _add_scene(spec: mujoco.MjSpec, world: WorldSpec, loaded: LoadedWorld | None,
               extent3: tuple[float, float, float], prims: PrimTable) -> None:
    """The static scene: the warehouse, a world file, or both (``world.model.mode``). A
    file that replaces the warehouse gets srr's ground, sky and sun where it has none."""
    if world.procedural:
        add_warehouse(spec, world, prims)
    if loaded is None:
        return
    if not world.procedural:
        if not loaded.has_floor:
            add_ground(spec, spec.worldbody, (extent3[0], extent3[1]), _GROUND_PREFIX)
        if not loaded.has_sky:
            add_sky(spec, _GROUND_PREFIX)
        set_headlight(spec)
        if not loaded.has_light:
            add_sun(spec, extent3[2], _GROUND_PREFIX)
    add_world_file(spec, loaded, prims)


def _assemble(scenario: Scenario, prims: PrimTable, source: str, environ: Mapping[str, str],
              loaded: LoadedWorld | None,
              ) -> tuple[mujoco.MjSpec, list[tuple[RobotBuild, MountedSensors]]]:
    """The whole spec: options, warehouse and/or world file, enabled robots with their
    sensors, fixed cameras."""
    spec = mujoco.MjSpec()
    extent3 = _scene_extent(scenario.world, loaded)
    _configure(spec, scenario, extent3)
    _add_scene(spec, scenario.world, loaded, extent3, prims)
    builds: list[tuple[RobotBuild, MountedSensors]] = []
    seen: set[str] = set()
    assets: dict[str, bytes] = dict(loaded.assets) if loaded is not None else {}
    for i, robot in enumerate(scenario.robots):
        if not robot.enabled:
            continue
        if robot.name in seen:
            raise SimulationError(f"robots.{robot.name}: two robots share this name")
        seen.add(robot.name)
        x, y, z = robot.spawn.position
        quat = quat_wxyz_from_rpy_deg_mj(robot.spawn.rpy_deg)
        field = f"robots[{i}]"
        where = ModelSource(scenario.file_for(field, source), field,
                            Path(scenario.source_file(field, source)).parent, environ,
                            origin=lambda path: scenario.file_for(path, source))
        height = float(z) if robot.model_file is not None else 0.0
        build = add_robot(spec, robot, (float(x), float(y), height), quat, prims, where)
        assets.update(build.assets)
        builds.append((build, add_robot_sensors(spec, robot, build, prims, where)))
    for camera in scenario.cameras:
        if camera.enabled:
            add_fixed_camera(spec, camera, prims)
    if assets:
        spec.assets = assets
    return spec, builds


def _robot_of_element(scenario: Scenario, message: str) -> tuple[int, Any] | None:
    """(index, model file) of the enabled robot with a model file whose element MuJoCo's
    ``message`` names (``Element name 'diffbot/base_link'``: the robot's name is the
    prefix of its elements), else None."""
    found = re.search(r"Element name '([^'/]+)/", message)
    if found is None:
        return None
    for i, robot in enumerate(scenario.robots):
        if robot.enabled and robot.name == found.group(1) and robot.model_file is not None:
            return i, robot.model_file
    return None


def _check_drives(model: mujoco.MjModel, data: mujoco.MjData, scenario: Scenario,
                  robots: Mapping[str, RobotInfo], prims: Mapping[str, PrimRef],
                  source: str) -> tuple[str, ...]:
    """Every enabled robot's control block against its compiled model
    (:mod:`harness.sim.kinematics`): the warnings, or the first error raised. Reads the spawn
    state's poses, which ``mj_kinematics`` computes here (the world's ``mj_forward`` computes
    the same again)."""
    mujoco.mj_kinematics(model, data)
    out: list[str] = []
    for i, robot in enumerate(scenario.robots):
        info = robots.get(robot.name)
        if not robot.enabled or info is None:
            continue
        front = (robot.odometry.robot_front if robot.odometry.robot_front is not None
                 else info.robot_front)  # as odometry reads it
        base = base_axes(model, data, prims[info.base_prim].id, front, f"{robot.name}/")
        out += check_drive(model, data, robot, f"robots[{i}]",
                           lambda path: scenario.file_for(path, source),
                           {j: ref.joint_id for j, ref in info.joints.items()}, base)
    return tuple(out)


class World:
    """A compiled MuJoCo world plus the prim and robot tables; build it with :meth:`build`."""

    def __init__(self, scenario: Scenario, model: mujoco.MjModel, data: mujoco.MjData,
                 prims: Mapping[str, PrimRef], robots: Mapping[str, RobotInfo],
                 workers: WorkerDriver | None = None,
                 world_file: LoadedWorld | None = None,
                 scene_files: Mapping[str, str] | None = None,
                 warnings: tuple[str, ...] = ()) -> None:
        self._scenario = scenario
        self._world_file = world_file
        self.scene_files: Mapping[str, str] = types.MappingProxyType(dict(scene_files or {}))
        #: ``file: field: message`` lines about the robots' model files that do not stop a
        #: run (a link that collides but weighs nothing), and about control blocks that do
        #: not agree with their models (:mod:`harness.sim.kinematics`), and about fixed
        #: cameras inside something (:func:`~harness.sim.spawns.camera_warnings`).
        self.warnings = warnings
        self._model = model
        self._data = data
        self._prims = prims
        self._robots = robots
        self._workers = workers if workers is not None else WorkerDriver(model, ())
        self._rgba0 = model.geom_rgba.copy()
        # Live views into ``data`` (its buffers never move), read by every step's divergence
        # check: MuJoCo's counts of bad qpos, qvel and qacc (on the first two it resets the
        # state to the model's initial one and carries on: a robot back at its spawn)
        self._bad = data.warning.number[_BADQPOS:_BADQACC + 1]
        self._qpos = data.qpos
        self._moving = bool(self._workers.workers)  # any worker to place each tick
        _last_divergence.clear()
        mujoco.set_mju_user_warning(_mujoco_warning)
        mujoco.mj_forward(model, data)

    # ------------------------------------------------------------------ building
    @classmethod
    def build(cls, scenario: Scenario, source: str = "<scenario>",
              environ: Mapping[str, str] | None = None) -> World:
        """Build the world for ``scenario`` (enabled robots and cameras only). ``source`` is
        the scenario file: robots' and the world's model files are found relative to it (or
        to the include that holds the robot or the world) and errors about them name it;
        ``environ`` (default: the process environment) holds ``SRR_PACKAGE_PATH`` /
        ``ROS_PACKAGE_PATH``. A control block that does not agree with its robot's model is
        a warning in :attr:`warnings`, wheels listed right before left an error."""
        check_layout(scenario, source)
        check_lidars(scenario, source)
        prims = PrimTable()
        workers = plan_workers(scenario)
        env = os.environ if environ is None else environ
        loaded = None
        if scenario.world.model is not None:
            loaded = load_world_file(scenario.world.model, ModelSource(
                scenario.file_for("world", source), "world",
                Path(scenario.source_file("world", source)).parent, env,
                origin=lambda path: scenario.file_for(path, source)))
        try:
            spec, builds = _assemble(scenario, prims, source, env, loaded)
            add_workers(spec, workers, prims)
            model = spec.compile()
        except ValueError as err:  # MuJoCo refuses a spec element (e.g. a repeated name)
            robot = _robot_of_element(scenario, str(err))
            if robot is not None:  # an element of a robot's model file: name that file
                i, model = robot
                field = f"robots[{i}].model"
                raise ScenarioError(scenario.file_for(f"robots[{i}]", source), field,
                                    f"{model.path}: MuJoCo cannot build the robot from it: "
                                    f"{' '.join(str(err).split())}") from err
            raise SimulationError(f"scenario {scenario.name}: MuJoCo model could not be built: "
                                  f"{err}") from err
        apply_render_settings(model, scenario.render)
        data = mujoco.MjData(model)
        resolved = prims.resolve(model)
        robots = {b.name: _resolve_robot(model, b, s) for b, s in builds}
        files = {f"robots[{scenario.robot_index(b.name)}].model": b.file_digest
                 for b, _ in builds if b.file_digest is not None}
        if loaded is not None:
            files["world.model"] = file_digest(loaded.path, loaded.assets)
        drives = _check_drives(model, data, scenario, robots, resolved, source)
        world = cls(scenario, model, data, resolved, types.MappingProxyType(robots),
                    WorkerDriver(model, workers), loaded, files,
                    (*(w for b, _ in builds for w in b.warnings), *drives))
        owner = {b: name for name in world.robot_names() for b in world.robot_body_ids(name)}
        describe = None if loaded is None else loaded.describe_static
        check_spawns(model, data, owner, robot_spawn(scenario, source), describe)
        world.warnings = (*world.warnings, *camera_warnings(
            model, data, owner, fixed_cameras(scenario, source), describe))
        return world

    # ------------------------------------------------------------------ world file
    @property
    def world_file(self) -> LoadedWorld | None:
        """The world file (``world.model``) as it was read, or None."""
        return self._world_file

    def footprints(self) -> tuple[Footprint, ...]:
        """Outlines on the floor of the world file's static geometry, for the map (see
        :mod:`harness.sim.world_file`); empty without a world file."""
        return () if self._world_file is None else self._world_file.footprints

    # ------------------------------------------------------------------ state
    @property
    def model(self) -> mujoco.MjModel:
        return self._model

    @property
    def data(self) -> mujoco.MjData:
        return self._data

    @property
    def scenario(self) -> Scenario:
        return self._scenario

    @property
    def timestep(self) -> float:
        return float(self._model.opt.timestep)

    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps, then refresh derived quantities for the new state."""
        if n < 0:
            raise SimulationError(f"cannot step a negative number of times ({n})")
        m, d = self._model, self._data
        start = d.time
        for _ in range(n):
            mujoco.mj_step(m, d)
        if n:
            # mj_step leaves poses/velocities of the state *before* its integration; refresh
            # them (and position/velocity sensors) for the new state — far cheaper than
            # mj_forward. Acceleration sensors keep the values of the last substep.
            mujoco.mj_kinematics(m, d)
            mujoco.mj_comPos(m, d)
            mujoco.mj_camlight(m, d)
            mujoco.mj_comVel(m, d)
            mujoco.mj_sensorPos(m, d)
            mujoco.mj_sensorVel(m, d)
        # q·q is finite exactly when every entry of qpos is (squares: no inf - inf; only
        # entries beyond 1e154 could overflow, far past MuJoCo's own 1e10 limit on qpos),
        # and one dot product costs a third of np.isfinite(q).all().
        qpos = self._qpos
        if self._bad.any() or not math.isfinite(qpos.dot(qpos)):
            said = f": MuJoCo: {self._named_dof(_last_divergence.pop())}" \
                if _last_divergence else ""
            # a bad qpos or qvel has sent MuJoCo's clock back to 0 with the state
            raise SimulationError(f"simulation diverged at t={max(d.time, start):.4f} s "
                                  f"(non-finite state){said}")

    def _named_dof(self, text: str) -> str:
        """MuJoCo's ``at DOF 7`` with the joint it belongs to (for QPOS the number is an
        index into qpos, for QVEL and QACC one into the degrees of freedom)."""
        m, model = re.search(r"at DOF (\d+)", text), self._model
        if m is None or model.njnt == 0:
            return text
        i = int(m[1])
        if "QPOS" in text:
            joint = int(np.searchsorted(model.jnt_qposadr, i, side="right")) - 1 \
                if i < model.nq else -1
        else:
            joint = int(model.dof_jntid[i]) if i < model.nv else -1
        name = model.joint(joint).name if joint >= 0 else ""
        return text.replace(m[0], f"{m[0]} (joint {name})", 1) if name else text

    def reset(self) -> None:
        """Back to the spawn state: ``mj_resetData`` (controls, warm start, time cleared) and
        the build-time geom colours."""
        mujoco.mj_resetData(self._model, self._data)
        self._model.geom_rgba[:] = self._rgba0
        mujoco.mj_forward(self._model, self._data)

    # ------------------------------------------------------------------ workers
    def update_workers(self, time_ns: int) -> None:
        """Put every worker where it is at ``time_ns`` (a pure function of time, see
        :mod:`harness.sim.workers`) and refresh poses so prims, rays and renders agree."""
        if self._moving and self._workers.place(self._data, time_ns):
            mujoco.mj_kinematics(self._model, self._data)
            mujoco.mj_comPos(self._model, self._data)
            mujoco.mj_camlight(self._model, self._data)

    def workers(self) -> tuple[Worker, ...]:
        """The enabled workers, in ``scenario.workers`` order."""
        return self._workers.workers

    def worker_prims(self) -> tuple[str, ...]:
        """Prims of the enabled workers (``/World/Characters/<name>``), in list order."""
        return tuple(w.prim for w in self._workers.workers)

    # ------------------------------------------------------------------ prims
    def prims(self) -> tuple[str, ...]:
        """Every prim path, sorted."""
        return tuple(self._prims)

    def has_prim(self, path: str) -> bool:
        return path in self._prims

    def prim_ref(self, path: str) -> PrimRef:
        """The MuJoCo object (kind, id, name) behind ``path``."""
        try:
            return self._prims[path]
        except KeyError:
            raise SimulationError(f"no prim {path} in the world") from None

    def prim_pose(self, path: str) -> tuple[FloatArray, FloatArray]:
        """World position (3,) and orientation (w, x, y, z) of ``path``.

        Camera prims are returned in the world axes convention (+X forward, +Z up).
        """
        ref, d = self.prim_ref(path), self._data
        if ref.kind is PrimKind.BODY:
            return d.xpos[ref.id].copy(), d.xquat[ref.id].copy()
        if ref.kind is PrimKind.SITE:
            return d.site_xpos[ref.id].copy(), quat_wxyz_from_mat_mj(d.site_xmat[ref.id])
        if ref.kind is PrimKind.GEOM:
            return d.geom_xpos[ref.id].copy(), quat_wxyz_from_mat_mj(d.geom_xmat[ref.id])
        q_mj = quat_wxyz_from_mat_mj(d.cam_xmat[ref.id])
        return d.cam_xpos[ref.id].copy(), world_convention_quat(q_mj)

    def prim_velocity(self, path: str) -> tuple[FloatArray, FloatArray]:
        """Linear (m/s) and angular (rad/s) velocity of ``path``'s origin, world frame."""
        ref = self.prim_ref(path)
        res = np.zeros(6)
        # mjOBJ_BODY means the body's inertial frame to mj_objectVelocity; XBODY is its origin.
        objtype = _XBODY if ref.kind is PrimKind.BODY else ref.kind.objtype
        mujoco.mj_objectVelocity(self._model, self._data, objtype, ref.id, res, 0)
        return res[3:], res[:3]  # two halves of an array made here: no copies needed

    def prim_body_id(self, path: str) -> int:
        """The MuJoCo body ``path`` belongs to (the body itself for body prims)."""
        ref, m = self.prim_ref(path), self._model
        if ref.kind is PrimKind.BODY:
            return ref.id
        if ref.kind is PrimKind.SITE:
            return int(m.site_bodyid[ref.id])
        if ref.kind is PrimKind.GEOM:
            return int(m.geom_bodyid[ref.id])
        return int(m.cam_bodyid[ref.id])

    def set_geom_rgba(self, prim_path: str, rgba: Sequence[float]) -> None:
        """Recolour the geom at ``prim_path`` (shows in the next render)."""
        ref = self.prim_ref(prim_path)
        if ref.kind is not PrimKind.GEOM:
            raise SimulationError(f"prim {prim_path} is a {ref.kind.value}, not a geom")
        values = [float(v) for v in rgba]
        if len(values) != 4 or not all(0.0 <= v <= 1.0 for v in values):
            raise SimulationError(f"rgba for {prim_path} must be 4 values in [0, 1], got {rgba}")
        self._model.geom_rgba[ref.id] = values

    # ------------------------------------------------------------------ robots
    def robot_names(self) -> tuple[str, ...]:
        return tuple(self._robots)

    def robot(self, name: str) -> RobotInfo:
        try:
            return self._robots[name]
        except KeyError:
            raise SimulationError(f"no robot named {name!r} in the world "
                                  f"(robots: {', '.join(self._robots) or 'none'})") from None

    def robot_at(self, robot_prim: str) -> RobotInfo:
        """The robot whose prim is ``robot_prim`` or an ancestor of it (deepest match)."""
        best: RobotInfo | None = None
        for info in self._robots.values():
            inside = robot_prim == info.prim or robot_prim.startswith(info.prim + "/")
            if inside and (best is None or len(info.prim) > len(best.prim)):
                best = info
        if best is None:
            raise SimulationError(f"no robot at prim {robot_prim}")
        return best

    def articulation_links(self, prim: str) -> tuple[tuple[str, str], ...] | None:
        """If ``prim`` is a robot's articulation root (the robot prim or its root link's
        prim), every link's (parent prim, child prim), the root named ``prim``; else None."""
        ref = self._prims.get(prim)
        if ref is None or ref.kind is not PrimKind.BODY:
            return None
        for info in self._robots.values():
            if ref.id == info.root_body_id and (prim == info.prim
                                                or prim.startswith(info.prim + "/")):
                root = info.root_body_id
                return tuple((prim if self._prims[p].id == root else p, c)
                             for p, c in info.link_tree)
        return None

    def robot_body_ids(self, robot_name: str) -> tuple[int, ...]:
        return self.robot(robot_name).body_ids

    def robot_front(self, name: str) -> Vec3:
        """The model's forward axis in its chassis frame ((-1,0,0) forklift, (1,0,0) tb3)."""
        return self.robot(name).robot_front

    def base_prim(self, name: str) -> str:
        """The chassis prim odometry reads (``<prim>/body`` or ``<prim>/base_footprint``)."""
        return self.robot(name).base_prim

    def default_base_frame(self, name: str) -> str:
        return self.robot(name).default_base_frame

    def link_prim(self, name: str, link: str) -> str:
        """Prim path of robot ``name``'s link ``link`` (``base_scan``, ``body``, ...)."""
        info = self.robot(name)
        try:
            return info.links[link]
        except KeyError:
            raise SimulationError(f"robot {name} has no link {link!r} "
                                  f"(links: {', '.join(sorted(info.links))})") from None

    def sensor_prim(self, name: str, kind: str) -> str:
        """Prim of robot ``name``'s mounted ``lidar``/``imu``/``camera``."""
        info = self.robot(name)
        try:
            return info.sensors[kind]
        except KeyError:
            raise SimulationError(f"robot {name} has no enabled {kind} sensor") from None

    def imu(self, name: str) -> ImuReading:
        """Current IMU sample of robot ``name`` (needs ``sensors.imu`` enabled)."""
        info = self.robot(name)
        if not info.imu_sensors:
            raise SimulationError(f"robot {name} has no enabled imu sensor")
        data = self._data.sensordata

        def read(kind: str) -> FloatArray:
            adr, dim = info.imu_sensors[kind]
            return np.array(data[adr:adr + dim], dtype=np.float64)

        return ImuReading(read("orientation"), read("gyro"), read("accelerometer"))

    # ------------------------------------------------------------------ joints
    def joint_names(self, robot_prim: str) -> tuple[str, ...]:
        """Plain names of the robot's hinge joints, in model order."""
        return tuple(self.robot_at(robot_prim).joints)

    def _joint(self, info: RobotInfo, joint: str) -> JointRef:
        try:
            return info.joints[joint]
        except KeyError:
            raise SimulationError(
                f"robot {info.name} ({info.prim}) has no joint {joint!r} "
                f"(joints: {', '.join(info.joints)})") from None

    def joint_state(self, robot_prim: str, joint: str) -> tuple[float, float]:
        """(qpos, qvel) of a robot's joint: radians and rad/s."""
        ref = self._joint(self.robot_at(robot_prim), joint)
        return float(self._data.qpos[ref.qposadr]), float(self._data.qvel[ref.dofadr])

    def apply_joint_commands(self, robot_prim: str, joint_names: Sequence[str],
                             positions: Sequence[float] | None = None,
                             velocities: Sequence[float] | None = None) -> None:
        """Set actuator targets, IsaacArticulationController style.

        For each named joint, a position-driven joint takes its ``positions`` entry and a
        velocity-driven joint its ``velocities`` entry; ``None`` or an empty sequence means
        "no command of that kind", and a NaN entry leaves that actuator as it is. Position
        targets are clamped to the actuator's range by MuJoCo. Everything is checked before
        anything is written.
        """
        info = self.robot_at(robot_prim)
        names = list(joint_names)
        pos = list(positions) if positions is not None and len(positions) else None
        vel = list(velocities) if velocities is not None and len(velocities) else None
        for label, values in (("positions", pos), ("velocities", vel)):
            if values is not None and len(values) != len(names):
                raise SimulationError(
                    f"robot {info.name}: {len(names)} joint names but {len(values)} {label}")
        writes: list[tuple[int, float]] = []
        for i, joint in enumerate(names):
            ref = self._joint(info, joint)
            if ref.actuator_id < 0:
                raise SimulationError(f"robot {info.name}: joint {joint!r} has no drive")
            values = pos if ref.mode is ActuatorMode.POSITION else vel
            if values is None:
                continue
            value = float(values[i])
            if math.isnan(value):
                continue
            if not math.isfinite(value):
                raise SimulationError(f"robot {info.name}: command {value} for joint {joint!r}")
            writes.append((ref.actuator_id, value))
        for act, value in writes:
            self._data.ctrl[act] = value
