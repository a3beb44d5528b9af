"""Worlds from model files (``world.model``): the bundled shelf world read from MJCF, its
sensors against its known geometry (lidar ranges, camera depth), the map's footprints of its
static geoms, determinism and the baseline; URDF worlds, ``mode: extend``, a pose, movable
bodies; and bad input answered with one line naming the scenario file, the field and the
world file."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import shapely
import yaml
from shapely.geometry import Point, Polygon, box

from harness import api
from harness.cli import main
from harness.errors import ScenarioError
from harness.report.data import RunData, world_map
from harness.report.plots import map_svg
from harness.scenario import load_scenario
from harness.sim import World
from harness.sim.world_file import map_json
from tests.conftest import SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded

SCENARIO = SCENARIOS / "shelf_world_mjcf.yaml"
WORLD = SCENARIOS / "models" / "shelf_world" / "shelf_world.xml"
# The file's geometry (see its header): inner wall faces, walls 0.2 m thick, 2 m high.
EAST, WEST, NORTH, SOUTH, T = 4.0, -4.0, 3.0, -3.0, 0.2
SHELF_X, SHELF_Y, SHELF_LEN, SHELF_DEPTH = (-2.2, 0.0, 2.2), 1.6, 2.0, 0.6
SHELF_FRONT = SHELF_Y - SHELF_DEPTH / 2  # 1.3: the plinths' faces towards the aisle
PILLAR, PILLAR_R = (-1.0, -1.8), 0.15
BOLLARD, BOLLARD_R = (2.5, -1.8), 0.2  # octagon, a corner on +X


@pytest.fixture(scope="module")
def world() -> World:
    return World.build(load_scenario(SCENARIO), str(SCENARIO))


def outlines(w: World) -> dict[str, Polygon]:
    return {fp.name: Polygon(fp.points) for fp in w.footprints()}


def same_shape(a: Polygon, b: Polygon, tol: float = 1e-6) -> bool:
    return a.symmetric_difference(b).area < tol


# ------------------------------------------------------------------ the world as built

def test_the_file_replaces_the_warehouse_with_prefixed_names_and_its_prims(world: World) -> None:
    m = world.model
    geoms = [m.geom(i).name for i in range(m.ngeom)]
    assert not any(n.startswith("warehouse/") for n in geoms)  # mode: replace
    assert "world-file/wall_east" in geoms and "world-file/floor" in geoms
    assert not any(n.startswith("srr-ground/floor") for n in geoms)  # the file has a floor
    assert [m.light(i).name for i in range(m.nlight)] == ["world-file/ceiling"]
    assert "world-file/concrete" in [m.material(i).name for i in range(m.nmat)]
    for prim in ("/World/Environment/shelf_1", "/World/Environment/shelf_1/shelf_1_plinth",
                 "/World/Environment/wall_north", "/World/Environment/bollard"):
        assert world.has_prim(prim), prim
    pos, _ = world.prim_pose("/World/Environment/shelf_2")
    assert np.allclose(pos, (2.2, 1.6, 0.0))
    # the robot still comes from the scenario, with its own names
    assert world.robot_names() == ("turtlebot3",)


def test_map_footprints_are_the_files_walls_shelves_pillar_and_bollard(world: World) -> None:
    fp = outlines(world)
    assert same_shape(fp["wall_east"], box(EAST, SOUTH - T, EAST + T, NORTH + T))
    assert same_shape(fp["wall_west"], box(WEST - T, SOUTH - T, WEST, NORTH + T))
    assert same_shape(fp["wall_north"], box(WEST, NORTH, EAST, NORTH + T))
    assert same_shape(fp["wall_south"], box(WEST, SOUTH - T, EAST, SOUTH))
    for k, x in enumerate(SHELF_X):
        rack = box(x - SHELF_LEN / 2, SHELF_FRONT, x + SHELF_LEN / 2, SHELF_Y + SHELF_DEPTH / 2)
        assert same_shape(fp[f"shelf_{k}_plinth"], rack)
        parts = [p for name, p in fp.items() if name.startswith(f"shelf_{k}")]
        assert len(parts) == 8  # plinth, four uprights, three boards
        assert same_shape(shapely.union_all(parts), rack)
    circle = Point(PILLAR).buffer(PILLAR_R, 256)
    assert fp["pillar"].buffer(1e-9).contains(circle)  # circumscribed: never cuts into it
    assert fp["pillar"].area < circle.area * 1.01
    octagon = Polygon([(BOLLARD[0] + BOLLARD_R * math.cos(math.pi * k / 4),
                        BOLLARD[1] + BOLLARD_R * math.sin(math.pi * k / 4)) for k in range(8)])
    assert same_shape(fp["bollard"], octagon)  # the OBJ mesh's hull
    assert "floor" not in fp  # planes are not outlines
    heights = {fp_.name: (fp_.z_min, fp_.z_max) for fp_ in world.footprints()}
    assert heights["shelf_0_plinth"] == pytest.approx((0.0, 0.25))
    assert heights["bollard"] == pytest.approx((0.0, 0.8), abs=1e-6)  # float32 vertices
    for f in world.footprints():  # counter-clockwise, as the module promises
        assert shapely.is_ccw(shapely.LinearRing(f.points))


def test_a_robot_bumps_into_the_files_wall(tmp_path: Path) -> None:
    """Static geoms collide: a robot driven at the east wall for 4 s (1 m at its wheels'
    speed) is held 0.3 m on, at the wall's face."""
    path = scenario_file(tmp_path, robots=[{
        "name": "tb", "model": "turtlebot3_waffle_pi",
        "spawn": {"position": [3.3, -1.0, 0.0]}}], duration=4.0)
    w = World.build(load_scenario(path), str(path))
    joints = ["wheel_left_joint", "wheel_right_joint"]
    xs = []
    for _ in range(4 * 60):
        w.apply_joint_commands("/World/tb", joints, velocities=[8.0, 8.0])
        w.step(4)
        xs.append(float(w.prim_pose(w.base_prim("tb"))[0][0]))
    assert 3.8 < xs[-1] < EAST
    assert abs(xs[-1] - xs[-60]) < 0.01  # standing against the wall for the last second


