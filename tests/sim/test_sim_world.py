"""The world's structure: prims, poses, the warehouse and dock, cameras, joints API."""

from __future__ import annotations

import logging
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from harness.errors import ScenarioError, SimulationError
from harness.geometry import quat_wxyz_from_rpy_deg, quat_wxyz_rotate
from harness.scenario.schema import (
    CameraSpec,
    DiffDriveControl,
    DockSpec,
    ForkliftControl,
    ImuSpec,
    LidarSpec,
    PhysicsSpec,
    Pose,
    RobotCameraSpec,
    RobotSpec,
    SafetyIndicatorSpec,
    Scenario,
    SensorsSpec,
    WorldSpec,
)
from harness.sim import PrimKind, World

STATIC = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)  # geom group 0 only


def scenario(*robots: RobotSpec, cameras: tuple[CameraSpec, ...] = (),
             world: WorldSpec | None = None, physics: PhysicsSpec | None = None) -> Scenario:
    return Scenario(format_version=1, name="t", robots=robots, cameras=cameras,
                    world=world or WorldSpec(), physics=physics or PhysicsSpec())


def forklift(**kw: object) -> RobotSpec:
    kw.setdefault("spawn", Pose(position=(-10.0, 0.0, 0.0), rpy_deg=(0.0, 0.0, 180.0)))
    return RobotSpec(name="forklift", model="forklift", **kw)  # type: ignore[arg-type]


def tb3(**kw: object) -> RobotSpec:
    return RobotSpec(name="tb3", model="turtlebot3_waffle_pi", **kw)  # type: ignore[arg-type]


def ray(world: World, start: tuple[float, float, float], direction: tuple[float, float, float],
        ) -> tuple[float, str]:
    geom = np.zeros(1, dtype=np.int32)
    vec = np.asarray(direction, dtype=np.float64)
    dist = mujoco.mj_ray(world.model, world.data, np.asarray(start, dtype=np.float64),
                         vec / np.linalg.norm(vec), STATIC, 1, -1, geom)
    return dist, (world.model.geom(int(geom[0])).name if geom[0] >= 0 else "")


# ---------------------------------------------------------------- physics and prims

def test_physics_block_sets_timestep_integrator_and_iterations() -> None:
    world = World.build(scenario(physics=PhysicsSpec(tick_hz=50, substeps=5, integrator="euler",
                                                     solver_iterations=17)))
    assert world.timestep == pytest.approx(1 / 250)
    assert world.model.opt.integrator == mujoco.mjtIntegrator.mjINT_EULER
    assert world.model.opt.iterations == 17
    world.step(3)
    assert world.data.time == pytest.approx(3 / 250)
    with pytest.raises(SimulationError):
        world.step(-1)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_non_finite_qpos_entry_is_a_divergence_and_a_huge_finite_one_is_not(
        bad: float) -> None:
    world = World.build(scenario(forklift()))
    qpos = world.data.qpos
    world.step(0)  # the check runs with no step too
    qpos[-1] = 1e150  # finite, far beyond any sane joint: its square stays finite
    world.step(0)
    qpos[-1] = bad
    with pytest.raises(SimulationError, match="diverged"):
        world.step(0)


@pytest.mark.parametrize("field", ["qpos", "qvel"])
def test_a_bad_state_mujoco_resets_is_a_divergence_named_by_joint(
        field: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capfd: pytest.CaptureFixture[str]) -> None:
    """On a non-finite qpos or qvel MuJoCo puts the state back to the model's initial one and
    goes on (a robot back at its spawn, time at 0); srr ends the run, with MuJoCo's words and
    the joint, and MuJoCo writes nothing to stdout or to MUJOCO_LOG.TXT here."""
    monkeypatch.chdir(tmp_path)
    world = World.build(scenario(forklift()))
    world.step(5)
    getattr(world.data, field)[-1] = math.nan
    with pytest.raises(SimulationError) as e:
        world.step(1)
    assert str(e.value).startswith("simulation diverged at t=0.0208 s (non-finite state): "
                                   f"MuJoCo: Nan, Inf or huge value in {field.upper()} at DOF")
    assert "(joint forklift/back_wheel_drive)" in str(e.value)
    assert list(tmp_path.iterdir()) == []
    assert capfd.readouterr().out == ""


def test_other_mujoco_warnings_go_to_the_harness_sim_logger(
        caplog: pytest.LogCaptureFixture) -> None:
    World.build(scenario(forklift()))
    with caplog.at_level(logging.WARNING, logger="harness.sim"):
        mujoco.get_mju_user_warning()("Pre-allocated contact buffer is full.")
    assert [r.getMessage() for r in caplog.records] == [
        "MuJoCo: Pre-allocated contact buffer is full."]


