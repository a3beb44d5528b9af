"""Range and inertial sensor nodes: the lidar (RTX helper and PhysX beam pair) and the IMU.

* ``RtxLidarHelper`` (Isaac's ``ROS2RtxLidarHelper``): casts a scan from the lidar named by
  its render product (``renderProductPath`` from CreateRenderProduct, whose ``cameraPrim``
  is the lidar prim) or directly by ``lidarPrim``, and publishes ``sensor_msgs/LaserScan``
  (``type = laser_scan``) or ``sensor_msgs/PointCloud2`` x, y, z float32 in the lidar frame
  (``type = point_cloud``).
* ``ReadLidarBeams`` + ``PublishLaserScan`` (the PhysX lidar pair of the seed): beams as
  arrays, angles in degrees as Isaac gives them, then a ``LaserScan``.
* ``ReadIMU`` + ``PublishImu``: specific force (m/s², +9.81 on z when level and still),
  angular velocity (rad/s) in the IMU frame and the IMU's orientation in the world frame.

Every node casts or samples only when execution reaches it, so a SimulationGate upstream sets
the rate. Lidar settings (beams, range limits, noise) come from the robot's
``sensors.lidar`` block of the scenario; the lidar prim must be one a robot mounts
(``<link prim>/lidar``). Noise is drawn from a generator seeded with ``ctx.seed`` and the
node's path (:func:`harness.sim.lidar.noise_rng`). Ranges follow REP-117 (see
:mod:`harness.sim.lidar`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from harness.bus.endpoints import Endpoint, TfEdge
from harness.geometry import quat_wxyz_conj, quat_wxyz_rotate, wxyz_to_xyzw
from harness.graph import Attr, NodeType, register
from harness.graph.errors import GraphError
from harness.graph.nodes.camera import point_cloud_message, render_products
from harness.graph.nodes.ros_bridge import (
    BRIDGE_INPUTS,
    EXEC_OUT,
    _Publisher,
    aliases,
    stamp_of,
    topic_of,
)
from harness.scenario.schema import LidarSpec
from harness.serde.messages import header, msg_type, quaternion_xyzw
from harness.sim.lidar import Lidar, LidarConfig, Scan, noise_rng

__all__ = [
    "LIDAR_TYPES",
    "PublishImu",
    "PublishLaserScan",
    "ReadIMU",
    "ReadLidarBeams",
    "RtxLidarHelper",
    "imu_message",
    "laser_scan_message",
    "lidar_spec_of",
]

LIDAR_TYPES = ("laser_scan", "point_cloud")
_UNKNOWN_COVARIANCE = -1.0  # sensor_msgs/Imu: covariance[0] = -1 means "no estimate"

_BRIDGE = BRIDGE_INPUTS
_EXEC_OUT = EXEC_OUT
# What ReadLidarBeams outputs and PublishLaserScan takes in, attribute for attribute (the
# PhysX pair is wired output → input by these names).
_BEAMS = (
        Attr("azimuthRange", "double[2]", (0.0, 0.0)),
        Attr("depthRange", "double[2]", (0.0, 0.0)),
        Attr("horizontalFov", "double", 0.0),
        Attr("horizontalResolution", "double", 0.0),
        Attr("intensitiesData", "float[]", ()),
        Attr("linearDepthData", "float[]", ()),
        Attr("numCols", "int", 0),
        Attr("numRows", "int", 0),
        Attr("rotationRate", "double", 0.0),
)


def _first(value: Any) -> str:
    if isinstance(value, str):
        return value
    return str(value[0]) if value else ""


def _mounted(world: Any, kind: str) -> dict[str, str]:
    """Sensor prim → robot name for every robot mounting a ``kind`` sensor."""
    out: dict[str, str] = {}
    for name in world.robot_names():
        prim = world.robot(name).sensors.get(kind)
        if prim is not None:
            out[prim] = name
    return out


def _sensor_robot(world: Any, prim: str, kind: str, where: str) -> str:
    """The robot mounting the ``kind`` sensor at ``prim`` (or at a child of link ``prim``)."""
    mounted = _mounted(world, kind)
    if prim in mounted:
        return mounted[prim]
    for sensor_prim, robot in mounted.items():
        if sensor_prim.rsplit("/", 1)[0] == prim:
            return robot
    known = ", ".join(sorted(mounted)) or f"none; enable robots[].sensors.{kind}"
    raise GraphError(f"{where}: {prim!r} is not a mounted {kind} (mounted: {known})")


def lidar_spec_of(world: Any, prim: str, where: str) -> tuple[str, LidarSpec]:
    """The lidar site prim and its scenario block for a lidar (or lidar link) prim."""
    robot = _sensor_robot(world, prim, "lidar", where)
    spec = world.scenario.robot(robot).sensors.lidar
    if spec is None:  # the world mounts only configured lidars
        raise GraphError(f"{where}: robot {robot} has no sensors.lidar block")
    return world.sensor_prim(robot, "lidar"), spec


def _render_product_prim(ctx: Any, path: str, where: str) -> str:
    """The prim a render product (from CreateRenderProduct) names, via the run's table."""
    return render_products(ctx).product(path, where).camera_prim


