"""Workers on foot: exact kinematics, seeded speed variation, MuJoCo bodies rays can see."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from harness.engine import Simulation
from harness.scenario.schema import Pose, RobotSpec, Scenario, WorkerSpec
from harness.sim import World
from harness.sim.workers import (
    CHARACTERS_PRIM,
    PEOPLE_GROUP,
    WorkerPath,
    plan_workers,
    speed_factor,
)

S = 1_000_000_000  # ns per second
SEEN = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)  # the lidar's groups: world, robots, people


def scenario(*workers: WorkerSpec, seed: int = 0, robots: tuple[RobotSpec, ...] = ()) -> Scenario:
    return Scenario(format_version=1, name="t", seed=seed, workers=workers, robots=robots)


def path(loop: str, pause_s: float = 0.0, delay_s: float = 0.0) -> WorkerPath:
    """An L: 4 m along +X, then 3 m along +Y, at 1 m/s."""
    spec = WorkerSpec(route=((0.0, 0.0), (4.0, 0.0), (4.0, 3.0)), speed=1.0, loop=loop,  # type: ignore[arg-type]
                      pause_s=pause_s, start_delay=delay_s)
    return WorkerPath.from_spec(spec, spec.speed)


def at(p: WorkerPath, seconds: float) -> tuple[float, float, float]:
    return p.pose_at(round(seconds * S))


def approx(pose: tuple[float, float, float], x: float, y: float, yaw: float) -> None:
    assert pose[0] == pytest.approx(x, abs=1e-12) and pose[1] == pytest.approx(y, abs=1e-12)
    assert math.remainder(pose[2] - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-12), pose


# ---------------------------------------------------------------- kinematics

def test_once_walks_the_polyline_at_its_speed_facing_each_segment_then_stops() -> None:
    p = path("once")
    approx(at(p, 0.0), 0.0, 0.0, 0.0)
    approx(at(p, 2.5), 2.5, 0.0, 0.0)
    approx(at(p, 4.0), 4.0, 0.0, math.pi / 2)  # on the corner: facing the next segment
    approx(at(p, 5.0), 4.0, 1.0, math.pi / 2)
    approx(at(p, 7.0), 4.0, 3.0, math.pi / 2)
    approx(at(p, 500.0), 4.0, 3.0, math.pi / 2)


def test_back_and_forth_pauses_at_each_end_and_walks_back_facing_backwards() -> None:
    p = path("back_and_forth", pause_s=1.0)  # period 2 * (7 + 1) = 16 s
    approx(at(p, 7.5), 4.0, 3.0, math.pi / 2)  # pausing at the far end
    approx(at(p, 9.0), 4.0, 2.0, -math.pi / 2)  # 1 m on the way back
    approx(at(p, 13.0), 2.0, 0.0, math.pi)
    approx(at(p, 15.5), 0.0, 0.0, math.pi)  # pausing at the start
    approx(at(p, 16.5), 0.5, 0.0, 0.0)  # second lap
    approx(at(p, 16.0 * 1000 + 5.0), 4.0, 1.0, math.pi / 2)  # no drift after 1000 laps


def test_cycle_closes_the_route_back_to_its_first_point() -> None:
    p = path("cycle")  # 4 + 3 + 5 = 12 m loop
    approx(at(p, 9.5), 4.0 - 0.8 * 2.5, 3.0 - 0.6 * 2.5, math.atan2(-3.0, -4.0))
    approx(at(p, 13.0), 1.0, 0.0, 0.0)


def test_start_delay_holds_the_worker_at_its_first_waypoint() -> None:
    p = path("once", delay_s=2.0)
    approx(at(p, 1.999), 0.0, 0.0, 0.0)
    approx(at(p, 3.0), 1.0, 0.0, 0.0)


def test_pose_is_a_pure_function_of_time() -> None:
    p = path("back_and_forth", pause_s=0.5)
    times = [int(t) for t in np.linspace(0, 60 * S, 97)]
    forward = [p.pose_at(t) for t in times]
    backward = [p.pose_at(t) for t in reversed(times)][::-1]
    assert forward == backward


# ---------------------------------------------------------------- seeded variation

def test_speed_variation_is_seeded_per_worker_and_within_its_range() -> None:
    same = [speed_factor(7, "character_0", 0.1) for _ in range(3)]
    assert len(set(same)) == 1 and 0.9 <= same[0] <= 1.1 and same[0] != 1.0
    assert speed_factor(8, "character_0", 0.1) != same[0]
    assert speed_factor(7, "character_1", 0.1) != same[0]
    assert speed_factor(7, "character_0", 0.0) == 1.0

    w = WorkerSpec(route=((0.0, 0.0), (100.0, 0.0)), speed=1.0, variation=0.1, loop="once")
    speeds = {seed: plan_workers(scenario(w, seed=seed))[0].path.speed for seed in (1, 1, 2)}
    assert len(speeds) == 2 and speeds[1] != speeds[2]
    assert plan_workers(scenario(w, seed=1))[0].path.speed == speeds[1]
    assert plan_workers(scenario(w, seed=1))[0].path.speed == pytest.approx(
        speed_factor(1, "character_0", 0.1))


# ---------------------------------------------------------------- the MuJoCo side

def test_workers_are_mocap_bodies_that_move_with_sim_time_in_the_engine() -> None:
    sc = scenario(
        WorkerSpec(route=((0.0, 2.0), (6.0, 2.0)), speed=1.5),
        WorkerSpec(route=((1.0, 1.0), (1.0, 5.0)), enabled=False),
        WorkerSpec(name="alice", route=((-3.0, -3.0), (-3.0, 3.0)), speed=0.8, start_delay=0.5),
    )
    sim = Simulation(sc)
    world = sim.world
    assert world.worker_prims() == (f"{CHARACTERS_PRIM}/character_0", f"{CHARACTERS_PRIM}/alice")
    assert [w.frame for w in world.workers()] == ["character_0", "character_2"]
    assert not world.has_prim(f"{CHARACTERS_PRIM}/character_1")
    for prim in world.worker_prims():
        for part in ("torso", "head"):
            assert world.has_prim(f"{prim}/{part}")
    for k in range(90):
        sim.step_tick()
        t_ns = k * S // 60
        for w in world.workers():
            x, y, yaw = w.path.pose_at(t_ns)
            pos, quat = world.prim_pose(w.prim)
            np.testing.assert_allclose(pos, [x, y, 0.0], atol=1e-12)
            np.testing.assert_allclose(quat, [math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)],
                                       atol=1e-12)
    # tick 89 is at 89 * 1e9 // 60 ns: character_0 walked at 1.5 m/s, alice at 0.8 m/s from 0.5 s
    t = (89 * S // 60) / S
    assert world.prim_pose(f"{CHARACTERS_PRIM}/character_0")[0][0] == pytest.approx(
        1.5 * t, abs=1e-12)
    assert world.prim_pose(f"{CHARACTERS_PRIM}/alice")[0][1] == pytest.approx(
        -3.0 + 0.8 * (t - 0.5), abs=1e-12)
    head = world.prim_pose(f"{CHARACTERS_PRIM}/alice/head")[0]
    assert 1.5 < head[2] < 1.75  # the head is at the top of a 1.75 m person


def test_rays_hit_a_worker_in_group_people_and_cameras_render_that_group() -> None:
    w = WorkerSpec(route=((3.0, 0.0), (3.0, 5.0)), start_delay=100.0, radius=0.25)
    world = World.build(scenario(w))
    geom = np.zeros(1, dtype=np.int32)
    start = np.array([0.0, 0.0, 1.0])
    dist = mujoco.mj_ray(world.model, world.data, start, np.array([1.0, 0.0, 0.0]), SEEN,
                         1, -1, geom)
    assert dist == pytest.approx(3.0 - 0.25, abs=1e-9)
    assert world.model.geom(int(geom[0])).name == "characters/character_0/torso"
    assert world.model.geom_group[geom[0]] == PEOPLE_GROUP
    head = mujoco.mj_ray(world.model, world.data, np.array([0.0, 0.0, 1.68]),
                         np.array([1.0, 0.0, 0.0]), SEEN, 1, -1, geom)
    assert world.model.geom(int(geom[0])).name == "characters/character_0/head"
    assert 2.8 < head < 3.0
    no_people = SEEN.copy()
    no_people[PEOPLE_GROUP] = 0
    past = mujoco.mj_ray(world.model, world.data, start, np.array([1.0, 0.0, 0.0]), no_people,
                         1, -1, geom)
    assert past > 3.0  # the same ray without group 2 goes past the worker
    assert mujoco.MjvOption().geomgroup[PEOPLE_GROUP] == 1  # rendered by default


def test_workers_walk_through_the_forklift_without_pushing_it() -> None:
    forklift = RobotSpec(name="forklift", model="forklift",  # type: ignore[arg-type]
                         spawn=Pose(position=(0.0, 0.0, 0.0)))
    crossing = WorkerSpec(route=((-3.0, 0.0), (3.0, 0.0)), speed=3.0)
    with_worker = Simulation(scenario(crossing, robots=(forklift,)))
    alone = Simulation(scenario(robots=(forklift,)))
    for sim in (with_worker, alone):
        sim.run(120)
    w_ids = [i for i in range(with_worker.world.model.ngeom)
             if with_worker.world.model.geom(i).name.startswith("characters/")]
    assert w_ids and not with_worker.world.model.geom_contype[w_ids].any()
    assert not with_worker.world.model.geom_conaffinity[w_ids].any()
    np.testing.assert_allclose(with_worker.world.prim_pose("/World/forklift")[0],
                               alone.world.prim_pose("/World/forklift")[0], atol=1e-9)
