"""The scenario's cross-field rules, which the type hints cannot express (unique names, valid
ROS names and prims, sensor rates the tick can give, output settings that work together, ...),
checked on the typed :class:`~harness.scenario.schema.Scenario`; each failure is one line naming
the file and the field (:meth:`harness.validation.Validator.fail`)."""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from harness.errors import SrrError
from harness.geometry import axis_label, cross_2d, side_of_line, signed_area
from harness.scenario.resolve import graph_name
from harness.scenario.schema import (
    BUILTIN_JOINTS,
    FORMAT_VERSION,
    CameraRecordSpec,
    ControlScoring,
    DiffDriveControl,
    ForkliftControl,
    H264Spec,
    ModelFile,
    RobotSpec,
    SafetyScoring,
    Scenario,
    WorldSpec,
    gated_rate,
)
from harness.scenario.specs import ZONES, SignalContext, SpecError, parse_formula
from harness.validation import Validator, close_match, join

__all__ = [
    "H264_PRESETS",
    "RATE_TOLERANCE",
    "check_semantics",
    "degree_warnings",
    "polygon_crossing",
    "rate_warnings",
    "robot_warnings",
    "sensor_rates",
    "spec_context",
    "tripwire_warnings",
    "worker_warnings",
]


def _orient(p: Sequence[float], q: Sequence[float], r: Sequence[float]) -> int:
    """The turn p → q → r: 1 counter-clockwise, -1 clockwise, 0 on one line."""
    cross = cross_2d(p, q, r)
    return (cross > 0) - (cross < 0)


def _on_segment(p: Sequence[float], q: Sequence[float], r: Sequence[float]) -> bool:
    """``r``, on the line through ``p`` and ``q``, lies within the segment p–q."""
    return (min(p[0], q[0]) <= r[0] <= max(p[0], q[0])
            and min(p[1], q[1]) <= r[1] <= max(p[1], q[1]))


def _segments_meet(p1: Sequence[float], p2: Sequence[float], q1: Sequence[float],
                   q2: Sequence[float]) -> bool:
    """The closed segments p1–p2 and q1–q2 share a point (they cross, or one touches the
    other)."""
    o1, o2 = _orient(p1, p2, q1), _orient(p1, p2, q2)
    o3, o4 = _orient(q1, q2, p1), _orient(q1, q2, p2)
    if o1 != o2 and o3 != o4 and 0 not in (o1, o2, o3, o4):
        return True
    return ((o1 == 0 and _on_segment(p1, p2, q1)) or (o2 == 0 and _on_segment(p1, p2, q2))
            or (o3 == 0 and _on_segment(q1, q2, p1)) or (o4 == 0 and _on_segment(q1, q2, p2)))


def polygon_crossing(points: Sequence[Sequence[float]]
                     ) -> tuple[tuple[int, int], tuple[int, int]] | None:
    """The first two edges of the closed polygon ``points`` that are not neighbours and yet
    meet (it crosses or touches itself: a bow-tie), each as the indices of the points it
    runs between (the last edge runs back to point 0); None for a simple polygon. A point
    repeated right after itself makes no edge."""
    ring = [i for i in range(len(points)) if points[i] != points[i - 1]] \
        if len(points) > 1 else []
    n = len(ring)
    edges = [(ring[k], ring[(k + 1) % n]) for k in range(n)]
    for a in range(n):
        for b in range(a + 2, n):
            if a == 0 and b == n - 1:  # the last edge closes onto the first: neighbours
                continue
            (p1, p2), (q1, q2) = edges[a], edges[b]
            if _segments_meet(points[p1], points[p2], points[q1], points[q2]):
                return edges[a], edges[b]
    return None


def _check_polygon(v: Validator, field: str, points: Sequence[Sequence[float]]) -> None:
    """A polygon (given: none is fine) has three points or more, does not cross itself and
    has an area."""
    if not points:
        return
    if len(points) < 3:
        v.fail(field, f"a polygon needs at least three points, got {len(points)}")
    crossing = polygon_crossing(points)
    if crossing is not None:
        (i, i2), (j, j2) = crossing
        v.fail(field, f"the polygon crosses itself: its edge from point {i} "
               f"{list(points[i])} to point {i2} {list(points[i2])} meets its edge from point "
               f"{j} {list(points[j])} to point {j2} {list(points[j2])}; list the points in "
               "order around the polygon")
    if abs(2 * signed_area(points)) < 1e-9:
        v.fail(field, "the polygon has zero area")


def check_semantics(sc: Scenario, v: Validator) -> None:
    """Cross-field rules the type hints cannot express."""
    if sc.format_version != FORMAT_VERSION:
        v.fail("format_version", f"unsupported version {sc.format_version} (this srr reads "
               f"{FORMAT_VERSION})")
    _check_name(v, "name", sc.name)
    robots: dict[str, int] = {}
    for i, robot in enumerate(sc.robots):
        _check_unique_name(v, robots, "robots", "robot", i, robot.name)
    for name, route in sc.routes.items():
        if len(route.waypoints) < 2:
            v.fail(f"routes.{name}.waypoints", "a route needs at least two waypoints")
    _check_workers_and_zones(sc, v)
    _check_names(v, sc, "")
    _check_world(sc, v)
    _check_robots(sc, v)
    _check_robot_cameras(sc, v)
    _check_cameras(sc, v)
    _check_suts(sc, v)
    _check_graphs(sc, v)
    _check_control_scoring(sc, v)
    _check_tolerances(sc, v)
    _check_specs(sc, v)
    _check_output(sc, v)
    _check_rates(sc, v)