def _make_lidar(ctx: Any, node_path: str, prim: str) -> tuple[Lidar, LidarSpec]:
    """The lidar model of ``prim`` with its noise seeded from ``ctx.seed`` and the node path."""
    site, spec = lidar_spec_of(ctx.world, prim, node_path)
    config = LidarConfig.from_spec(spec)
    return Lidar(ctx.world, site, config, noise_rng(int(ctx.seed), node_path)), spec


# ----------------------------------------------------------------------------- messages

def laser_scan_message(ns: int, frame_id: str, ranges: Sequence[float] | np.ndarray,
                       intensities: Sequence[float] | np.ndarray, *, angle_min: float,
                       angle_increment: float, range_min: float, range_max: float,
                       scan_time: float = 0.0, time_increment: float = 0.0) -> Any:
    """A ``sensor_msgs/LaserScan``; ``angle_max = angle_min + (n - 1) * angle_increment``."""
    r = np.asarray(ranges, dtype=np.float32)
    inten = np.asarray(intensities, dtype=np.float32)
    return msg_type("sensor_msgs/msg/LaserScan")(
        header=header(ns, frame_id),
        angle_min=float(angle_min),
        angle_max=float(angle_min + max(len(r) - 1, 0) * angle_increment),
        angle_increment=float(angle_increment),
        time_increment=float(time_increment),
        scan_time=float(scan_time),
        range_min=float(range_min),
        range_max=float(range_max),
        ranges=r,
        intensities=inten,
    )


def imu_message(ns: int, frame_id: str, orientation_xyzw: Sequence[float] | None,
                angular_velocity: Sequence[float] | None,
                linear_acceleration: Sequence[float] | None) -> Any:
    """A ``sensor_msgs/Imu``; a part given as None is zeroed with covariance[0] = -1."""
    vec3 = msg_type("geometry_msgs/msg/Vector3")

    def cov(present: bool) -> np.ndarray:
        c = np.zeros(9, dtype=np.float64)
        if not present:
            c[0] = _UNKNOWN_COVARIANCE
        return c

    q = orientation_xyzw if orientation_xyzw is not None else (0.0, 0.0, 0.0, 1.0)
    w = angular_velocity if angular_velocity is not None else (0.0, 0.0, 0.0)
    a = linear_acceleration if linear_acceleration is not None else (0.0, 0.0, 0.0)
    return msg_type("sensor_msgs/msg/Imu")(
        header=header(ns, frame_id),
        orientation=quaternion_xyzw(q),
        orientation_covariance=cov(orientation_xyzw is not None),
        angular_velocity=vec3(x=float(w[0]), y=float(w[1]), z=float(w[2])),
        angular_velocity_covariance=cov(angular_velocity is not None),
        linear_acceleration=vec3(x=float(a[0]), y=float(a[1]), z=float(a[2])),
        linear_acceleration_covariance=cov(linear_acceleration is not None),
    )


def _scan_time(spec_fps: float) -> float:
    return 1.0 / spec_fps if spec_fps > 0 else 0.0


# ----------------------------------------------------------------------------- lidar nodes

def _lidar_msgtype(kind: str) -> str:
    return "sensor_msgs/msg/LaserScan" if kind == "laser_scan" else "sensor_msgs/msg/PointCloud2"