# ------------------------------------------------------------------ a run: sensors, map, digests

@pytest.fixture(scope="module")
def run(module_tmp: ModuleTmp) -> api.RunResult:
    """The bundled scenario, its first two seconds."""
    sc = api.load(SCENARIO, duration=2.0)
    return api.run_scenario(sc, source=str(SCENARIO),
                            out=module_tmp("shelf") / "run")


@pytest.mark.slow
def test_lidar_ranges_to_the_files_walls_and_shelf_equal_the_geometry(
        run: api.RunResult, world: World) -> None:
    """The first scan (at the spawn, before the robot moves) against the file's faces."""
    lx, ly, _ = world.prim_pose(world.sensor_prim("turtlebot3", "lidar"))[0]
    scans = [(t, m) for topic, _, t, m in decoded(run.run_dir) if topic == "/scan"]
    t0, scan = scans[0]
    assert t0 == 0
    ranges = np.asarray(scan.ranges)
    angles = scan.angle_min + scan.angle_increment * np.arange(ranges.size)

    def beam(deg: float) -> float:
        return float(ranges[int(np.argmin(np.abs(angles - math.radians(deg))))])

    assert beam(0.0) == pytest.approx(EAST - lx, abs=0.01)
    assert beam(90.0) == pytest.approx(SHELF_FRONT - ly, abs=0.01)  # shelf_0's plinth
    assert beam(180.0) == pytest.approx(lx - WEST, abs=0.01)
    assert beam(270.0) == pytest.approx(ly - SOUTH, abs=0.01)


@pytest.mark.slow
def test_the_run_keeps_the_files_map_and_the_report_draws_it(run: api.RunResult,
                                                            world: World) -> None:
    wm = run.summary["world_map"]
    assert wm["file"] == str(WORLD) and wm["mode"] == "replace"
    stored = {f["name"]: f["points"] for f in wm["footprints"]}
    assert set(stored) == {fp.name for fp in world.footprints()}
    for fp in world.footprints():
        assert np.allclose(stored[fp.name], fp.points, atol=1e-4)
    html = (run.run_dir / "report.html").read_text()
    assert html.count('class="static"') == len(stored)
    assert "wall_east (shelf_world.xml)" in html and "warehouse floor" not in html
    assert "static geometry of shelf_world.xml" in html  # the map's legend
    # the report rebuilds the action graphs with the world file found from the scenario
    assert "could not be rebuilt" not in html and "/World/turtlebot3_TfGraph" in html


@pytest.mark.slow
def test_two_runs_give_identical_digests(run: api.RunResult, tmp_path: Path) -> None:
    again = api.run_scenario(api.load(SCENARIO, duration=2.0), source=str(SCENARIO),
                             out=tmp_path / "again")
    assert again.summary["digest"] == run.summary["digest"]
    assert {t: v["sha256"] for t, v in again.summary["topics"].items()} == \
        {t: v["sha256"] for t, v in run.summary["topics"].items()}