#: How far (relative) the rate a sensor really gets may be from the rate it asks for before
#: the scenario is refused; closer, ``srr validate`` warns (:func:`rate_warnings`).
RATE_TOLERANCE = 0.10


def sensor_rates(sc: Scenario) -> list[tuple[str, float, float]]:
    """(field, rate asked for, rate it really gets) of every sensor a built-in graph
    publishes behind a simulation gate: a sensor publishes every ``gate_step``-th tick, so
    only ``tick_hz / n`` is possible (:func:`~harness.scenario.schema.gated_rate`)."""
    hz = sc.physics.tick_hz
    out: list[tuple[str, float, float]] = []
    for i, robot in enumerate(sc.robots):
        if not robot.enabled:
            continue
        s = robot.sensors
        for kind, spec in (("camera", s.camera), ("lidar", s.lidar), ("imu", s.imu)):
            if spec is not None and spec.enabled and spec.graph:
                out.append((f"robots[{i}].sensors.{kind}.fps", spec.fps,
                            gated_rate(hz, spec.fps)))
    for i, cam in enumerate(sc.cameras):
        if cam.enabled and cam.outputs:
            out.append((f"cameras[{i}].fps", cam.fps, gated_rate(hz, cam.fps)))
    if sc.rtsp.enabled and any(c.enabled and c.port is not None for c in sc.cameras):
        out.append(("rtsp.fps", sc.rtsp.fps, gated_rate(hz, sc.rtsp.fps)))
    return out


def _possible_rates(tick_hz: int) -> str:
    return ", ".join(f"{tick_hz / n:.4g}" for n in range(1, 6))


def _rate_message(sc: Scenario, asked: float, real: float) -> str:
    hz = sc.physics.tick_hz
    return (f"{asked:g} Hz cannot be given on the {hz} Hz tick (physics.tick_hz): a sensor "
            f"publishes every n-th tick, so it would publish at {real:.4g} Hz")


def _check_rates(sc: Scenario, v: Validator) -> None:
    """Refuse a sensor rate the tick cannot give within :data:`RATE_TOLERANCE`."""
    for field, asked, real in sensor_rates(sc):
        if abs(real - asked) > RATE_TOLERANCE * asked:
            v.fail(field, f"{_rate_message(sc, asked, real)}; ask for tick_hz / n "
                   f"({_possible_rates(sc.physics.tick_hz)}, ... Hz) or change "
                   "physics.tick_hz")


