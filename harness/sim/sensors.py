"""Attach points for robot-mounted sensors (``robots[].sensors``), added at build time.

Each enabled sensor gets an addressable prim under its link's prim:

* lidar  → site ``<link prim>/lidar`` (rays are cast from it; +X is the 0° beam, +Z up)
* imu    → site ``<link prim>/imu`` plus MuJoCo ``framequat``/``gyro``/``accelerometer``
  sensors on it (so ``mj_step`` computes body accelerations)
* camera → MuJoCo camera ``<link prim>/camera`` looking along the mount's +X (world
  convention)

The mount is the link's origin, or a ``site`` of a model file (on the site's body, at the
site's pose), moved by the sensor's ``offset`` (position, then roll/pitch/yaw, in the link's
or the site's frame). A sensor off its link's origin must publish in a frame of its own
(``frame_id`` other than the link's), which the sensor graphs place under the link.
A sensor on a link or site the robot does not have is refused with the scenario field named.
"""

from __future__ import annotations

import types
from collections.abc import Mapping
from dataclasses import dataclass

import mujoco
import numpy as np

from harness.scenario.schema import ImuSpec, LidarSpec, RobotCameraSpec, RobotSpec
from harness.sim.cameras import add_mounted_camera
from harness.sim.mjquat import quat_wxyz_from_rpy_deg_mj, quat_wxyz_mul_mj, quat_wxyz_rotate_mj
from harness.sim.prims import PrimKind, PrimTable
from harness.sim.robots.common import RobotBuild
from harness.sim.robots.paths import ModelSource

__all__ = ["IMU_SENSORS", "MountedSensors", "add_robot_sensors"]

IMU_SENSORS = ("orientation", "gyro", "accelerometer")


@dataclass(frozen=True)
class MountedSensors:
    """Prims of a robot's mounted sensors (kind → prim) and MuJoCo IMU sensor names."""

    prims: Mapping[str, str]
    imu_sensors: Mapping[str, str]


@dataclass(frozen=True)
class _Mount:
    """Where a sensor sits: the link (name, prim, MuJoCo body) and its pose in the link."""

    link: str
    prim: str
    body: mujoco.MjsBody
    pos: list[float]
    quat: list[float]  # w, x, y, z


def _mount(spec: mujoco.MjSpec, robot: RobotSpec, build: RobotBuild, kind: str,
           block: RobotCameraSpec | LidarSpec | ImuSpec, src: ModelSource) -> _Mount:
    """The mount of ``robot.sensors.<kind>``: its link or site, moved by its offset."""
    field = f"sensors.{kind}"
    pos, quat = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])
    if block.site is not None:
        site = spec.site(f"{robot.name}/{block.site}") if robot.model_file is not None else None
        if site is None:
            where = (f"{robot.model_file.path} has no site {block.site!r}"
                     if robot.model_file is not None else
                     f"{build.model} has no sites (sites are named in model files)")
            raise src.error(f"{field}.site", where)
        body_name = site.parent.name
        link = next(k for k, (_, b) in build.links.items() if b == body_name)
        pos, quat = np.asarray(site.pos, dtype=float), np.asarray(site.quat, dtype=float)
    elif block.link not in build.links:
        raise src.error(f"{field}.link", f"{build.model} has no link {block.link!r} (links: "
                        f"{', '.join(sorted(build.links))})")
    else:
        link = block.link
    off = block.offset
    pos = pos + quat_wxyz_rotate_mj(quat, off.position)
    quat = quat_wxyz_mul_mj(quat, quat_wxyz_from_rpy_deg_mj(off.rpy_deg))
    off_origin = bool(np.any(np.abs(pos) > 1e-12) or abs(abs(float(quat[0])) - 1.0) > 1e-12)
    if off_origin and block.frame_id == link:
        raise src.error(f"{field}.frame_id", f"the {kind} sits off the origin of link {link!r} "
                        f"(its {'site' if block.site else 'offset'}), so its data needs a frame "
                        f"of its own: set frame_id to another name (published as {link} → "
                        "frame_id)")
    prim, body_name = build.links[link]
    body = spec.body(body_name)
    assert body is not None, body_name
    return _Mount(link, prim, body, [float(v) for v in pos], [float(v) for v in quat])


def add_robot_sensors(spec: mujoco.MjSpec, robot: RobotSpec, build: RobotBuild,
                      prims: PrimTable, src: ModelSource) -> MountedSensors:
    """Add the attach points of ``robot.sensors`` (enabled ones) to the robot's links."""
    n = robot.name
    out: dict[str, str] = {}
    imu_names: dict[str, str] = {}
    lidar = robot.sensors.lidar
    if lidar is not None and lidar.enabled:
        m = _mount(spec, robot, build, "lidar", lidar, src)
        m.body.add_site(name=f"{n}/{m.link}/lidar", size=[0.005, 0, 0], pos=m.pos, quat=m.quat,
                        group=4, rgba=[1, 0, 0, 0.5])
        out["lidar"] = prims.declare(f"{m.prim}/lidar", PrimKind.SITE, f"{n}/{m.link}/lidar")
    imu = robot.sensors.imu
    if imu is not None and imu.enabled:
        m = _mount(spec, robot, build, "imu", imu, src)
        site = f"{n}/{m.link}/imu"
        m.body.add_site(name=site, size=[0.005, 0, 0], pos=m.pos, quat=m.quat, group=4,
                        rgba=[0, 1, 0, 0.5])
        out["imu"] = prims.declare(f"{m.prim}/imu", PrimKind.SITE, site)
        for kind, stype in (("orientation", mujoco.mjtSensor.mjSENS_FRAMEQUAT),
                            ("gyro", mujoco.mjtSensor.mjSENS_GYRO),
                            ("accelerometer", mujoco.mjtSensor.mjSENS_ACCELEROMETER)):
            name = f"{n}/imu/{kind}"
            spec.add_sensor(name=name, type=stype, objtype=mujoco.mjtObj.mjOBJ_SITE,
                            objname=site)
            imu_names[kind] = name
    camera = robot.sensors.camera
    if camera is not None and camera.enabled:
        m = _mount(spec, robot, build, "camera", camera, src)
        add_mounted_camera(m.body, f"{n}/{m.link}/camera", camera.fovy_deg,
                           camera.resolution, f"{m.prim}/camera", prims, m.pos, m.quat)
        out["camera"] = f"{m.prim}/camera"
    return MountedSensors(types.MappingProxyType(out), types.MappingProxyType(imu_names))
