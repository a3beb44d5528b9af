"""Workers on foot: kinematic MuJoCo bodies walking polyline routes (``scenario.workers``).

Every enabled worker becomes a mocap body at prim ``/World/Characters/<name>``: origin on the
floor under the worker's centre, +X the direction it faces. It carries a capsule torso in a
hi-vis vest colour and a sphere head in a blue hard-hat colour, prims ``.../torso`` and
``.../head``. The geoms are in geom group 2 (people), which cameras render and lidar rays hit,
and have ``contype = conaffinity = 0``: a mocap body is infinitely heavy, so a worker that
collided would shove the forklift; instead workers walk through it and the scoring counts
the near misses.

Kinematics are a pure function of simulation time (:meth:`WorkerPath.pose_at`), never
integrated, so a pose at ``t`` is exact and the same on every run. A worker stands at its first
waypoint until ``start_delay``, then walks at ``speed`` (times a seeded ``variation`` factor)
facing along the segment it is on:

* ``once``: to the last waypoint, and stays there;
* ``back_and_forth``: to the last waypoint, ``pause_s``, back to the first, ``pause_s``, again;
* ``cycle``: to the last waypoint, straight back to the first, ``pause_s``, again.

Ground truth names worker ``i`` (its index in ``scenario.workers``, disabled ones included)
``character_<i>``, whatever its ``name``: see :func:`character_frame`.
"""

from __future__ import annotations

import bisect
import math
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from harness.errors import SimulationError
from harness.geometry import quat_wxyz_from_yaw
from harness.scenario.schema import Scenario, WorkerSpec
from harness.sim.prims import PrimKind, PrimTable

__all__ = [
    "CHARACTERS_PRIM",
    "HEAD_RGBA",
    "PEOPLE_GROUP",
    "TORSO_RGBA",
    "Worker",
    "WorkerDriver",
    "WorkerPath",
    "add_workers",
    "character_frame",
    "plan_workers",
    "speed_factor",
]

CHARACTERS_PRIM = "/World/Characters"
PEOPLE_GROUP = 2
TORSO_RGBA = (0.80, 1.00, 0.10, 1.0)  # fluorescent yellow-green vest
HEAD_RGBA = (0.10, 0.30, 0.85, 1.0)  # blue hard hat
_HEAD_FRACTION = 0.065  # head radius / body height

Vec2 = tuple[float, float]


def character_frame(index: int) -> str:
    """Ground-truth frame (and topic segment) of ``workers[index]``: ``character_<index>``."""
    return f"character_{index}"


def speed_factor(seed: int, name: str, variation: float) -> float:
    """Speed multiplier of worker ``name``: U(1 - variation, 1 + variation) drawn once from a
    generator seeded by the scenario ``seed`` and a stable hash of the name; 1 when
    ``variation`` is 0."""
    if variation <= 0.0:
        return 1.0
    rng = np.random.default_rng([int(seed), zlib.crc32(f"workers/{name}".encode())])
    return float(rng.uniform(1.0 - variation, 1.0 + variation))


@dataclass(frozen=True)
class WorkerPath:
    """Where a worker is at any time: ``pose_at(time_ns) -> (x, y, yaw)``.

    ``points`` are the vertices walked in order (for ``cycle`` the first point is repeated at
    the end so the closing leg is a segment like the others).
    """

    points: tuple[Vec2, ...]
    speed: float
    start_delay_ns: int = 0
    loop: str = "back_and_forth"
    pause_s: float = 0.0
    _cum: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if len(self.points) < 2:
            raise SimulationError("a worker route needs at least two points")
        if not self.speed > 0.0:
            raise SimulationError(f"worker speed must be > 0, got {self.speed}")
        cum = [0.0]
        for (x0, y0), (x1, y1) in zip(self.points, self.points[1:], strict=False):
            step = math.hypot(x1 - x0, y1 - y0)
            if step <= 0.0:
                raise SimulationError(f"worker route repeats the point {(x0, y0)}")
            cum.append(cum[-1] + step)
        object.__setattr__(self, "_cum", tuple(cum))

    @classmethod
    def from_spec(cls, spec: WorkerSpec, speed: float) -> WorkerPath:
        points = tuple((float(x), float(y)) for x, y in spec.route)
        if spec.loop == "cycle" and points[-1] != points[0]:
            points = (*points, points[0])
        return cls(points, speed, round(spec.start_delay * 1e9), spec.loop,
                   float(spec.pause_s))

    @property
    def length(self) -> float:
        """Metres walked from the first point to the last (one way)."""
        return self._cum[-1]

    def pose_at(self, time_ns: int) -> tuple[float, float, float]:
        """Position (x, y) and heading (yaw, radians) at simulation time ``time_ns``."""
        t = (int(time_ns) - self.start_delay_ns) / 1e9
        if t <= 0.0:
            return self._at(0.0, forward=True)
        length, v, pause = self.length, self.speed, self.pause_s
        walk = length / v
        if self.loop == "once":
            return self._at(min(v * t, length), forward=True)
        if self.loop == "cycle":
            tau = t % (walk + pause)
            return self._at(min(v * tau, length), forward=True)
        tau = t % (2.0 * (walk + pause))
        if tau < walk:
            return self._at(v * tau, forward=True)
        if tau < walk + pause:
            return self._at(length, forward=True)
        if tau < 2.0 * walk + pause:
            return self._at(max(length - v * (tau - walk - pause), 0.0), forward=False)
        return self._at(0.0, forward=False)

    def _at(self, s: float, *, forward: bool) -> tuple[float, float, float]:
        """The point ``s`` metres along the polyline, facing the way the worker goes next."""
        cum, pts = self._cum, self.points
        k = (bisect.bisect_right(cum, s) if forward else bisect.bisect_left(cum, s)) - 1
        k = min(max(k, 0), len(pts) - 2)
        (x0, y0), (x1, y1) = pts[k], pts[k + 1]
        f = (s - cum[k]) / (cum[k + 1] - cum[k])
        yaw = math.atan2(y1 - y0, x1 - x0)
        if not forward:
            yaw = math.atan2(y0 - y1, x0 - x1)
        return x0 + f * (x1 - x0), y0 + f * (y1 - y0), yaw