@register("srr.RtxLidarHelper", aliases=aliases("RtxLidarHelper"))
class RtxLidarHelper(NodeType):
    """Casts a scan and publishes it as LaserScan or PointCloud2 (``inputs:type``).

    The lidar is the ``cameraPrim`` of the render product at ``renderProductPath``, or
    ``lidarPrim`` when that is set. ``frameSkipCount`` skips that many executions between
    publications. All beams are cast at one instant, so ``time_increment`` is 0;
    ``scan_time`` is the configured period ``1 / fps``.
    """

    kind = "action"
    inputs = (
        *_BRIDGE,
        Attr("renderProductPath", "token", ""),
        Attr("lidarPrim", "target", ()),
        Attr("type", "token", "laser_scan"),
        Attr("topicName", "string", "scan"),
        Attr("frameId", "string", "sim_lidar"),
        Attr("timeStamp", "double", 0.0),
        Attr("frameSkipCount", "uint", 0),
        Attr("fullScan", "bool", True),
        Attr("enabled", "bool", True),
        Attr("resetSimulationTimeOnStop", "bool", False),
        Attr("showDebugView", "bool", False),
    )
    outputs = _EXEC_OUT

    def initialize(self, db: Any, ctx: Any) -> None:
        kind = str(db.inputs.type)
        if kind not in LIDAR_TYPES:
            raise GraphError(f"{db.node_path}.inputs:type: {kind!r} is not one of "
                             f"{', '.join(LIDAR_TYPES)}")
        prim = _first(db.inputs.lidarPrim)
        if not prim:
            product = str(db.inputs.renderProductPath)
            if not product:
                raise GraphError(f"{db.node_path}: connect inputs:renderProductPath (from "
                                 "CreateRenderProduct) or set inputs:lidarPrim")
            prim = _render_product_prim(ctx, product, db.node_path)
        self._type = kind
        self._lidar, self._spec = _make_lidar(ctx, db.node_path, prim)
        self._pub = ctx.bus.advertise(topic_of(db), _lidar_msgtype(kind), None)
        self._count = 0

    def endpoints(self, value: Callable[[str], Any]) -> Sequence[Endpoint | TfEdge]:
        kind = str(value("type"))
        if kind not in LIDAR_TYPES:
            raise GraphError(f"type {kind!r} is not one of {', '.join(LIDAR_TYPES)}")
        return (Endpoint("pub", str(value("topicName")), _lidar_msgtype(kind),
                         str(value("nodeNamespace"))),)

    def compute(self, db: Any, ctx: Any) -> bool:
        if not db.inputs.enabled:
            return True
        count = self._count
        self._count += 1
        if count % (int(db.inputs.frameSkipCount) + 1):
            return True
        scan = self._lidar.scan()
        ns, frame = stamp_of(db, ctx), str(db.inputs.frameId)
        if self._type == "laser_scan":
            self._pub.publish(_scan_msg(ns, frame, scan, self._spec))
        else:
            self._pub.publish(point_cloud_message(ns, frame, scan.points()))
        return True

    def reset(self) -> None:
        self._count = 0


def _scan_msg(ns: int, frame: str, scan: Scan, spec: LidarSpec) -> Any:
    cfg = scan.config
    return laser_scan_message(ns, frame, scan.ranges, scan.intensities,
                              angle_min=cfg.angle_min, angle_increment=cfg.angle_increment,
                              range_min=cfg.range_min, range_max=cfg.range_max,
                              scan_time=_scan_time(spec.fps))


@register("srr.ReadLidarBeams", aliases=(
    "omni.isaac.range_sensor.IsaacReadLidarBeams",
    "isaacsim.sensors.physx.IsaacReadLidarBeams",
))
class ReadLidarBeams(NodeType):
    """One scan of ``lidarPrim`` as beam arrays (PhysX lidar style, one row).

    Angles are in degrees (``azimuthRange`` = first and last beam, ``horizontalFov`` = 360,
    ``horizontalResolution`` = the increment), ``depthRange`` is (range_min, range_max) in
    metres, ``linearDepthData`` the ranges with REP-117 ``±inf``, ``rotationRate`` the scan
    rate in Hz (``sensors.lidar.fps``).
    """

    kind = "action"
    inputs = (Attr("execIn", "execution"), Attr("lidarPrim", "target", ()))
    outputs = (*_EXEC_OUT, *_BEAMS)

    def initialize(self, db: Any, ctx: Any) -> None:
        prim = _first(db.inputs.lidarPrim)
        if not prim:
            raise GraphError(f"{db.node_path}.inputs:lidarPrim: not set")
        self._lidar, self._spec = _make_lidar(ctx, db.node_path, prim)

    def compute(self, db: Any, ctx: Any) -> bool:
        scan = self._lidar.scan()
        cfg = scan.config
        o = db.outputs
        o.azimuthRange = (math.degrees(cfg.angle_min), math.degrees(cfg.angle_max))
        o.depthRange = (cfg.range_min, cfg.range_max)
        o.horizontalFov = 360.0
        o.horizontalResolution = math.degrees(cfg.angle_increment)
        o.intensitiesData = scan.intensities.tolist()
        o.linearDepthData = scan.ranges.tolist()
        o.numCols = cfg.beams
        o.numRows = 1
        o.rotationRate = float(self._spec.fps)
        return True