def test_prims_of_warehouse_and_robots_are_registered() -> None:
    world = World.build(scenario(forklift(), tb3(spawn=Pose(position=(0.0, -3.0, 0.0)))))
    prims = world.prims()
    assert prims == tuple(sorted(prims))
    for path in ("/World/Warehouse", "/World/Warehouse/Dock/Trailer", "/World/Warehouse/Floor",
                 "/World/Warehouse/Shelf_0", "/World/forklift", "/World/forklift/body",
                 "/World/forklift/body/body/safety_indicator", "/World/tb3/base_footprint",
                 "/World/tb3/base_link", "/World/tb3/base_scan", "/World/tb3/imu_link",
                 "/World/tb3/camera_link", "/World/tb3/wheel_left_link",
                 "/World/tb3/caster_back_right_link"):
        assert world.has_prim(path), path
    assert not world.has_prim("/World/nothing")
    with pytest.raises(SimulationError, match="/World/nothing"):
        world.prim_pose("/World/nothing")
    assert world.base_prim("forklift") == "/World/forklift/body"
    assert world.base_prim("tb3") == "/World/tb3/base_footprint"
    assert world.default_base_frame("forklift") == "base_link"
    assert world.default_base_frame("tb3") == "base_footprint"
    assert world.robot_front("tb3") == (1.0, 0.0, 0.0)


def test_disabled_robots_and_cameras_are_left_out() -> None:
    world = World.build(scenario(
        forklift(enabled=False), tb3(),
        cameras=(CameraSpec(name="cam_a", enabled=False), CameraSpec(name="cam_b"))))
    assert world.robot_names() == ("tb3",)
    assert not world.has_prim("/World/forklift/body")
    assert not world.has_prim("/World/cam_a")
    assert world.prim_ref("/World/cam_b").kind is PrimKind.CAMERA


