"""The ray-cast lidar model against known geometry: an empty room whose inner wall faces are at
x, y = ±3 m, so every beam's true range is the distance to the nearest wall along it."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from harness.errors import SimulationError
from harness.scenario.schema import (
    DockSpec,
    LidarSpec,
    Pose,
    RobotSpec,
    Scenario,
    SensorsSpec,
    WorldSpec,
)
from harness.sim import World
from harness.sim.lidar import LIDAR_GEOM_GROUPS, Lidar, LidarConfig, noise_rng

HALF = 3.0  # inner wall faces of a 6 x 6 m room
ROOM = WorldSpec(size=(2 * HALF, 2 * HALF), wall_height=1.0, shelves=(),
                 dock=DockSpec(enabled=False))


def tb3(name: str = "tb3", *, x: float = 0.0, y: float = 0.0, yaw_deg: float = 0.0,
        link: str = "base_scan") -> RobotSpec:
    sensors = SensorsSpec(lidar=LidarSpec(link=link, range_max=10.0))
    return RobotSpec(name=name, model="turtlebot3_waffle_pi", sensors=sensors,
                     spawn=Pose(position=(x, y, 0.0), rpy_deg=(0.0, 0.0, yaw_deg)))


def room(*robots: RobotSpec) -> World:
    return World.build(Scenario(format_version=1, name="lidar", world=ROOM, robots=robots))


def room_ranges(x: float, y: float, angles: np.ndarray) -> np.ndarray:
    """Distance from (x, y) along each world angle to the nearest inner wall face."""
    c, s = np.cos(angles), np.sin(angles)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 1e-12, (HALF - x) / c, np.where(c < -1e-12, (-HALF - x) / c, np.inf))
        ty = np.where(s > 1e-12, (HALF - y) / s, np.where(s < -1e-12, (-HALF - y) / s, np.inf))
    return np.minimum(tx, ty)


def lidar_of(world: World, config: LidarConfig, robot: str = "tb3",
             rng: np.random.Generator | None = None) -> Lidar:
    return Lidar(world, world.sensor_prim(robot, "lidar"), config, rng)


def test_every_beam_reads_the_wall_distance_of_the_room() -> None:
    """Robot yawed 30° off-centre: beam i points at yaw + i·2π/360 in the world, and reads the
    analytic distance to the wall it points at (float32, noise 0)."""
    yaw = math.radians(30.0)
    world = room(tb3(x=0.5, y=-1.0, yaw_deg=30.0))
    lidar = lidar_of(world, LidarConfig(beams=360, range_min=0.12, range_max=10.0))
    scan = lidar.scan()
    # base_scan sits 0.064 m behind the base centre (TurtleBot3 URDF)
    sx, sy = 0.5 - 0.064 * math.cos(yaw), -1.0 - 0.064 * math.sin(yaw)
    np.testing.assert_allclose(world.prim_pose("/World/tb3/base_scan/lidar")[0][:2], [sx, sy],
                               atol=1e-12)
    expected = room_ranges(sx, sy, yaw + lidar.config.angles())
    assert scan.ranges.dtype == np.float32 and scan.ranges.shape == (360,)
    np.testing.assert_allclose(scan.ranges, expected, atol=1e-5)
    # the beam that points straight at the east wall (world angle 0) is beam 330
    assert scan.ranges[330] == pytest.approx(HALF - sx, abs=1e-5)
    assert lidar.config.angle_min == 0.0
    assert lidar.config.angle_increment == pytest.approx(2 * math.pi / 360)
    assert lidar.config.angle_max == pytest.approx(2 * math.pi - 2 * math.pi / 360)


def test_own_robot_is_never_hit_even_from_inside_its_shell() -> None:
    """A lidar on base_link sits inside the robot, level with the wheel tyres: a plain
    mj_multiRay hits the robot's own wheels, the lidar never does."""
    world = room(tb3(link="base_link"))
    prim = world.sensor_prim("tb3", "lidar")
    lidar = lidar_of(world, LidarConfig(beams=360, range_min=0.0, range_max=10.0))
    m, d = world.model, world.data
    site = world.prim_ref(prim).id
    dirs = lidar._local_dirs @ d.site_xmat[site].reshape(3, 3).T
    geom = np.zeros(360, dtype=np.int32)
    dist = np.zeros(360)
    mujoco.mj_multiRay(m, d, d.site_xpos[site].copy(), dirs.ravel(), LIDAR_GEOM_GROUPS, 1,
                       int(m.site_bodyid[site]), geom, dist, None, 360, 100.0)
    own = set(world.robot_body_ids("tb3"))
    self_hits = [i for i in range(360) if geom[i] >= 0 and m.geom_bodyid[geom[i]] in own]
    assert len(self_hits) > 10  # the precondition: the robot is in the way of some beams

    true, hit_geoms = lidar.true_ranges()
    assert not any(m.geom_bodyid[g] in own for g in hit_geoms if g >= 0)
    pos = d.site_xpos[site]
    np.testing.assert_allclose(true, room_ranges(pos[0], pos[1], lidar.config.angles()),
                               atol=1e-5)