@register("srr.PublishLaserScan", aliases=aliases("PublishLaserScan"))
class PublishLaserScan(_Publisher):
    """``sensor_msgs/LaserScan`` from ReadLidarBeams' outputs (angles in degrees)."""

    inputs = (
        *_BRIDGE,
        Attr("topicName", "string", "scan"),
        Attr("frameId", "string", "sim_lidar"),
        Attr("timeStamp", "double", 0.0),
        *_BEAMS,
    )
    outputs = _EXEC_OUT
    msgtype = "sensor_msgs/msg/LaserScan"

    def compute(self, db: Any, ctx: Any) -> bool:
        i = db.inputs
        cols, rows = int(i.numCols), int(i.numRows)
        depth = i.linearDepthData
        if rows != 1:
            raise GraphError(f"{db.node_path}.inputs:numRows: a LaserScan needs one row, "
                             f"got {rows}")
        if len(depth) != cols:
            raise GraphError(f"{db.node_path}.inputs:linearDepthData: {len(depth)} values "
                             f"for numCols={cols}")
        intensities = i.intensitiesData
        if intensities and len(intensities) != cols:
            raise GraphError(f"{db.node_path}.inputs:intensitiesData: {len(intensities)} "
                             f"values for numCols={cols}")
        lo, hi = i.depthRange
        self._pub.publish(laser_scan_message(
            stamp_of(db, ctx), str(i.frameId), depth, intensities,
            angle_min=math.radians(i.azimuthRange[0]),
            angle_increment=math.radians(i.horizontalResolution),
            range_min=lo, range_max=hi, scan_time=_scan_time(float(i.rotationRate))))
        return True


# ----------------------------------------------------------------------------- IMU nodes

@register("srr.ReadIMU", aliases=(
    "omni.isaac.sensor.IsaacReadIMU",
    "isaacsim.sensors.physics.IsaacReadIMU",
))
class ReadIMU(NodeType):
    """One IMU sample of ``imuPrim`` (the IMU site, or the link carrying it).

    ``linAcc`` is the accelerometer's specific force in the IMU frame (+9.81 m/s² on z when
    level and still); with ``readGravity`` False gravity is removed (0 at rest). ``angVel``
    is the gyro (rad/s, IMU frame), ``orientation`` the IMU frame in the world (IJKR x, y, z,
    w), ``sensorTime`` the simulation time in seconds.
    """

    kind = "action"
    inputs = (
        Attr("execIn", "execution"),
        Attr("imuPrim", "target", ()),
        Attr("readGravity", "bool", True),
        Attr("useLatestData", "bool", False),
    )
    outputs = (
        *_EXEC_OUT,
        Attr("linAcc", "double[3]", (0.0, 0.0, 0.0)),
        Attr("angVel", "double[3]", (0.0, 0.0, 0.0)),
        Attr("orientation", "quatd[4]", (0.0, 0.0, 0.0, 1.0)),
        Attr("sensorTime", "double", 0.0),
    )

    def initialize(self, db: Any, ctx: Any) -> None:
        prim = _first(db.inputs.imuPrim)
        if not prim:
            raise GraphError(f"{db.node_path}.inputs:imuPrim: not set")
        self._robot = _sensor_robot(ctx.world, prim, "imu", db.node_path)

    def compute(self, db: Any, ctx: Any) -> bool:
        reading = ctx.world.imu(self._robot)
        acc = np.asarray(reading.linear_acceleration, dtype=np.float64)
        if not db.inputs.readGravity:
            gravity = [float(v) for v in ctx.world.model.opt.gravity]
            to_imu = quat_wxyz_conj([float(v) for v in reading.orientation])
            acc = acc + quat_wxyz_rotate(list(to_imu), gravity)
        db.outputs.linAcc = tuple(float(v) for v in acc)
        db.outputs.angVel = tuple(float(v) for v in reading.angular_velocity)
        db.outputs.orientation = tuple(float(v) for v in wxyz_to_xyzw(reading.orientation))
        db.outputs.sensorTime = int(ctx.time_ns) / 1e9
        return True


@register("srr.PublishImu", aliases=aliases("PublishImu"))
class PublishImu(_Publisher):
    """``sensor_msgs/Imu`` from ReadIMU's outputs; a part switched off by its
    ``publish*`` flag is zeroed with covariance[0] = -1 (the message's "no estimate")."""

    inputs = (
        *_BRIDGE,
        Attr("topicName", "string", "imu"),
        Attr("frameId", "string", "sim_imu"),
        Attr("timeStamp", "double", 0.0),
        Attr("linearAcceleration", "double[3]", (0.0, 0.0, 0.0)),
        Attr("angularVelocity", "double[3]", (0.0, 0.0, 0.0)),
        Attr("orientation", "quatd[4]", (0.0, 0.0, 0.0, 1.0)),
        Attr("publishLinearAcceleration", "bool", True),
        Attr("publishAngularVelocity", "bool", True),
        Attr("publishOrientation", "bool", True),
    )
    outputs = _EXEC_OUT
    msgtype = "sensor_msgs/msg/Imu"

    def compute(self, db: Any, ctx: Any) -> bool:
        i = db.inputs
        self._pub.publish(imu_message(
            stamp_of(db, ctx), str(i.frameId),
            tuple(i.orientation) if i.publishOrientation else None,
            tuple(i.angularVelocity) if i.publishAngularVelocity else None,
            tuple(i.linearAcceleration) if i.publishLinearAcceleration else None))
        return True
