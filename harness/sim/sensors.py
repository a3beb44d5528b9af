"""Attach points for robot-mounted sensors (``robots[].sensors``), added at build time.

Each enabled sensor gets an addressable prim under its link's prim:

* lidar  → site ``<link prim>/lidar`` (rays are cast from it; +X is the 0° beam, +Z up)
* imu    → site ``<link prim>/imu`` plus MuJoCo ``framequat``/``gyro``/``accelerometer``
  sensors on it (so ``mj_step`` computes body accelerations)
* camera → MuJoCo camera ``<link prim>/camera`` looking along the link's +X (world convention)

A sensor on a link the robot does not have is refused with the scenario field named.
"""

from __future__ import annotations

import types
from collections.abc import Mapping
from dataclasses import dataclass

import mujoco

from harness.errors import SimulationError
from harness.scenario.schema import RobotSpec
from harness.sim.cameras import add_mounted_camera
from harness.sim.prims import PrimKind, PrimTable
from harness.sim.robots.common import RobotBuild

__all__ = ["IMU_SENSORS", "MountedSensors", "add_robot_sensors"]

IMU_SENSORS = ("orientation", "gyro", "accelerometer")


@dataclass(frozen=True)
class MountedSensors:
    """Prims of a robot's mounted sensors (kind → prim) and MuJoCo IMU sensor names."""

    prims: Mapping[str, str]
    imu_sensors: Mapping[str, str]


def _link_body(spec: mujoco.MjSpec, build: RobotBuild, link: str,
               field: str) -> tuple[str, mujoco.MjsBody]:
    if link not in build.links:
        raise SimulationError(
            f"robots.{build.name}.{field}: {build.model} has no link {link!r} "
            f"(links: {', '.join(sorted(build.links))})")
    prim, body_name = build.links[link]
    body = spec.body(body_name)
    if body is None:
        raise SimulationError(f"robots.{build.name}.{field}: body {body_name} missing from spec")
    return prim, body


def add_robot_sensors(spec: mujoco.MjSpec, robot: RobotSpec, build: RobotBuild,
                      prims: PrimTable) -> MountedSensors:
    """Add the attach points of ``robot.sensors`` (enabled ones) to the robot's links."""
    n = robot.name
    out: dict[str, str] = {}
    imu_names: dict[str, str] = {}
    lidar = robot.sensors.lidar
    if lidar is not None and lidar.enabled:
        prim, body = _link_body(spec, build, lidar.link, "sensors.lidar.link")
        body.add_site(name=f"{n}/{lidar.link}/lidar", size=[0.005, 0, 0],
                      group=4, rgba=[1, 0, 0, 0.5])
        out["lidar"] = prims.declare(f"{prim}/lidar", PrimKind.SITE, f"{n}/{lidar.link}/lidar")
    imu = robot.sensors.imu
    if imu is not None and imu.enabled:
        prim, body = _link_body(spec, build, imu.link, "sensors.imu.link")
        site = f"{n}/{imu.link}/imu"
        body.add_site(name=site, size=[0.005, 0, 0], group=4, rgba=[0, 1, 0, 0.5])
        out["imu"] = prims.declare(f"{prim}/imu", PrimKind.SITE, site)
        for kind, stype in (("orientation", mujoco.mjtSensor.mjSENS_FRAMEQUAT),
                            ("gyro", mujoco.mjtSensor.mjSENS_GYRO),
                            ("accelerometer", mujoco.mjtSensor.mjSENS_ACCELEROMETER)):
            name = f"{n}/imu/{kind}"
            spec.add_sensor(name=name, type=stype, objtype=mujoco.mjtObj.mjOBJ_SITE,
                            objname=site)
            imu_names[kind] = name
    camera = robot.sensors.camera
    if camera is not None and camera.enabled:
        prim, body = _link_body(spec, build, camera.link, "sensors.camera.link")
        add_mounted_camera(body, f"{n}/{camera.link}/camera", camera.fovy_deg,
                           camera.resolution, f"{prim}/camera", prims)
        out["camera"] = f"{prim}/camera"
    return MountedSensors(types.MappingProxyType(out), types.MappingProxyType(imu_names))