def test_no_range_shorter_than_the_robot_at_rest_in_an_empty_room() -> None:
    world = room(tb3(x=1.0, y=0.5, yaw_deg=-70.0))
    world.step(240)  # settle on the wheels and casters for one second
    scan = lidar_of(world, LidarConfig(beams=720, range_min=0.0, range_max=10.0)).scan()
    assert np.isfinite(scan.ranges).all()
    assert scan.ranges.min() > 1.5  # the nearest wall; the robot itself is ~0.2 m across


def test_other_robots_are_seen() -> None:
    """Only the lidar's own robot is excluded: a second TurtleBot3 1 m ahead is hit. At the
    scan height (0.132 m) the beam passes over its shell and meets its lidar housing, a
    cylinder of radius 0.035 m around its base_scan (0.064 m behind its base centre)."""
    world = room(tb3(x=-1.0), tb3("other", x=0.0))
    scan = lidar_of(world, LidarConfig(beams=360, range_min=0.0, range_max=10.0)).scan()
    housing_rear = 0.0 - 0.064 - 0.035
    assert scan.ranges[0] == pytest.approx(housing_rear - (-1.0 - 0.064), abs=1e-5)
    assert scan.ranges[180] == pytest.approx(HALF - 1.064, abs=1e-5)  # west wall behind


def test_out_of_range_is_plus_inf_and_too_close_is_minus_inf() -> None:
    world = room(tb3(x=2.5))  # lidar at x = 2.436: east wall 0.564 m ahead, west 5.436 behind
    lidar = lidar_of(world, LidarConfig(beams=4, range_min=0.6, range_max=3.5))
    scan = lidar.scan()
    assert scan.ranges[0] == -np.inf  # 0.564 < range_min (REP-117)
    assert scan.ranges[2] == np.inf  # 5.436 > range_max
    assert scan.ranges[1] == pytest.approx(HALF, abs=1e-5)  # north wall at 3.0
    assert scan.ranges[3] == pytest.approx(HALF, abs=1e-5)
    np.testing.assert_array_equal(scan.intensities, [0.0, 1.0, 0.0, 1.0])
    assert len(scan.points()) == 2


def test_noise_is_seeded_and_has_the_configured_spread() -> None:
    world = room(tb3())
    config = LidarConfig(beams=360, range_min=0.0, range_max=10.0, noise_std=0.01)
    a = [lidar_of(world, config, rng=noise_rng(7, "/World/g/Lidar")).scan() for _ in range(2)]
    same = lidar_of(world, config, rng=noise_rng(7, "/World/g/Lidar"))
    other_seed = lidar_of(world, config, rng=noise_rng(8, "/World/g/Lidar"))
    other_path = lidar_of(world, config, rng=noise_rng(7, "/World/h/Lidar"))
    assert a[0].ranges.tobytes() == a[1].ranges.tobytes() == same.scan().ranges.tobytes()
    assert other_seed.scan().ranges.tobytes() != a[0].ranges.tobytes()
    assert other_path.scan().ranges.tobytes() != a[0].ranges.tobytes()

    lidar = lidar_of(world, config, rng=noise_rng(7, "/World/g/Lidar"))
    true, _ = lidar.true_ranges()
    errors = np.concatenate([lidar.scan().ranges - true for _ in range(10)])
    assert np.std(errors) == pytest.approx(0.01, rel=0.1)
    assert abs(np.mean(errors)) < 0.002
    # successive scans draw fresh noise
    assert lidar.scan().ranges.tobytes() != lidar.scan().ranges.tobytes()


def test_noise_needs_a_generator_and_config_is_checked() -> None:
    world = room(tb3())
    with pytest.raises(SimulationError, match="seeded generator"):
        lidar_of(world, LidarConfig(noise_std=0.01))
    with pytest.raises(SimulationError, match="range_min"):
        LidarConfig(range_min=5.0, range_max=3.0)
    with pytest.raises(SimulationError, match="not a site"):
        Lidar(world, "/World/tb3/base_scan", LidarConfig())


def test_point_cloud_is_the_scan_in_the_lidar_frame() -> None:
    world = room(tb3(x=0.3, y=0.2, yaw_deg=45.0))
    lidar = lidar_of(world, LidarConfig(beams=90, range_min=0.0, range_max=3.0))
    scan = lidar.scan()
    pts = scan.points()
    keep = np.isfinite(scan.ranges)
    assert pts.dtype == np.float32 and pts.shape == (int(keep.sum()), 3)
    assert 0 < len(pts) < 90  # the corners are beyond 3 m
    np.testing.assert_allclose(np.linalg.norm(pts, axis=1), scan.ranges[keep], rtol=1e-6)
    np.testing.assert_allclose(np.arctan2(pts[:, 1], pts[:, 0]) % (2 * np.pi),
                               lidar.config.angles()[keep], atol=1e-5)
    assert not pts[:, 2].any()


def test_reflectance_intensity_follows_the_wall_colour() -> None:
    world = room(tb3())
    lidar = lidar_of(world, LidarConfig(beams=8, range_min=0.0, range_max=10.0,
                                        intensity=100.0, intensity_mode="reflectance"))
    wall_luma = 0.2126 * 0.82 + 0.7152 * 0.80 + 0.0722 * 0.74  # warehouse wall rgba
    np.testing.assert_allclose(lidar.scan().intensities, 100.0 * wall_luma, rtol=1e-5)
