"""A planar 360° lidar cast with ``mujoco.mj_multiRay`` from a robot's lidar site.

Conventions (those of the TurtleBot3 LDS-01 driver and REP-103/REP-117):

* Beams are evenly spread over a full turn, counter-clockwise seen from above, starting on the
  site's +X axis: beam ``i`` points at ``angle_min + i * angle_increment`` with
  ``angle_min = 0`` and ``angle_increment = 2π / beams``, so ``angle_max = 2π - increment``
  (the LDS publishes 0 … 6.2657 rad for 360 beams). Rays lie in the site's XY plane and
  tilt with the robot.
* Ranges are in metres, ``float32``. No return within ``range_max`` is ``+inf``; a return
  closer than ``range_min`` is ``-inf`` (REP-117). Gaussian noise (``noise_std``) is added to
  the true distance before that classification, so noise can push a reading out of range.
* Rays see geom groups 0 (static world), 1 (robot shells) and 2 (people); hidden robot
  collision shapes (group 3) and sites are invisible. The lidar's own robot is never hit:
  ``mj_multiRay`` excludes the body carrying the site, and a ray that meets any other body of
  the same robot is cast again from that hit point with that body excluded.
* Intensities are ``intensity`` for every return (``"constant"``) or ``intensity`` times the
  luminance of the hit geom's colour (``"reflectance"``); 0 where there is no return.
* Noise comes only from the :class:`numpy.random.Generator` handed in; use :func:`noise_rng`
  to seed one from the scenario seed and a stable key (the graph node's path), never the
  global RNG. One scan draws exactly ``beams`` normals, whatever it hits.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass
from typing import Any, Literal

import mujoco
import numpy as np
import numpy.typing as npt

from harness.errors import ScenarioError, SimulationError
from harness.geometry import rotate_rows
from harness.scenario.schema import LidarSpec, Scenario

__all__ = [
    "LIDAR_GEOM_GROUPS",
    "Lidar",
    "LidarConfig",
    "Scan",
    "check_lidars",
    "noise_rng",
]

#: Geom groups a lidar sees: 0 static world, 1 robot shells, 2 people (3 hidden colliders, no).
LIDAR_GEOM_GROUPS: npt.NDArray[np.uint8] = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)
_RECAST_NUDGE = 1e-6  # metres past a self-hit before casting again
_LUMA = np.array([0.2126, 0.7152, 0.0722])

Float32Array = npt.NDArray[np.float32]


def noise_rng(seed: int, key: str) -> np.random.Generator:
    """A generator seeded from the scenario ``seed`` and a stable ``key`` (a node path)."""
    return np.random.default_rng([int(seed), zlib.crc32(key.encode("utf-8"))])


def check_lidars(scenario: Scenario, source: str = "<scenario>") -> None:
    """Refuse (:class:`ScenarioError`, naming the file and the field) a lidar whose
    ``range_min`` is not below its ``range_max`` (each is in range on its own: a rule of
    two fields, checked when the world is built, as ``srr validate`` builds it)."""
    for i, robot in enumerate(scenario.robots):
        lidar = robot.sensors.lidar
        if robot.enabled and lidar is not None and not lidar.range_min < lidar.range_max:
            field = f"robots[{i}].sensors.lidar.range_min"
            raise ScenarioError(scenario.file_for(field, source), field,
                                f"must be below range_max ({lidar.range_max:g}), got "
                                f"{lidar.range_min:g}")


@dataclass(frozen=True)
class LidarConfig:
    """Beam layout, range limits, noise and intensity model of one lidar."""

    beams: int = 360
    range_min: float = 0.12
    range_max: float = 3.5
    noise_std: float = 0.0
    intensity: float = 1.0
    intensity_mode: Literal["constant", "reflectance"] = "constant"

    def __post_init__(self) -> None:
        if self.beams < 1:
            raise SimulationError(f"lidar: beams must be >= 1, got {self.beams}")
        if not 0.0 <= self.range_min < self.range_max:
            raise SimulationError(f"lidar: need 0 <= range_min < range_max, got "
                                  f"{self.range_min}, {self.range_max}")
        if self.noise_std < 0.0:
            raise SimulationError(f"lidar: noise_std must be >= 0, got {self.noise_std}")

    @classmethod
    def from_spec(cls, spec: LidarSpec) -> LidarConfig:
        return cls(beams=int(spec.beams), range_min=float(spec.range_min),
                   range_max=float(spec.range_max), noise_std=float(spec.noise_std))

    @property
    def angle_min(self) -> float:
        return 0.0

    @property
    def angle_increment(self) -> float:
        return 2.0 * math.pi / self.beams

    @property
    def angle_max(self) -> float:
        return self.angle_min + (self.beams - 1) * self.angle_increment

    def angles(self) -> npt.NDArray[np.float64]:
        """Beam angles in radians, ``angle_min + i * angle_increment``."""
        return self.angle_min + np.arange(self.beams, dtype=np.float64) * self.angle_increment


@dataclass(frozen=True)
class Scan:
    """One sweep: ranges (REP-117 ``±inf`` for no/too-close returns) and intensities."""

    config: LidarConfig
    ranges: Float32Array
    intensities: Float32Array

    def points(self) -> Float32Array:
        """Finite returns as (N, 3) float32 x, y, z in the lidar frame (z = 0), beam order."""
        ranges = self.ranges.astype(np.float64)
        keep = np.isfinite(ranges)
        angles = self.config.angles()[keep]
        r = ranges[keep]
        pts = np.stack([r * np.cos(angles), r * np.sin(angles), np.zeros_like(r)], axis=1)
        return pts.astype(np.float32)


class Lidar:
    """Casts scans from the lidar site ``prim`` of ``world`` (a :class:`harness.sim.World`)."""

    def __init__(self, world: Any, prim: str, config: LidarConfig,
                 rng: np.random.Generator | None = None) -> None:
        ref = world.prim_ref(prim)
        if ref.kind.value != "site":
            raise SimulationError(f"lidar prim {prim} is a {ref.kind.value}, not a site")
        if config.noise_std > 0.0 and rng is None:
            raise SimulationError(f"lidar {prim}: noise_std > 0 needs a seeded generator")
        self.prim = prim
        self.config = config
        self._world = world
        self._rng = rng
        self._site = ref.id
        model = world.model
        self._site_body = int(model.site_bodyid[ref.id])
        robot = world.robot_at(prim)
        self._own = np.zeros(model.nbody, dtype=bool)
        self._own[list(robot.body_ids)] = True
        angles = config.angles()
        self._local_dirs = np.stack(
            [np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
        self._geomid = np.zeros(config.beams, dtype=np.int32)
        self._dist = np.zeros(config.beams, dtype=np.float64)
        self._max_recasts = len(robot.body_ids)

    def true_ranges(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]:
        """Noise-free distance of each beam to the first visible geom not on the own robot
        (``inf`` when nothing is hit) and the id of that geom (-1 for none)."""
        m, d = self._world.model, self._world.data
        origin = d.site_xpos[self._site].copy()
        rot = d.site_xmat[self._site].reshape(3, 3)
        dirs = np.ascontiguousarray(rotate_rows(self._local_dirs, rot))
        cutoff = self.config.range_max + 1.0 + 10.0 * self.config.noise_std
        mujoco.mj_multiRay(m, d, origin, dirs.ravel(), LIDAR_GEOM_GROUPS, 1, self._site_body,
                           self._geomid, self._dist, None, self.config.beams, cutoff)
        dist = self._dist.copy()
        geom = self._geomid.copy()
        hit = geom >= 0
        own = np.zeros_like(hit)
        own[hit] = self._own[m.geom_bodyid[geom[hit]]]
        for i in np.flatnonzero(own):
            dist[i], geom[i] = self._recast(origin, dirs[i], float(dist[i]), int(geom[i]))
        dist[geom < 0] = np.inf
        return dist, geom

    def _recast(self, origin: npt.NDArray[np.float64], direction: npt.NDArray[np.float64],
                dist: float, geom: int) -> tuple[float, int]:
        """Walk past hits on the own robot, one excluded body at a time."""
        m, d = self._world.model, self._world.data
        out = np.zeros(1, dtype=np.int32)
        travelled = dist
        for _ in range(self._max_recasts):
            body = int(m.geom_bodyid[geom])
            start = origin + (travelled + _RECAST_NUDGE) * direction
            step = mujoco.mj_ray(m, d, start, direction, LIDAR_GEOM_GROUPS, 1, body, out)
            if out[0] < 0 or step < 0:
                return math.inf, -1
            travelled += _RECAST_NUDGE + float(step)
            geom = int(out[0])
            if not self._own[m.geom_bodyid[geom]]:
                return travelled, geom
        return math.inf, -1

    def scan(self) -> Scan:
        """One sweep from the current state (noise drawn from the generator)."""
        cfg = self.config
        dist, geom = self.true_ranges()
        measured = dist.copy()
        if cfg.noise_std > 0.0:
            assert self._rng is not None
            noise = self._rng.standard_normal(cfg.beams) * cfg.noise_std
            finite = np.isfinite(measured)
            measured[finite] += noise[finite]
        hit = np.isfinite(measured) & (measured <= cfg.range_max)
        ranges = np.full(cfg.beams, np.inf, dtype=np.float64)
        ranges[hit] = measured[hit]
        ranges[hit & (measured < cfg.range_min)] = -np.inf
        valid = np.isfinite(ranges)
        intensities = np.zeros(cfg.beams, dtype=np.float64)
        if cfg.intensity_mode == "constant":
            intensities[valid] = cfg.intensity
        else:
            intensities[valid] = cfg.intensity * self._luminance(geom[valid])
        return Scan(cfg, ranges.astype(np.float32), intensities.astype(np.float32))

    def _luminance(self, geoms: npt.NDArray[np.int32]) -> npt.NDArray[np.float64]:
        m = self._world.model
        rgba = m.geom_rgba[geoms].copy()
        mat = m.geom_matid[geoms]
        with_mat = mat >= 0
        rgba[with_mat] = m.mat_rgba[mat[with_mat]]
        rgb = rgba[:, :3].astype(np.float64)  # Rec. 709 luma, summed in order (no BLAS)
        luma: npt.NDArray[np.float64] = (rgb[:, 0] * _LUMA[0] + rgb[:, 1] * _LUMA[1]
                                         + rgb[:, 2] * _LUMA[2])
        return luma