@pytest.mark.slow
def test_a_replay_keeps_the_recorded_map(run: api.RunResult, tmp_path: Path) -> None:
    rep = api.replay(run.run_dir, out=tmp_path / "replay")
    assert rep.summary["world_map"] == run.summary["world_map"]


@pytest.mark.slow
def test_the_bundled_scenario_passes_against_its_baseline(tmp_path: Path) -> None:
    res = api.run_scenario(api.load(SCENARIO), source=str(SCENARIO), out=tmp_path / "r")
    assert res.verdict == "PASS", res.summary["reasons"]
    assert {e["status"] for e in res.summary["comparison"]} <= {"ok", "improved"}
    metrics = {m["name"]: m["value"] for m in res.summary["metrics"]}
    assert metrics["control.goal_reached"] == 1.0


@pytest.mark.slow
def test_camera_depth_to_the_files_wall(tmp_path: Path) -> None:
    """The robot turned to the west wall: depth at the image centre (odd resolution, so a
    pixel sits on the optical axis) is the distance along the axis to x = -4."""
    path = scenario_file(tmp_path, robots=[{
        "name": "tb", "model": "turtlebot3_waffle_pi",
        "spawn": {"position": [-3.0, -1.0, 0.0], "rpy_deg": [0.0, 0.0, 180.0]},
        "sensors": {"camera": {"resolution": [65, 49], "fps": 10,
                               "depth_topic": "camera/depth"}}}], duration=0.1)
    sc = load_scenario(path)
    w = World.build(sc, str(path))
    (cx, _, cz), quat = w.prim_pose(w.sensor_prim("tb", "camera"))
    forward = np.array([1 - 2 * (quat[2] ** 2 + quat[3] ** 2),
                        2 * (quat[1] * quat[2] + quat[0] * quat[3]),
                        2 * (quat[1] * quat[3] - quat[0] * quat[2])])  # +X of the camera prim
    assert forward[0] < -0.99  # it looks at the west wall
    res = api.run_scenario(sc, source=str(path), out=tmp_path / "run")
    depth = next(m for topic, _, _, m in decoded(res.run_dir) if topic == "/camera/depth")
    assert (depth.width, depth.height, depth.encoding) == (65, 49, "32FC1")
    img = np.frombuffer(bytes(depth.data), dtype=np.float32).reshape(49, 65)
    along = (WEST - cx) / forward[0]
    assert float(img[24, 32]) == pytest.approx(along, abs=0.01)
    assert cz > 0.0  # above the floor, below the wall's top: the centre ray meets the wall


# ------------------------------------------------------------------ other forms

def scenario_file(tmp: Path, world: dict[str, Any] | None = None,
                  robots: list[dict[str, Any]] | None = None, duration: float = 1.0,
                  name: str = "scene.yaml") -> Path:
    path = tmp / name
    path.write_text(yaml.safe_dump({
        "format_version": 1, "name": "worldfile", "duration": duration,
        "world": world if world is not None else {"model": {"mjcf": str(WORLD)}},
        "robots": robots if robots is not None else []}))
    return path


BARE = """<mujoco>
  <worldbody>
    <geom name="block" type="box" pos="1 0 0.5" size="0.5 0.25 0.5"/>
    <geom name="lamp" type="box" pos="0 0 3.5" size="0.2 0.2 0.05"/>
    <geom name="drum" type="cylinder" pos="-1 1 0.4" euler="90 0 0" size="0.3 0.4"/>
    <body name="crate" pos="0 2 0.5"><freejoint/><geom type="box" size="0.2 0.2 0.2"/></body>
  </worldbody>
</mujoco>
"""


def test_a_posed_file_without_floor_or_light_gets_srrs_and_its_bodies_move(
        tmp_path: Path) -> None:
    (tmp_path / "bare.xml").write_text(BARE)
    path = scenario_file(tmp_path, {"model": {
        "mjcf": "bare.xml", "pose": {"position": [10.0, 0.0, 0.0], "rpy_deg": [0, 0, 90]}}})
    w = World.build(load_scenario(path), str(path))
    m = w.model
    names = [m.geom(i).name for i in range(m.ngeom)]
    assert "srr-ground/floor" in names
    assert [m.light(i).name for i in range(m.nlight)] == ["srr-ground/sun"]
    fp = outlines(w)
    # yaw 90° about the origin, then +10 m in x: the block's (1, 0) centre lands at (10, 1)
    assert same_shape(fp["block"], box(9.75, 0.5, 10.25, 1.5))
    # a cylinder lying along the file's y axis: a 0.8 x 0.6 rectangle (its rim polygons'
    # corners stick out by at most r (1/cos(pi/32) - 1))
    drum = box(10.0 - 1.0 - 0.4, -1.0 - 0.3, 10.0 - 1.0 + 0.4, -1.0 + 0.3)
    assert fp["drum"].buffer(1e-9).contains(drum) and fp["drum"].area < drum.area * 1.01
    assert "lamp" not in fp  # above the map's band
    assert not any(name.startswith("crate") for name in fp)  # movable: not static
    assert w.has_prim("/World/Environment/crate")
    w.step(240)  # it falls onto srr's ground and rests there
    pos, _ = w.prim_pose("/World/Environment/crate")
    assert pos == pytest.approx((8.0, 0.0, 0.2), abs=2e-3)