def rate_warnings(sc: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """One warning per sensor whose real rate differs (by less than
    :data:`RATE_TOLERANCE`; more is refused) from the rate it asks for."""
    return tuple(f"{sc.file_for(field, source)}: {field}: {_rate_message(sc, asked, real)}"
                 for field, asked, real in sensor_rates(sc) if abs(real - asked) > 1e-9)


def robot_warnings(sc: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """Warnings about robots that run, but not as their block reads: a built-in model
    spawned with a height (it stands on the floor; only a model file's robot is placed at
    its ``z``), and a robot camera stamped in its link's own frame (``frame_id`` equal to
    ``link``): its images are then in the link's axes (+X forward), not the optical frame
    (+Z forward, +X right, +Y down) that ROS image consumers assume and that srr adds under
    the link for any other ``frame_id``."""
    out = []
    for i, robot in enumerate(sc.robots):
        z = robot.spawn.position[2]
        if robot.enabled and robot.model_file is None and z != 0:
            field = f"robots[{i}].spawn.position"
            out.append(f"{sc.file_for(field, source)}: {field}: z {z:g} is not used: the "
                       f"built-in model {robot.model_name!r} stands on the floor (only a "
                       "robot from a model file is placed at its z)")
        cam = robot.sensors.camera
        if robot.enabled and cam is not None and cam.enabled and cam.graph \
                and cam.frame_id == cam.link:
            field = f"robots[{i}].sensors.camera.frame_id"
            out.append(f"{sc.file_for(field, source)}: {field}: {cam.frame_id!r} is the "
                       "camera link's own frame (+X forward), so its images are not in an "
                       "optical frame (+Z forward) as ROS image consumers assume; give another "
                       f"name (e.g. {cam.link}_optical) and srr publishes that optical frame "
                       "under the link")
    return tuple(out)


#: Radians a value of a ``*_deg`` field is taken for when it lies within
#: :data:`RADIAN_TOLERANCE` of one of them: pi/2, pi, 2 pi and their negatives.
RADIAN_LOOKALIKES = tuple(s * k * math.pi for k in (0.5, 1.0, 2.0) for s in (1, -1))
RADIAN_TOLERANCE = 0.01


def _degree_fields(obj: Any, path: str) -> list[tuple[str, str, float]]:
    """(field path, field name, value) of every number in a ``*_deg`` field of ``obj`` (a
    scenario block, walked like :func:`_check_names`; a vector field gives one entry per
    component, ``rpy_deg[2]``). Disabled robots and cameras are left out."""
    if isinstance(obj, tuple):
        return [hit for i, item in enumerate(obj) for hit in _degree_fields(item, f"{path}[{i}]")]
    if not dataclasses.is_dataclass(obj) or getattr(obj, "enabled", True) is False:
        return []
    out: list[tuple[str, str, float]] = []
    for f in dataclasses.fields(obj):
        value, sub = getattr(obj, f.name), join(path, f.name)
        if not f.name.endswith("_deg"):
            out += _degree_fields(value, sub)
        elif isinstance(value, tuple):
            out += [(f"{sub}[{i}]", f.name, float(v)) for i, v in enumerate(value)
                    if isinstance(v, int | float) and not isinstance(v, bool)]
        elif isinstance(value, int | float) and not isinstance(value, bool):
            out.append((sub, f.name, float(value)))
    return out


def _looks_like_radians(name: str, value: float) -> bool:
    """Whether a ``*_deg`` value reads as radians: near +-pi/2, +-pi or +-2 pi; a field of
    view (``fovy_deg``) also below pi, as no lens sees 180 degrees or more and a value that
    small in degrees is a telescope's, while 0.5-3 is what a radian field of view reads (URDF,
    SDF and MuJoCo's fovy in radians: 1.047 is 60 degrees)."""
    if name == "fovy_deg" and value < math.pi:
        return True
    return any(abs(value - r) <= RADIAN_TOLERANCE for r in RADIAN_LOOKALIKES)


def degree_warnings(sc: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """One warning per value of a ``*_deg`` field (every one the schema has: poses'
    ``rpy_deg``, shelves' and the dock's ``yaw_deg``, ``fovy_deg``, ``max_steer_deg``, ...)
    that looks like radians (:func:`_looks_like_radians`): ``rpy_deg: [0, 0, 3.14159]``
    turns the robot by 3 degrees, not 180. A warning, not an error: 3.14 degrees may be
    meant."""
    out = []
    for field, name, value in _degree_fields(sc, ""):
        if not _looks_like_radians(name, value):
            continue
        deg = math.degrees(value)
        write = f"{deg:.3g}"
        out.append(f"{sc.file_for(field, source)}: {field}: {value:g} looks like radians: "
                   f"{value:g} rad is {write}°; this field is in degrees, write {write}")
    return tuple(out)


def worker_warnings(sc: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """Warnings about workers that never walk: an enabled worker whose ``start_delay`` is not
    before the end of the run stands at its first waypoint the whole run. A warning, not an
    error: a sweep over ``start_delay`` or ``duration`` may reach such points on purpose."""
    out = []
    for i, worker in enumerate(sc.workers):
        if worker.enabled and worker.start_delay >= sc.duration:
            field = f"workers[{i}].start_delay"
            out.append(f"{sc.file_for(field, source)}: {field}: {worker.start_delay:g} s is not "
                       f"before the end of the run (duration {sc.duration:g} s): worker "
                       f"{sc.worker_name(i)!r} stands at its first waypoint the whole run")
    return tuple(out)


#: The safety monitor's plugin: its ``params.tripwire`` (two points) and ``params.inside``
#: replace the scenario's ``zones.trailer_tripwire``.
SAFETY_MONITOR = "harness.sut.safety_monitor:SafetyMonitor"


def tripwire_warnings(sc: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """A warning per trailer tripwire (``zones.trailer_tripwire``, or a safety monitor's own
    ``params.tripwire``) that no robot ever crosses from outside because every enabled
    robot's spawn and every route waypoint already lie on its ``inside`` side (by the
    safety monitor's own test, :func:`~harness.geometry.side_of_line`): the forklift then
    counts as in the trailer from the first tick, and the monitor mutes from the start
    whenever no worker is in the loading ROI. That is what an ``inside`` given as the wrong
    side does (the whole room past the tripwire); a robot that starts inside and drives out,
    or one that drives in, is not warned about. A warning, not an error: a scene may start
    with the forklift parked in the trailer on purpose."""
    points = [(r.spawn.position[0], r.spawn.position[1]) for r in sc.robots if r.enabled]
    if not points:
        return ()
    points += [(x, y) for route in sc.routes.values() for x, y in route.waypoints]
    wires: list[tuple[str, Sequence[float], Sequence[float], str]] = []
    if sc.zones.trailer_tripwire is not None:
        w = sc.zones.trailer_tripwire
        wires.append(("zones.trailer_tripwire.inside", w.a, w.b, w.inside))
    for i, sut in enumerate(sc.systems_under_test):
        wire = sut.params.get("tripwire")
        if sut.enabled and sut.plugin == SAFETY_MONITOR and isinstance(wire, list | tuple) \
                and len(wire) == 2:
            try:
                ends = [(float(p[0]), float(p[1])) for p in wire]
            except (TypeError, ValueError, IndexError, KeyError):
                continue  # the monitor refuses it when the run sets it up
            wires.append((f"systems_under_test[{i}].params.inside", ends[0], ends[1],
                          str(sut.params.get("inside") or "left")))
    out = []
    for field, a, b, inside in wires:
        dx, dy = b[0] - a[0], b[1] - a[1]
        if (dx, dy) == (0, 0) or inside not in ("left", "right"):
            continue  # refused elsewhere
        if all(side_of_line(x, y, a, b) == inside for x, y in points):
            normal = (-dy, dx) if inside == "left" else (dy, -dx)
            out.append(
                f"{sc.file_for(field, source)}: {field}: {inside!r} puts every robot's spawn "
                f"and every route waypoint past the tripwire a {[*a]} → b {[*b]} ({inside} "
                f"of a → b, seen from above, is toward {axis_label(normal)}): the robot is in "
                "the trailer from the first tick and never crosses in, so the safety monitor "
                "mutes from the start unless a worker is in the loading ROI; if the trailer "
                f"is on the other side, inside: {'right' if inside == 'left' else 'left'}")
    return tuple(out)


def _check_output(sc: Scenario, v: Validator) -> None:
    """``output:`` values that cannot work together (what the graphs imply is checked once
    they are built: :mod:`harness.output`)."""
    out = sc.output
    if isinstance(out.ros, bool):  # YAML true == 1 to Literal[1, 2]
        v.fail("output.ros", f"expected one of 1, 2, got {out.ros!r}")
    if out.format == "bag" and out.ros == 2:
        v.fail("output.format", "bag is a ROS 1 bag; ROS 2 output is a rosbag2 directory "
               "(format: mcap)")
    ros1 = out.ros == 1 or out.format == "bag"
    if out.format == "bag" and sc.recording.compression == "zstd":
        v.fail("recording.compression", "a ROS 1 bag compresses its chunks with lz4 (or "
               "bz2), not zstd: use lz4 or none, or output.format: mcap")
    if ros1 and sc.ros2.enabled:
        v.fail("ros2.enabled", "the live ROS 2 bridge needs ROS 2 output, and this scenario "
               "records ROS 1 (output)")


_PROCEDURAL_FIELDS = ("size", "wall_height", "shelves", "dock")


def _check_world(sc: Scenario, v: Validator) -> None:
    """A world file: exactly one of ``mjcf``/``urdf``; with ``mode: replace`` no procedural
    field set to anything but its default (it would be silently unused); a valid prim that no
    robot or camera lies in (or holds)."""
    from harness.scenario.prims import check_prim_path

    model = sc.world.model
    if model is None:
        return
    if (model.urdf is None) == (model.mjcf is None):
        v.fail("world.model", "set exactly one of 'urdf' and 'mjcf' (the path of the world's "
               "model file)")
    if not model.path.strip():
        v.fail(f"world.model.{model.kind}", "must not be empty")
    if model.urdf is not None and _is_xacro(model.urdf):
        v.fail("world.model.urdf", f"{model.urdf} is a xacro file: srr reads xacro only for "
               "robots (model: {xacro: ...}); expand it to URDF with xacro first")
    if model.mode == "replace":
        default = WorldSpec()
        for name in _PROCEDURAL_FIELDS:
            if getattr(sc.world, name) != getattr(default, name):
                v.fail(f"world.{name}", "is not used: world.model.mode is 'replace' (the model "
                       "file is the whole world); use mode: extend to build the procedural "
                       "warehouse around the file, or leave this field out")
    try:
        check_prim_path(model.prim)
    except SrrError as err:
        v.fail("world.model.prim", str(err))
    root = model.prim.rstrip("/")
    taken = [(f"robots[{i}].articulation_prim", r.prim) for i, r in enumerate(sc.robots)
             if r.enabled]
    taken += [(f"cameras[{i}].camera_prim", c.prim) for i, c in enumerate(sc.cameras)
              if c.enabled]
    for field, prim in taken:
        if prim == root or prim.startswith(root + "/") or root.startswith(prim + "/"):
            v.fail(field, f"{prim} overlaps {root}, where the world file's bodies are "
                   "(world.model.prim): move one of them")


def _check_robots(sc: Scenario, v: Validator) -> None:
    """Namespaces and frame prefixes that ROS accepts; no two enabled robots on one prim (or
    one robot's prim inside another's)."""
    from harness.bus.names import (
        FrameIdError,
        TopicNameError,
        validate_frame_id,
        validate_namespace,
    )
    from harness.scenario.prims import check_prim_path

    for i, robot in enumerate(sc.robots):
        if robot.articulation_prim:
            try:
                check_prim_path(robot.prim)
            except SrrError as err:
                v.fail(f"robots[{i}].articulation_prim", str(err))
        model = robot.model_file
        if model is not None:
            _check_model_file(v, f"robots[{i}].model", model)
        else:
            _check_builtin_joints(v, f"robots[{i}].control", robot)
        front = robot.odometry.robot_front
        if front is not None and not (math.isfinite(front[0]) and math.isfinite(front[1])
                                      and math.hypot(front[0], front[1]) > 1e-9):
            v.fail(f"robots[{i}].odometry.robot_front",
                   f"{list(front)} has no part along the floor: it is the chassis axis that "
                   "points forward (as [1, 0, 0], or [-1, 0, 0] for a model that faces -x); "
                   "odometry turns it onto +x as a yaw")
        if robot.namespace is not None:
            try:
                validate_namespace(robot.namespace)
            except TopicNameError as err:
                v.fail(f"robots[{i}].namespace", str(err))
        if robot.frame_prefix:
            try:
                validate_frame_id(robot.frame_prefix)
            except FrameIdError as err:
                v.fail(f"robots[{i}].frame_prefix", str(err).replace("frame id", "prefix"))
            if "//" in robot.frame_prefix:
                v.fail(f"robots[{i}].frame_prefix", f"prefix {robot.frame_prefix!r} has an "
                       "empty part ('//'): its frames would read 'b//odom'; write "
                       f"{'/'.join(p for p in robot.frame_prefix.split('/') if p) + '/'!r}")
    enabled = [(i, r) for i, r in enumerate(sc.robots) if r.enabled]
    for n, (i, robot) in enumerate(enabled):
        for j, other in enabled[:n]:
            if robot.prim == other.prim:
                v.fail(f"robots[{i}].articulation_prim", f"{robot.prim} is also the prim of "
                       f"robots[{j}] ({other.name}): two robots cannot share one prim")
            for inner, outer, k in ((robot, other, j), (other, robot, i)):
                if inner.prim.startswith(outer.prim.rstrip("/") + "/"):
                    v.fail(f"robots[{i}].articulation_prim",
                           f"{inner.prim} lies inside {outer.prim}, the prim of robots[{k}] "
                           f"({outer.name})")


def _check_model_file(v: Validator, where: str, model: ModelFile) -> None:
    """Exactly one of ``urdf``/``mjcf``/``xacro``, not empty; ``args`` only for ``xacro``;
    a ``.xacro`` file given as ``urdf`` is refused (it is no URDF until xacro expands it)."""
    if sum(p is not None for p in (model.urdf, model.mjcf, model.xacro)) != 1:
        v.fail(where, "set exactly one of 'urdf', 'mjcf' and 'xacro' (the path of the "
               "robot's model file)")
    if not model.path.strip():
        v.fail(f"{where}.{model.kind}", "must not be empty")
    if model.urdf is not None and _is_xacro(model.urdf):
        v.fail(f"{where}.urdf", f"{model.urdf} is a xacro file: write 'xacro: {model.urdf}' "
               "(srr expands it with xacro, with 'args' for its $(arg ...))")
    if model.args and model.xacro is None:
        v.fail(f"{where}.args", "arguments are for a xacro file: set 'xacro', not "
               f"'{model.kind}'")


def _is_xacro(path: str) -> bool:
    return path.strip().lower().endswith(".xacro")


def _check_builtin_joints(v: Validator, where: str, robot: RobotSpec) -> None:
    """A built-in model's ``control:`` names joints it has: the TurtleBot3's two wheel
    joints; the forklift's swivel and drive joints, distinct from each other and from its
    front wheels' joints."""
    control, fixed = robot.control, BUILTIN_JOINTS.get(str(robot.model), ())
    if isinstance(control, DiffDriveControl):
        unknown = [j for j in control.joint_names if j not in fixed]
        if unknown:
            v.fail(f"{where}.joint_names", f"{unknown} are not joints of {robot.model} "
                   f"(it has {list(fixed)})")
    elif isinstance(control, ForkliftControl):
        for sub, name in (("swivel_joint", control.swivel_joint),
                          ("drive_joint", control.drive_joint)):
            if name in fixed:
                v.fail(f"{where}.{sub}", f"{name!r} is a front wheel joint of the forklift; "
                       "name the swivel and drive joints otherwise")
        if control.swivel_joint == control.drive_joint:
            v.fail(f"{where}.drive_joint", f"{control.drive_joint!r} is also the swivel "
                   "joint: the two joints need distinct names")


def _check_cameras(sc: Scenario, v: Validator) -> None:
    """Unique names; no camera on another camera's or a robot's prim (resolutions: their
    ``range`` in the schema)."""
    from harness.scenario.prims import check_prim_path

    cams: dict[str, int] = {}
    prims: dict[str, str] = {r.prim: f"robots[{i}] ({r.name})"
                             for i, r in enumerate(sc.robots) if r.enabled}
    for i, cam in enumerate(sc.cameras):
        _check_unique_name(v, cams, "cameras", "camera", i, cam.name)
        for j, output in enumerate(cam.outputs):
            if output in cam.outputs[:j]:
                v.fail(f"cameras[{i}].outputs[{j}]", f"{output!r} is listed twice")
        if cam.camera_prim:
            try:
                check_prim_path(cam.prim)
            except SrrError as err:
                v.fail(f"cameras[{i}].camera_prim", str(err))
        _check_record(v, f"cameras[{i}]", cam.record,
                      {s: f"{cam.name}_{s}" for s in ("rgb", "depth") if s in cam.outputs},
                      f"cameras[{i}].outputs has no '{{stream}}'", cam.resolution)
        if not cam.enabled:
            continue
        if cam.prim in prims:
            v.fail(f"cameras[{i}].camera_prim", f"{cam.prim} is already the prim of "
                   f"{prims[cam.prim]}")
        prims[cam.prim] = f"cameras[{i}] ({cam.name})"
    _check_rtsp(sc, v)


_MOUNT_PATH = re.compile(r"^(/[A-Za-z0-9._~-]+)+$")


def _check_record(v: Validator, where: str, rec: CameraRecordSpec, raw: Mapping[str, str],
                  lacking: str, resolution: tuple[int, int]) -> None:
    """The ``record`` block of the camera at ``where`` (``raw``: the raw topic of each image
    stream it publishes; ``lacking``: why it does not publish a ``{stream}``): formats of
    streams the camera has, each once, one still format per topic, even sizes for h264."""
    _check_h264(v, f"{where}.record.h264", rec.h264)
    for stream, formats in (("rgb", rec.rgb), ("depth", rec.depth)):
        path = f"{where}.record.{stream}"
        for k, fmt in enumerate(formats):
            if fmt in formats[:k]:
                v.fail(f"{path}[{k}]", f"{fmt!r} is listed twice")
        if formats and formats != ("raw",) and stream not in raw:
            v.fail(path, f"records {', '.join(formats)} of the {stream} stream, but "
                   + lacking.format(stream=stream))
    if "jpeg" in rec.rgb and "png" in rec.rgb:
        v.fail(f"{where}.record.rgb", "jpeg and png both go to "
               f"{raw['rgb']}/compressed: choose one")
    w, h = resolution
    if "h264" in rec.rgb and (w % 2 or h % 2):
        v.fail(f"{where}.resolution", f"h264 ({where}.record.rgb) needs an even "
               f"width and height, got {w}x{h}")


def _check_robot_cameras(sc: Scenario, v: Validator) -> None:
    """A robot camera's ``record`` block, as a fixed camera's; none without srr's graph."""
    for i, robot in enumerate(sc.robots):
        cam = robot.sensors.camera
        if cam is None:
            continue
        where = f"robots[{i}].sensors.camera"
        if not cam.graph and cam.record != CameraRecordSpec():
            v.fail(f"{where}.record", "has no effect with graph: false (the graphs: builder "
                   "that publishes the camera decides what it records)")
        raw = {"rgb": cam.topic} | ({"depth": cam.depth_topic} if cam.depth_topic else {})
        _check_record(v, where, cam.record, raw, f"{where}.depth_topic is not set",
                      cam.resolution)


#: Speed presets each h264 encoder knows.
H264_PRESETS = {
    "x264": ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow",
             "slower", "veryslow", "placebo"),
    "nvenc": ("p1", "p2", "p3", "p4", "p5", "p6", "p7"),
}


def _check_h264(v: Validator, path: str, spec: H264Spec) -> None:
    if spec.preset is not None and spec.preset not in H264_PRESETS[spec.encoder]:
        v.fail(f"{path}.preset", f"{spec.encoder} has no preset {spec.preset!r} (presets: "
               f"{', '.join(H264_PRESETS[spec.encoder])})")


def _check_rtsp(sc: Scenario, v: Validator) -> None:
    """``rtsp:`` and the cameras' ``port`` / ``mount_path``: valid mount paths, no two
    streams at one URL, h264-able sizes, at least one stream when enabled."""
    urls: dict[tuple[int, str], int] = {}
    streams = 0
    for i, cam in enumerate(sc.cameras):
        if cam.mount_path is not None and not _MOUNT_PATH.match(cam.mount_path):
            v.fail(f"cameras[{i}].mount_path", "must be '/' followed by letters, digits and "
                   f"'._~-' (segments separated by '/'), got {cam.mount_path!r}")
        if cam.port is None or not cam.enabled:
            continue
        streams += 1
        key = (cam.port, cam.mount)
        if key in urls:
            j = urls[key]
            v.fail(f"cameras[{i}].port", f"rtsp://{sc.rtsp.host}:{cam.port}{cam.mount} is "
                   f"also the stream of cameras[{j}] ({sc.cameras[j].name}): give each "
                   "camera its own port (or mount_path)")
        urls[key] = i
        w, h = cam.resolution
        if sc.rtsp.enabled and (w % 2 or h % 2):
            v.fail(f"cameras[{i}].resolution", f"an RTSP stream (h264, 4:2:0) needs an even "
                   f"width and height, got {w}x{h}")
    _check_h264(v, "rtsp.h264", sc.rtsp.h264)
    if not sc.rtsp.enabled:
        return
    if not sc.rtsp.host.strip():
        v.fail("rtsp.host", "must not be empty")
    if streams == 0:
        v.fail("rtsp.enabled", "no enabled camera has a port: give each camera to stream a "
               "port (and optionally a mount_path) in cameras")


def _check_suts(sc: Scenario, v: Validator) -> None:
    """Unique names, ``module:Class`` plug-ins, a bound robot that exists, valid namespaces
    and remapping rules."""
    from harness.bus.names import TopicNameError, validate_namespace, validate_topic

    robots = [r.name for r in sc.robots if r.enabled]
    suts: set[str] = set()
    for i, sut in enumerate(sc.systems_under_test):
        where = f"systems_under_test[{i}]"
        if sut.name in suts:
            v.fail(f"{where}.name", f"duplicate name {sut.name!r}")
        suts.add(sut.name)
        module, sep, attr = sut.plugin.partition(":")
        if not sep or not module or not attr:
            v.fail(f"{where}.plugin", f"expected 'module:Class', got {sut.plugin!r}")
        if sut.robot and sut.robot not in robots and sut.enabled:
            if any(r.name == sut.robot for r in sc.robots):
                v.fail(f"{where}.robot", f"robot {sut.robot!r} is disabled; disable this "
                       "system under test too (enabled: false) or bind it to another robot")
            close = close_match(sut.robot, robots)
            hint = f"did you mean {close!r}? " if close else ""
            v.fail(f"{where}.robot", f"no enabled robot named {sut.robot!r} ({hint}robots: "
                   f"{', '.join(robots) or 'none'})")
        if sut.namespace is not None:
            try:
                validate_namespace(sut.namespace)
            except TopicNameError as err:
                v.fail(f"{where}.namespace", str(err))
        for src, dst in sut.remap.items():
            for name, sub in ((src, f"{where}.remap"), (dst, f"{where}.remap.{src}")):
                try:
                    validate_topic(name)
                except TopicNameError as err:
                    v.fail(sub, str(err))

def _check_graphs(sc: Scenario, v: Validator) -> None:
    """``module:function`` builders, unique names that make valid graph paths, and a robot
    that exists and is enabled (or, left out, a scene with exactly one enabled robot)."""
    robots = [r.name for r in sc.robots if r.enabled]
    names: dict[str, int] = {}
    for i, spec in enumerate(sc.graphs):
        where = f"graphs[{i}]"
        module, sep, func = spec.builder.partition(":")
        if not sep or not module or not func:
            v.fail(f"{where}.builder", f"expected 'module:function', got {spec.builder!r}")
        name = graph_name(spec)
        _check_name(v, f"{where}.name", name)
        if name in names:
            v.fail(f"{where}.name", f"duplicate graph name {name!r} (also graphs[{names[name]}]"
                   "); give one of them another name")
        names[name] = i
        if spec.robot and spec.enabled and spec.robot not in robots:
            close = close_match(spec.robot, robots)
            hint = f"did you mean {close!r}? " if close else ""
            v.fail(f"{where}.robot", f"no enabled robot named {spec.robot!r} ({hint}robots: "
                   f"{', '.join(robots) or 'none'})")


#: What a metric's name starts with (``harness.metrics.types.MetricResult.group``; ``*``:
#: a glob that may match any group).
METRIC_GROUPS = ("control", "perception", "safety", "spec")


def _check_tolerances(sc: Scenario, v: Validator) -> None:
    """A tolerance's key is a metric name or glob: it starts with a metric group (a misspelt
    group would match nothing, and the tolerance would silently not apply)."""
    for key in sc.scoring.tolerances:
        head = key.split(".", 1)[0]
        if head in METRIC_GROUPS or any(c in head for c in "*?["):
            continue
        near = close_match(head, METRIC_GROUPS)
        hint = f" (did you mean {near!r}?)" if near else ""
        v.fail(f"scoring.tolerances.{key}", f"matches no metric: metric names start with "
               f"{', '.join(METRIC_GROUPS)}{hint}")


def _check_control_scoring(sc: Scenario, v: Validator) -> None:
    """One control block per robot when ``scoring.control`` is a list; a block (or the
    safety block) that leaves ``robot`` out needs exactly one enabled robot to default to."""
    robots = [r.name for r in sc.robots if r.enabled]
    c = sc.scoring.control
    blocks: list[tuple[str, ControlScoring | SafetyScoring]] = \
        [] if c is None else [("scoring.control", c)] if not isinstance(c, tuple) else \
        [(f"scoring.control[{i}]", b) for i, b in enumerate(c)]
    if sc.scoring.safety is not None:
        blocks.append(("scoring.safety", sc.scoring.safety))
    for where, block in blocks:
        if block.enabled and not block.robot and len(robots) != 1:
            v.fail(f"{where}.robot", "required: the scene has "
                   f"{len(robots) or 'no'} enabled robots ({', '.join(robots) or 'none'}), "
                   "so there is no single robot to default to")
    if not isinstance(sc.scoring.control, tuple):
        return
    seen: dict[str, int] = {}
    for i, block in enumerate(sc.scoring.control):
        if block.robot in seen:
            v.fail(f"scoring.control[{i}].robot", f"robot {block.robot!r} is already scored by "
                   f"scoring.control[{seen[block.robot]}]")
        seen[block.robot] = i

def _check_workers_and_zones(sc: Scenario, v: Validator) -> None:
    """Workers: unique names, walkable routes, bodies taller than wide. Zones: a real polygon
    (three or more points, non-zero area) and a tripwire with two distinct ends."""
    seen: set[str] = set()
    for i, worker in enumerate(sc.workers):
        where = f"workers[{i}]"
        if worker.name:
            _check_name(v, f"{where}.name", worker.name)
        name = sc.worker_name(i)
        if name in seen:
            v.fail(f"{where}.name", f"duplicate worker name {name!r}")
        seen.add(name)
        if len(worker.route) < 2:
            v.fail(f"{where}.route", "a route needs at least two waypoints")
        for j in range(1, len(worker.route)):
            if worker.route[j] == worker.route[j - 1]:
                v.fail(f"{where}.route[{j}]", "repeats the previous waypoint")
        if worker.radius > worker.height / 3:
            v.fail(f"{where}.radius", f"must be at most height / 3 ({worker.height / 3:g}), "
                   f"got {worker.radius!r}")
    _check_polygon(v, "zones.loading_roi", sc.zones.loading_roi)
    if sc.scoring.perception is not None:  # empty: everywhere
        _check_polygon(v, "scoring.perception.area", sc.scoring.perception.area)
    wire = sc.zones.trailer_tripwire
    if wire is not None and wire.a == wire.b:
        v.fail("zones.trailer_tripwire.b", f"must differ from a {list(wire.a)}")


def _name_rule(field: str) -> Callable[[str], None] | None:
    """The naming rule of a string field, by its name: ROS topic names for ``*topic``
    fields, tf2 frame ids for ``*_frame`` and ``frame_id`` fields."""
    from harness.bus.names import validate_frame_id, validate_topic

    if field.endswith("topic"):
        return validate_topic
    if field.endswith("_frame") or field == "frame_id":
        return validate_frame_id
    return None


def _check_names(v: Validator, obj: Any, path: str) -> None:
    """Every topic field must be a valid ROS 2 topic name and every frame field a frame id
    tf2 accepts (see :func:`_name_rule`)."""
    from harness.bus.names import FrameIdError, TopicNameError, validate_topic

    if isinstance(obj, tuple):
        for i, item in enumerate(obj):
            _check_names(v, item, f"{path}[{i}]")
        return
    if not dataclasses.is_dataclass(obj):
        return
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        sub = join(path, f.name)
        rule = _name_rule(f.name)
        if rule is not None and isinstance(value, str):
            try:
                rule(value)
            except (TopicNameError, FrameIdError) as err:
                v.fail(sub, str(err))
        elif f.name in _TOPIC_LISTS or f.name in _TOPIC_KEYED:
            names = value if f.name in _TOPIC_LISTS else tuple(value)
            for i, name in enumerate(names):
                try:
                    validate_topic(name)
                except TopicNameError as err:
                    v.fail(f"{sub}[{i}]" if f.name in _TOPIC_LISTS else f"{sub}.{name}",
                           str(err))
        else:
            _check_names(v, value, sub)


#: Fields that hold a list of topic names, and mappings keyed by topic names.
_TOPIC_LISTS = frozenset({"marker_topics"})
_TOPIC_KEYED = frozenset({"expected_rates", "sut_outputs"})

def _check_unique_name(v: Validator, seen: dict[str, int], block: str, kind: str, i: int,
                       name: str) -> None:
    """``block[i]``'s name unique among those ``seen`` so far (a duplicate names where the
    first one is) and valid; records it in ``seen``."""
    if name in seen:
        j = seen[name]
        v.fail(f"{block}[{i}].name", f"duplicate {kind} name {name!r} (also {block}[{j}], "
               f"from {v.file_for(f'{block}[{j}]')})")
    seen[name] = i
    _check_name(v, f"{block}[{i}].name", name)


def _check_name(v: Validator, path: str, name: str) -> None:
    if not name or not all(c.isascii() and (c.isalnum() or c == "_") for c in name) \
            or name[0].isdigit():  # names become prim paths and ROS names: ASCII only
        v.fail(path, f"must be letters, digits and '_' and not start with a digit (ASCII "
               f"only), got {name!r}")


def spec_context(sc: Scenario) -> SignalContext:
    """What ``specs:`` formulas may name in ``sc``: enabled robots and workers (by name and
    as ``character_<i>``), its zones, the robots a control block routes, the tick rate."""
    robots = [r.name for r in sc.robots if r.enabled]
    objects = set(robots)
    for i, w in enumerate(sc.workers):
        if w.enabled:
            objects |= {sc.worker_name(i), f"character_{i}"}
    zones = {"loading_roi"} if len(sc.zones.loading_roi) >= 3 else set()
    if sc.zones.trailer_tripwire is not None:
        zones.add("trailer")
    only = robots[0] if len(robots) == 1 else ""
    routed = {b.robot or only for b in sc.scoring.control_blocks} - {""}
    assert zones <= set(ZONES)
    return SignalContext(objects=objects, zones=zones, routed=routed,
                         tick_hz=sc.physics.tick_hz)


def _check_specs(sc: Scenario, v: Validator) -> None:
    """Every spec's name unique and valid (it names a metric), its formula one that parses
    and names only signals, objects and zones the scenario has."""
    if not sc.specs:
        return
    ctx = spec_context(sc)
    seen: dict[str, int] = {}
    for i, spec in enumerate(sc.specs):
        _check_unique_name(v, seen, "specs", "spec", i, spec.name)
        if not spec.enabled:
            continue
        try:
            parse_formula(spec.formula, ctx)
        except SpecError as err:
            v.fail(f"specs[{i}].formula", f"spec {spec.name!r}: {err}")