def test_spawn_places_wheels_on_the_floor_whatever_the_spawn_z() -> None:
    world = World.build(scenario(
        forklift(spawn=Pose(position=(-10.0, 2.0, 1.5), rpy_deg=(0.0, 0.0, 30.0))),
        tb3(spawn=Pose(position=(1.0, 2.0, 0.7)))))
    p, q = world.prim_pose("/World/forklift/body")
    np.testing.assert_allclose(p, [-10.0, 2.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(q, quat_wxyz_from_rpy_deg((0, 0, 30)), atol=1e-12)
    world.step(60)
    for base in ("/World/forklift/body", "/World/tb3/base_footprint"):
        assert abs(world.prim_pose(base)[0][2]) < 0.005, base


def test_base_scan_is_0132_above_base_footprint() -> None:
    world = World.build(scenario(tb3(spawn=Pose(position=(1.0, 2.0, 0.0),
                                                rpy_deg=(0.0, 0.0, 30.0)))))
    world.step(30)
    foot, q = world.prim_pose("/World/tb3/base_footprint")
    scan, _ = world.prim_pose("/World/tb3/base_scan")
    np.testing.assert_allclose(scan - foot, quat_wxyz_rotate(q, (-0.064, 0.0, 0.132)), atol=1e-6)
    assert scan[2] - foot[2] == pytest.approx(0.132, abs=1e-3)


def test_robot_masses_and_body_ids() -> None:
    world = World.build(scenario(forklift(), tb3(spawn=Pose(position=(0.0, -3.0, 0.0)))))
    m = world.model
    f_root = world.robot("forklift").root_body_id
    t_root = world.robot("tb3").root_body_id
    assert m.body_subtreemass[f_root] == pytest.approx(1500, rel=0.05)
    assert m.body_subtreemass[t_root] == pytest.approx(1.8, rel=0.05)
    f_ids = world.robot_body_ids("forklift")
    assert f_root in f_ids and 0 not in f_ids and not set(f_ids) & set(world.robot_body_ids("tb3"))
    assert world.prim_body_id("/World/forklift/body/body/safety_indicator") == f_root
    assert world.prim_body_id("/World/tb3/base_scan") in world.robot_body_ids("tb3")


def test_forklift_wheel_geometry_matches_the_control_block() -> None:
    control = ForkliftControl(wheelbase=1.7, wheel_radius=0.2)
    world = World.build(scenario(forklift(control=control)))
    front_l, _ = world.prim_pose("/World/forklift/front_left_wheel")
    front_r, _ = world.prim_pose("/World/forklift/front_right_wheel")
    back, _ = world.prim_pose("/World/forklift/back_wheel")
    assert np.linalg.norm(back - (front_l + front_r) / 2) == pytest.approx(1.7, abs=1e-9)
    assert back[2] == pytest.approx(0.2, abs=1e-9)


# ---------------------------------------------------------------- joints

def test_joint_names_and_states() -> None:
    world = World.build(scenario(forklift(), tb3(spawn=Pose(position=(0.0, -3.0, 0.0)))))
    assert world.joint_names("/World/forklift") == (
        "front_left_wheel_joint", "front_right_wheel_joint", "back_wheel_swivel",
        "back_wheel_drive")
    assert world.joint_names("/World/tb3/base_footprint") == ("wheel_left_joint",
                                                               "wheel_right_joint")
    assert world.joint_state("/World/forklift", "back_wheel_swivel") == (0.0, 0.0)


def test_unknown_joint_or_robot_raises() -> None:
    world = World.build(scenario(forklift()))
    with pytest.raises(SimulationError, match=r"forklift.*no joint 'steer'"):
        world.apply_joint_commands("/World/forklift", ["steer"], [0.1], [0.0])
    with pytest.raises(SimulationError, match="no robot"):
        world.apply_joint_commands("/World/robot", ["back_wheel_drive"], None, [1.0])
    with pytest.raises(SimulationError, match="2 joint names but 1 velocities"):
        world.apply_joint_commands("/World/forklift", ["back_wheel_drive", "back_wheel_swivel"],
                                   None, [1.0])
    with pytest.raises(SimulationError, match="no drive"):
        world.apply_joint_commands("/World/forklift", ["front_left_wheel_joint"], None, [1.0])
    with pytest.raises(SimulationError, match="no joint"):
        world.joint_state("/World/forklift", "nope")
    assert not world.data.ctrl.any()  # nothing half-written


def test_commands_route_by_actuator_kind_and_nan_leaves_as_is() -> None:
    world = World.build(scenario(forklift()))
    joints = ["back_wheel_drive", "back_wheel_swivel"]
    world.apply_joint_commands("/World/forklift", joints, [0.0, 0.3], [-5.0, 0.0])
    ctrl = {world.model.actuator(i).name: float(world.data.ctrl[i])
            for i in range(world.model.nu)}
    assert ctrl == {"forklift/back_wheel_swivel": 0.3, "forklift/back_wheel_drive": -5.0}
    world.apply_joint_commands("/World/forklift", joints, [math.nan, math.nan], [2.0, 9.0])
    assert float(world.data.ctrl[world.model.actuator("forklift/back_wheel_swivel").id]) == 0.3
    assert float(world.data.ctrl[world.model.actuator("forklift/back_wheel_drive").id]) == 2.0
    world.apply_joint_commands("/World/forklift", joints, None, [math.nan, 0.0])
    assert float(world.data.ctrl[world.model.actuator("forklift/back_wheel_drive").id]) == 2.0
    world.reset()
    assert not world.data.ctrl.any()


def test_control_block_of_the_wrong_model_is_refused() -> None:
    with pytest.raises(SimulationError, match=r"robots\.forklift\.control"):
        World.build(scenario(forklift(control=DiffDriveControl())))
    with pytest.raises(SimulationError, match=r"robots\.tb3\.control"):
        World.build(scenario(tb3(control=ForkliftControl())))


def test_custom_joint_names_are_used() -> None:
    control = ForkliftControl(drive_joint="rear_drive", swivel_joint="rear_steer")
    world = World.build(scenario(forklift(control=control)))
    world.apply_joint_commands("/World/forklift", ["rear_drive", "rear_steer"], [0, 0.2], [1, 0])
    world.step(48)
    assert world.joint_state("/World/forklift", "rear_steer")[0] == pytest.approx(0.2, abs=0.02)


# ---------------------------------------------------------------- safety indicator

def test_safety_indicator_starts_orange_and_can_be_recoloured() -> None:
    world = World.build(scenario(forklift()))
    path = "/World/forklift/body/body/safety_indicator"
    ref = world.prim_ref(path)
    assert ref.kind is PrimKind.GEOM
    assert world.model.geom_contype[ref.id] == 0 and world.model.geom_conaffinity[ref.id] == 0
    np.testing.assert_allclose(world.model.geom_rgba[ref.id], [1.0, 0.3, 0.0, 1.0])
    pos, _ = world.prim_pose(path)
    assert pos[2] > 2.0  # on top of the forklift, seen from above
    world.set_geom_rgba(path, (0.0, 1.0, 0.0, 1.0))
    np.testing.assert_allclose(world.model.geom_rgba[ref.id], [0.0, 1.0, 0.0, 1.0])
    with pytest.raises(SimulationError):
        world.set_geom_rgba("/World/forklift/body", (0.0, 1.0, 0.0, 1.0))
    with pytest.raises(SimulationError):
        world.set_geom_rgba(path, (0.0, 1.0, 0.0))
    world.reset()
    np.testing.assert_allclose(world.model.geom_rgba[ref.id], [1.0, 0.3, 0.0, 1.0])


def test_configured_indicator_prim_is_honoured() -> None:
    prim = "/World/forklift/indicator"
    world = World.build(scenario(forklift(
        safety_indicator=SafetyIndicatorSpec(enabled=True, indicator_prim=prim))))
    assert world.prim_ref(prim).kind is PrimKind.GEOM
    assert not world.has_prim("/World/forklift/body/body/safety_indicator")


# ---------------------------------------------------------------- warehouse and dock

def test_trailer_is_where_the_dock_says() -> None:
    dock = DockSpec()
    world = World.build(scenario(world=WorldSpec(dock=dock)))
    pos, quat = world.prim_pose("/World/Warehouse/Dock/Trailer")
    np.testing.assert_allclose(pos, [*dock.position, 0.0], atol=1e-12)
    np.testing.assert_allclose(quat, [1, 0, 0, 0], atol=1e-12)
    mid = (dock.position[0] + dock.length / 2, dock.position[1], 1.0)
    dist, name = ray(world, mid, (0, 1, 0))
    assert dist == pytest.approx(dock.width / 2, abs=1e-6) and "trailer" in name
    dist, name = ray(world, mid, (0, -1, 0))
    assert dist == pytest.approx(dock.width / 2, abs=1e-6) and "trailer" in name
    dist, name = ray(world, mid, (0, 0, 1))
    assert dist == pytest.approx(dock.height - 1.0, abs=1e-6) and "roof" in name
    dist, name = ray(world, mid, (0, 0, -1))
    assert dist == pytest.approx(1.0, abs=0.01)  # the trailer floor is at ground level
    # From the middle of the warehouse, through the door, to the trailer's front wall.
    dist, name = ray(world, (0.0, 0.0, 1.0), (1, 0, 0))
    assert dist == pytest.approx(dock.position[0] + dock.length, abs=1e-6)
    assert name == "warehouse/trailer/front"
    # Beside the door the wall is still there.
    dist, name = ray(world, (0.0, dock.width, 1.0), (1, 0, 0))
    assert dist == pytest.approx(15.0, abs=1e-6) and name.startswith("warehouse/wall_east")


def test_no_dock_means_no_door() -> None:
    world = World.build(scenario(world=WorldSpec(dock=DockSpec(enabled=False))))
    assert not world.has_prim("/World/Warehouse/Dock/Trailer")
    dist, name = ray(world, (0.0, 0.0, 1.0), (1, 0, 0))
    assert dist == pytest.approx(15.0, abs=1e-6) and name.startswith("warehouse/wall_east")


def test_yawed_dock_cuts_its_door_in_the_north_wall() -> None:
    dock = DockSpec(position=(3.0, 8.0), yaw_deg=90.0, length=6.0, width=2.4, height=2.5)
    world = World.build(scenario(world=WorldSpec(dock=dock, shelves=())))
    dist, name = ray(world, (3.0, 0.0, 1.0), (0, 1, 0))
    assert dist == pytest.approx(8.0 + 6.0, abs=1e-6) and name == "warehouse/trailer/front"
    dist, name = ray(world, (3.0 + 2.4, 0.0, 1.0), (0, 1, 0))
    assert dist == pytest.approx(10.0, abs=1e-6) and name.startswith("warehouse/wall_north")
    # A lintel closes the wall above the door.
    dist, name = ray(world, (3.0, 0.0, 3.5), (0, 1, 0))
    assert dist == pytest.approx(10.0, abs=1e-6) and name == "warehouse/wall_north_lintel"
    _pos, quat = world.prim_pose("/World/Warehouse/Dock/Trailer")
    np.testing.assert_allclose(quat_wxyz_rotate(quat, (1, 0, 0)), [0, 1, 0], atol=1e-12)


def test_shelves_walls_and_floor_are_static_group_0_with_distinct_colours() -> None:
    world = World.build(scenario(forklift()))
    m = world.model
    static = [g for g in range(m.ngeom) if m.body_weldid[m.geom_bodyid[g]] == 0]
    assert static and all(m.geom_group[g] == 0 for g in static)
    colours = {tuple(np.round(m.geom_rgba[g], 3)) for g in static}
    assert len(colours) >= 5
    # Toward Shelf_0 (centre (-6, 6), 1 m deep) at the height of its bottom board.
    dist, name = ray(world, (-6.0, 3.0, 0.15), (0, 1, 0))
    assert name.startswith("warehouse/shelf_0") and dist == pytest.approx(2.5, abs=1e-6)
    assert world.prim_pose("/World/Warehouse/Shelf_0")[0][:2] == pytest.approx((-6.0, 6.0))
    floor = world.prim_ref("/World/Warehouse/Floor")
    assert m.geom_type[floor.id] == mujoco.mjtGeom.mjGEOM_PLANE
    assert m.geom_matid[floor.id] >= 0  # textured


# ---------------------------------------------------------------- cameras and sensors

def test_fixed_camera_pose_uses_world_axes_convention() -> None:
    cam = CameraSpec(name="cam", spawn=Pose(position=(1.0, 2.0, 4.0), rpy_deg=(0.0, 30.0, 45.0)),
                     fovy_deg=50.0, resolution=(800, 600))
    world = World.build(scenario(cameras=(cam,)))
    pos, quat = world.prim_pose("/World/cam")
    q_expected = quat_wxyz_from_rpy_deg((0.0, 30.0, 45.0))
    np.testing.assert_allclose(pos, [1, 2, 4], atol=1e-12)
    assert abs(float(np.dot(quat, q_expected))) == pytest.approx(1.0, abs=1e-9)
    ref = world.prim_ref("/World/cam")
    xmat = world.data.cam_xmat[ref.id].reshape(3, 3)
    look = -xmat[:, 2]  # a MuJoCo camera looks along its -Z
    np.testing.assert_allclose(look, quat_wxyz_rotate(q_expected, (1, 0, 0)), atol=1e-9)
    assert look[2] < 0  # positive pitch looks down
    np.testing.assert_allclose(xmat[:, 1], quat_wxyz_rotate(q_expected, (0, 0, 1)), atol=1e-9)  # up
    assert world.model.cam_fovy[ref.id] == pytest.approx(50.0)
    assert world.model.vis.global_.offwidth >= 800


def test_mounted_sensors_get_prims_and_the_imu_reads_gravity() -> None:
    sensors = SensorsSpec(camera=RobotCameraSpec(), lidar=LidarSpec(), imu=ImuSpec())
    world = World.build(scenario(tb3(sensors=sensors, spawn=Pose(rpy_deg=(0, 0, 90)))))
    assert world.sensor_prim("tb3", "lidar") == "/World/tb3/base_scan/lidar"
    assert world.sensor_prim("tb3", "imu") == "/World/tb3/imu_link/imu"
    assert world.sensor_prim("tb3", "camera") == "/World/tb3/camera_link/camera"
    world.step(120)
    reading = world.imu("tb3")
    np.testing.assert_allclose(reading.linear_acceleration, [0, 0, 9.81], atol=0.05)
    np.testing.assert_allclose(reading.angular_velocity, [0, 0, 0], atol=1e-3)
    assert abs(float(np.dot(reading.orientation, quat_wxyz_from_rpy_deg((0, 0, 90))))) > 0.9999
    _cam_pos, cam_q = world.prim_pose("/World/tb3/camera_link/camera")
    # looks forward
    np.testing.assert_allclose(quat_wxyz_rotate(cam_q, (1, 0, 0)), [0, 1, 0], atol=1e-3)
    assert world.prim_body_id("/World/tb3/base_scan/lidar") in world.robot_body_ids("tb3")
    with pytest.raises(SimulationError):
        world.imu("nobody")


def test_sensor_on_a_missing_link_is_refused() -> None:
    sensors = SensorsSpec(lidar=LidarSpec(link="roof_scanner"))
    with pytest.raises(ScenarioError) as err:
        World.build(scenario(tb3(sensors=sensors)))
    assert err.value.field == "robots[0].sensors.lidar.link"
    assert "turtlebot3_waffle_pi has no link 'roof_scanner'" in err.value.message


def test_duplicate_prims_are_refused() -> None:
    cam = CameraSpec(name="cam", camera_prim="/World/forklift/body")
    with pytest.raises(SimulationError, match="declared twice"):
        World.build(scenario(forklift(), cameras=(cam,)))


def test_clashing_mujoco_names_become_a_simulation_error() -> None:
    twins = (tb3(), tb3(spawn=Pose(position=(2.0, 0.0, 0.0))))
    with pytest.raises(SimulationError, match="tb3"):
        World.build(scenario(*twins))
    cams = (CameraSpec(name="c", camera_prim="/World/c1"), CameraSpec(name="c"))
    with pytest.raises(SimulationError, match="could not be built"):
        World.build(scenario(cameras=cams))