WALL_URDF = """<robot name="site">
  <link name="base"/>
  <link name="wall_a">
    <visual><origin xyz="0 0 0.5"/><geometry><box size="4 0.2 1"/></geometry></visual>
    <collision><origin xyz="0 0 0.5"/><geometry><box size="4 0.2 1"/></geometry></collision>
  </link>
  <joint name="fix_a" type="fixed">
    <parent link="base"/><child link="wall_a"/><origin xyz="0 3 0"/>
  </joint>
</robot>
"""


def test_a_urdf_world_is_static_with_its_links_as_prims(tmp_path: Path) -> None:
    (tmp_path / "site.urdf").write_text(WALL_URDF)
    path = scenario_file(tmp_path, {"model": {"urdf": "site.urdf"}})
    w = World.build(load_scenario(path), str(path))
    m = w.model
    assert w.has_prim("/World/Environment/wall_a")
    groups = sorted((int(m.geom_group[i]), bool(m.geom_contype[i])) for i in range(m.ngeom)
                    if m.geom(i).name.startswith("world-file/"))
    assert groups == [(0, False), (3, True)]  # visual seen (group 0), collision hidden
    assert int(m.body_weldid[w.prim_ref("/World/Environment/wall_a").id]) == 0
    (fp,) = w.footprints()  # visual and collision shapes: one outline
    assert same_shape(Polygon(fp.points), box(-2.0, 2.9, 2.0, 3.1))


def test_extend_keeps_the_warehouse_and_drops_the_files_floor(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, {"model": {"mjcf": str(WORLD), "mode": "extend"},
                                    "size": [12.0, 10.0], "shelves": [],
                                    "dock": {"enabled": False}})
    sc = load_scenario(path)
    w = World.build(sc, str(path))
    names = [w.model.geom(i).name for i in range(w.model.ngeom)]
    assert "warehouse/floor" in names and "warehouse/wall_east_0" in names
    assert "world-file/floor" not in names and "world-file/wall_east" in names
    # the map draws both: the warehouse's walls and the file's outlines
    assert w.world_file is not None
    summary = {"world_map": map_json(w.world_file)}
    svg = map_svg(RunData(tmp_path, summary, "", scenario=sc))
    assert "warehouse floor 12 × 10 m" in svg and svg.count('class="static"') == \
        len(w.footprints())
    wm = world_map(summary)
    assert wm is not None and wm.mode == "extend"


def test_world_paths_are_relative_to_the_file_that_holds_the_world(tmp_path: Path) -> None:
    site = tmp_path / "site"
    shutil.copytree(WORLD.parent, site / "shelf_world")
    (site / "world.yaml").write_text(yaml.safe_dump(
        {"world": {"model": {"mjcf": "shelf_world/shelf_world.xml"}}}))
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump({"format_version": 1, "name": "inc",
                                    "include": ["site/world.yaml"]}))
    assert len(World.build(load_scenario(path), str(path)).footprints()) == 30
    (site / "shelf_world" / "meshes" / "bollard.obj").unlink()
    with pytest.raises(ScenarioError) as info:
        api.validate(load_scenario(path), source=str(path))
    assert info.value.file == str(site / "world.yaml")
    assert info.value.field == "world.model.mjcf"
    assert "shelf_world.xml: mesh 'bollard.obj': file not found" in info.value.message


# ------------------------------------------------------------------ bad input

SHELF = {"model": {"mjcf": "shelf.xml"}}