@dataclass(frozen=True)
class Worker:
    """An enabled worker: its index in ``scenario.workers``, names, body size and path."""

    index: int
    name: str
    prim: str
    frame: str
    body: str
    height: float
    radius: float
    path: WorkerPath


def plan_workers(scenario: Scenario) -> tuple[Worker, ...]:
    """The enabled workers of ``scenario`` with their seeded speeds, in list order."""
    out: list[Worker] = []
    for i, spec in enumerate(scenario.workers):
        if not spec.enabled:
            continue
        name = scenario.worker_name(i)
        speed = spec.speed * speed_factor(scenario.seed, name, spec.variation)
        try:
            path = WorkerPath.from_spec(spec, speed)
        except SimulationError as err:
            raise SimulationError(f"workers[{i}] ({name}): {err}") from err
        out.append(Worker(index=i, name=name, prim=f"{CHARACTERS_PRIM}/{name}",
                          frame=character_frame(i), body=f"characters/{name}",
                          height=float(spec.height), radius=float(spec.radius), path=path))
    return tuple(out)


def add_workers(spec: mujoco.MjSpec, workers: Sequence[Worker], prims: PrimTable) -> None:
    """Add one mocap body per worker, posed for time 0, and declare its prims."""
    for w in workers:
        x, y, yaw = w.path.pose_at(0)
        body = spec.worldbody.add_body(name=w.body, pos=[x, y, 0.0],
                                       quat=quat_wxyz_from_yaw(yaw).tolist(), mocap=True)
        head_r = _HEAD_FRACTION * w.height
        torso_top = w.height - 2.0 * head_r
        half = torso_top / 2.0 - w.radius
        if half <= 0.0:
            raise SimulationError(f"workers[{w.index}] ({w.name}): radius {w.radius} is too "
                                  f"large for height {w.height}")
        for part, gtype, size, z, rgba in (
            ("torso", mujoco.mjtGeom.mjGEOM_CAPSULE, [w.radius, half, 0.0], torso_top / 2.0,
             TORSO_RGBA),
            ("head", mujoco.mjtGeom.mjGEOM_SPHERE, [head_r, 0.0, 0.0], w.height - head_r,
             HEAD_RGBA),
        ):
            body.add_geom(name=f"{w.body}/{part}", type=gtype, size=size, pos=[0.0, 0.0, z],
                          rgba=list(rgba), group=PEOPLE_GROUP, contype=0, conaffinity=0,
                          density=0.0, mass=0.0)
            prims.declare(f"{w.prim}/{part}", PrimKind.GEOM, f"{w.body}/{part}")
        prims.declare(w.prim, PrimKind.BODY, w.body)


class WorkerDriver:
    """Workers bound to a compiled model's mocap slots; :meth:`place` poses them for a time."""

    def __init__(self, model: mujoco.MjModel, workers: Sequence[Worker]) -> None:
        self._workers = tuple(workers)
        slots = []
        for w in self._workers:
            body = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, w.body))
            if body < 0 or model.body_mocapid[body] < 0:
                raise SimulationError(f"worker {w.name}: no mocap body {w.body!r} in the model")
            slots.append(int(model.body_mocapid[body]))
        self._slots = tuple(slots)

    @property
    def workers(self) -> tuple[Worker, ...]:
        return self._workers

    def place(self, data: mujoco.MjData, time_ns: int) -> bool:
        """Write every worker's pose at ``time_ns`` into ``data``; False when there are none.
        The caller refreshes the kinematics."""
        for w, slot in zip(self._workers, self._slots, strict=True):
            x, y, yaw = w.path.pose_at(time_ns)
            data.mocap_pos[slot] = (x, y, 0.0)
            data.mocap_quat[slot] = quat_wxyz_from_yaw(yaw)
        return bool(self._workers)