@pytest.mark.parametrize(("world", "robots", "field", "words"), [
    ({"model": {"mjcf": "missing.xml"}}, [], "world.model.mjcf",
     ["missing.xml: file not found"]),
    ({"model": {"mjcf": "broken.xml"}}, [], "world.model.mjcf",
     ["broken.xml: MuJoCo cannot read it as MJCF"]),
    ({"model": {"urdf": "broken.urdf"}}, [], "world.model.urdf",
     ["broken.urdf: not well-formed XML"]),
    ({"model": {"mjcf": "nomesh.xml"}}, [], "world.model.mjcf",
     ["nomesh.xml: mesh 'nope.obj': file not found"]),
    ({"model": {"mjcf": "motor.xml"}}, [], "world.model.mjcf",
     ["motor.xml has actuators (door_motor)", "nothing in a scenario commands"]),
    ({"model": {"mjcf": "a.xml", "urdf": "b.urdf"}}, [], "world.model",
     ["exactly one of 'urdf' and 'mjcf'"]),
    ({"model": {"mjcf": "shelf.xml"}, "shelves": []}, [], "world.shelves",
     ["is not used: world.model.mode is 'replace'", "use mode: extend"]),
    ({"model": {"mjcf": "shelf.xml", "mode": "sideways"}}, [], "world.model.mode",
     ["expected one of 'replace', 'extend'"]),
    (SHELF, [{"name": "Environment", "model": "turtlebot3_waffle_pi"}],
     "robots[0].articulation_prim", ["/World/Environment overlaps /World/Environment"]),
    (SHELF, [{"name": "tb", "model": "turtlebot3_waffle_pi",
              "spawn": {"position": [4.05, 0.0, 0.0]}}], "robots[0].spawn.position",
     ["robot tb at (4.05, 0, 0) starts inside 'wall_east' of", "shelf.xml", "m deep"]),
    (SHELF, [{"name": "tb", "model": "turtlebot3_waffle_pi",
              "spawn": {"position": [0.0, 1.6, 0.0]}}], "robots[0].spawn.position",
     ["starts inside 'shelf_1_plinth'"]),
])
def test_bad_worlds_name_scenario_field_and_world_file(tmp_path: Path, world: dict[str, Any],
                                                       robots: list[dict[str, Any]],
                                                       field: str, words: list[str]) -> None:
    shutil.copy(WORLD, tmp_path / "shelf.xml")
    shutil.copytree(WORLD.parent / "meshes", tmp_path / "meshes")
    (tmp_path / "broken.xml").write_text("<mujoco><worldbody><oops/></worldbody></mujoco>")
    (tmp_path / "broken.urdf").write_text("<robot name='x'><link name='a'></robot>")
    (tmp_path / "nomesh.xml").write_text(
        "<mujoco><asset><mesh name='m' file='nope.obj'/></asset><worldbody>"
        "<geom type='mesh' mesh='m'/></worldbody></mujoco>")
    (tmp_path / "motor.xml").write_text(
        "<mujoco><worldbody><body name='door'><joint name='hinge'/>"
        "<geom type='box' size='0.5 0.05 1'/></body></worldbody>"
        "<actuator><motor name='door_motor' joint='hinge'/></actuator></mujoco>")
    path = scenario_file(tmp_path, world, robots)
    with pytest.raises(ScenarioError) as info:
        api.validate(load_scenario(path), source=str(path))
    err = info.value
    assert (err.file, err.field) == (str(path), field)
    for word in words:
        assert word in err.message
    assert "\n" not in str(err)


def test_srr_validate_answers_a_missing_world_file_with_one_line_and_exit_2(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = scenario_file(tmp_path, {"model": {"mjcf": "nowhere/site.xml"}})
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert err == (f"srr validate: {path}: world.model.mjcf: {tmp_path / 'nowhere/site.xml'}: "
                   "file not found")
    assert main(["validate", str(SCENARIO)]) == 0


def test_world_map_reads_back_leniently() -> None:
    assert world_map({}) is None
    wm = world_map({"world_map": {"file": "x.xml", "mode": "extend", "footprints": [
        {"name": "ok", "points": [[0, 0], [1, 0], [1, 1]]},
        {"name": "short", "points": [[0, 0], [1, 0]]},
        {"name": "junk", "points": [["a", 0], [1, 0], [1, 1]]},
        {"name": "nan", "points": [[0, 0], [1, float("nan")], [1, 1]]},
        "not a mapping"]}})
    assert wm is not None and [o.name for o in wm.outlines] == ["ok"]
    assert json.dumps(wm.outlines[0].points) == "[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]"


def test_a_replaced_warehouse_is_not_drawn_without_the_recorded_map(tmp_path: Path) -> None:
    """A run directory without ``world_map`` (recovered after a crash): the map draws no
    warehouse the scenario did not have."""
    sc = load_scenario(SCENARIO)
    svg = map_svg(RunData(tmp_path, {}, "", scenario=sc))
    assert svg and "warehouse floor" not in svg and 'class="shelf"' not in svg
    assert 'class="static"' not in svg
