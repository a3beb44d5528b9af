"""Semantic checks of a scenario beyond its types: defaults that follow the scene, values the
simulation cannot give, positions outside the world. Each is refused in one line (exit 2)
naming the file and the field, by ``srr validate`` as by ``srr run``."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main
from harness.scenario import load_scenario


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    return path


def _validate(capsys: pytest.CaptureFixture[str], path: Path) -> tuple[int, str, str]:
    code = main(["validate", str(path)])
    out, err = capsys.readouterr()
    return code, out.strip(), err.strip()


TB3 = """\
format_version: 1
name: t
duration: 2
srr_gt: true
robots:
  - {name: tb3, model: turtlebot3_waffle_pi}
routes:
  r: {waypoints: [[0, 0], [1, 0]]}
"""


def test_control_scoring_defaults_to_the_only_robot(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, TB3 + "scoring:\n  control: {route: r}\n")
    assert load_scenario(path).scoring.control.robot == "tb3"  # type: ignore[union-attr]
    code, _out, err = _validate(capsys, path)
    assert code == 0, err


def test_control_scoring_without_robot_in_a_two_robot_scene_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    two = TB3.replace("robots:\n", "robots:\n  - {name: other, model: turtlebot3_waffle_pi,"
                      " spawn: {position: [2, 2, 0]}}\n")
    path = _write(tmp_path, two + "scoring:\n  control: {route: r}\n")
    code, _out, err = _validate(capsys, path)
    assert code == 2
    assert len(err.splitlines()) == 1
    assert f"{path}: scoring.control.robot: " in err
    assert "tb3" in err and "other" in err


PLUGINS = """\
format_version: 1
name: t
duration: 2
robots:
  - {name: forklift, model: forklift}
routes:
  r: {waypoints: [[0, 0], [1, 0]]}
zones:
  loading_roi: [[10, -2], [14, -2], [14, 2], [10, 2]]
  trailer_tripwire: {a: [12, -1], b: [12, 1]}
systems_under_test:
  - {name: sut, plugin: "harness.sut.PLUGIN", params: {PARAMS}}
"""


@pytest.mark.parametrize(("plugin", "params", "field", "words"), [
    ("safety_monitor:SafetyMonitor", "rate_hz: 0", "rate_hz", "must be > 0"),
    ("safety_monitor:SafetyMonitor", "reaction_delay: -1", "reaction_delay", "must be >= 0"),
    ("safety_monitor:SafetyMonitor", "inside: up", "inside", "expected one of"),
    ("route_follower:RouteFollower", "route: r, rate_hz: 0", "rate_hz", "must be > 0"),
    ("route_follower:RouteFollower", "route: r, slow_radius: 0", "slow_radius",
     "must be > 0"),
    ("route_follower:RouteFollower", "route: r, speed: -1", "speed", "must be > 0"),
    ("perception:DepthPeopleTracker", "cameras: [], cell: 0", "cell", "must be > 0"),
    ("perception:DepthPeopleTracker", "cameras: [], pixel_stride: 0", "pixel_stride",
     "must be >= 1"),
    ("perception:DepthPeopleTracker", "cameras: [], z_max: 0.1", "z_max", "must be above"),
    ("teleop:ScriptedTeleop", "segments: [{duration: 1}], rate_hz: 0", "rate_hz",
     "must be > 0"),
])
def test_plugin_parameter_out_of_range_is_one_line_exit_2(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], plugin: str, params: str,
        field: str, words: str) -> None:
    path = _write(tmp_path, PLUGINS.replace("PLUGIN", plugin).replace("PARAMS", params))
    code, _out, err = _validate(capsys, path)
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert f"{path}: systems_under_test[0].params.{field}: " in err, err
    assert words in err, err


@pytest.mark.parametrize(("robot", "field", "words"), [
    ("{name: tb3, model: turtlebot3_waffle_pi, control: {joint_names: ['ñ/é', "
     "wheel_right_joint]}}", "robots[0].control.joint_names", "are not joints of"),
    ("{name: fl, model: forklift, control: {drive_joint: back_wheel_swivel}}",
     "robots[0].control.drive_joint", "distinct"),
    ("{name: fl, model: forklift, control: {swivel_joint: front_left_wheel_joint}}",
     "robots[0].control.swivel_joint", "front wheel joint"),
])
def test_builtin_robot_joint_names_are_checked_against_the_file(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], robot: str, field: str,
        words: str) -> None:
    path = _write(tmp_path, f"format_version: 1\nname: t\nduration: 2\nrobots:\n  - {robot}\n")
    code, _out, err = _validate(capsys, path)
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert f"{path}: {field}: " in err and words in err, err


ROOM = """\
format_version: 1
name: t
duration: 2
world: {size: [30, 20]}
robots:
  - {name: forklift, model: forklift, spawn: {position: [0, 0, 0]}}
"""


@pytest.mark.parametrize(("change", "field", "words"), [
    ("  - {name: far, model: forklift, spawn: {position: [40, 0, 0]}}\n",
     "robots[1].spawn.position", "(40, 0) is outside the 30 x 20 m room"),
    ("workers:\n  - {route: [[0, 5], [0, 30]]}\n", "workers[0].route[1]",
     "(0, 30) is outside"),
    ("cameras:\n  - {name: cam, spawn: {position: [-20, 0, 3]}, outputs: [rgb]}\n",
     "cameras[0].spawn.position", "(-20, 0) is outside"),
    ("routes:\n  go: {waypoints: [[0, 0], [1e308, 0]]}\n", "routes.go.waypoints[1]",
     "(1e+308, 0) is outside"),
])
def test_things_placed_outside_the_world_are_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], change: str, field: str,
        words: str) -> None:
    path = _write(tmp_path, ROOM + change)
    code, _out, err = _validate(capsys, path)
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert f"{path}: {field}: " in err and words in err, err


def test_inside_the_trailer_is_inside_the_world(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    """The default trailer reaches from x = 12 to 24 beyond the east wall (x = 15): a robot
    and a worker in it stand on the floor."""
    path = _write(tmp_path, ROOM.replace("[0, 0, 0]", "[20, 0, 0]")
                  + "workers:\n  - {route: [[10, 0], [22, 0.5]]}\n")
    code, _out, err = _validate(capsys, path)
    assert code == 0, err


@pytest.mark.parametrize(("world", "field", "words"), [
    ("{size: [10, 10]}", "world.shelves[0]", "a default shelf"),
    ("{size: [10, 10], shelves: []}", "world.dock.position", "the default dock"),
    ("{size: [10, 10], shelves: [{position: [4, 0]}]}", "world.shelves[0]",
     "reaches outside the 10 x 10 m room"),
])
def test_shelves_and_dock_outside_a_smaller_room_are_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], world: str, field: str,
        words: str) -> None:
    path = _write(tmp_path, ROOM.replace("{size: [30, 20]}", world))
    code, _out, err = _validate(capsys, path)
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert f"{path}: {field}: " in err and words in err, err


RATES = """\
format_version: 1
name: t
duration: 3
physics: {tick_hz: TICK}
robots:
  - name: tb3
    model: turtlebot3_waffle_pi
    sensors: {imu: {fps: IMU}}
cameras:
  - {name: cam, outputs: [rgb], fps: CAM}
"""


def _rates(tick: int, imu: float, cam: float) -> str:
    return (RATES.replace("TICK", str(tick)).replace("IMU", str(imu))
            .replace("CAM", str(cam)))


@pytest.mark.parametrize(("tick", "imu", "cam", "field", "words"), [
    (7, 7, 30, "cameras[0].fps", "30 Hz cannot be given on the 7 Hz tick"),
    (60, 50, 30, "robots[0].sensors.imu.fps", "it would publish at 60 Hz"),
])
def test_a_sensor_rate_the_tick_cannot_give_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], tick: int, imu: float, cam: float,
        field: str, words: str) -> None:
    path = _write(tmp_path, _rates(tick, imu, cam))
    code, _out, err = _validate(capsys, path)
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert f"{path}: {field}: " in err and words in err, err


def test_a_sensor_rate_slightly_off_is_warned_about(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, _rates(60, 60, 7))
    code, _out, err = _validate(capsys, path)
    assert code == 0, err
    assert f"warning: {path}: cameras[0].fps: 7 Hz" in err and "6.667 Hz" in err, err


def test_the_rate_gate_expects_the_rate_asked_for(tmp_path: Path) -> None:
    """7 Hz on a 60 Hz tick publishes every 9th tick (6.67 Hz): with rate_fraction 1 the
    gate must trip, not expect the 6.67 Hz the tick delivers."""
    import pandas as pd

    from harness.metrics.health import topic_rates
    from harness.scoring import expected_rates

    sc = load_scenario(_write(tmp_path, _rates(60, 60, 7)))
    expected = expected_rates(sc)
    assert expected["/cam_rgb"] == 7.0
    delivered = pd.DataFrame({"name": ["/cam_rgb"], "count": [20]})  # 180 ticks / 9
    [gate] = topic_rates(delivered, {"/cam_rgb": expected["/cam_rgb"]}, duration_s=3.0,
                         min_fraction=1.0)
    assert not gate.ok, gate.detail


CAMERA = """\
format_version: 1
name: t
duration: 45
robots:
  - {name: forklift, model: forklift}
cameras:
  - {name: cam, spawn: {position: [0, 0, 3]}}
"""


def test_a_camera_left_to_its_defaults_publishes_no_point_cloud(tmp_path: Path) -> None:
    from harness.diskspace import estimate_bag_bytes

    sc = load_scenario(_write(tmp_path, CAMERA))
    assert sc.cameras[0].outputs == ("rgb", "depth", "camera_info")
    parts = dict(estimate_bag_bytes(sc).parts)
    assert "cam_pointcloud" not in parts and "cam_rgb" in parts and "cam_depth" in parts
    assert estimate_bag_bytes(sc).total < 1e9  # 45 s of the default camera: ~0.6 GB


def test_a_large_bag_is_announced_by_validate_and_before_a_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, CAMERA.replace(
        "{name: cam,", "{name: cam, outputs: [rgb, depth, pointcloud, camera_info],"))
    code, _out, err = _validate(capsys, path)
    assert code == 0, err
    assert f"warning: {path}: the bag will be up to about 2.0 GB for 45 s (cam_pointcloud" \
        in err, err
    # The run announces it before building anything; a plug-in refused while building then
    # stops it before the first tick (so the test does not record 2 GB).
    bad = _write(tmp_path, path.read_text() + "systems_under_test:\n  - {name: m, plugin: "
                 "'harness.sut.teleop:ScriptedTeleop', params: {segments: [], rate_hz: 0}}\n")
    code = main(["run", str(bad), "--out", str(tmp_path / "run"), "-q"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "srr run: the bag will be up to about 2.0 GB for 45 s" in err, err
    assert "systems_under_test[0].params.rate_hz" in err, err
    assert not (tmp_path / "run" / "bag").exists()


def test_a_robot_camera_stamped_in_its_link_frame_is_warned_about(
        capsys: pytest.CaptureFixture[str]) -> None:
    # frame_id == link: the images are in the link's axes (+X forward), not an optical frame
    room = Path(__file__).resolve().parents[2] / "scenarios" / "turtlebot3_room.yaml"
    assert main(["validate", str(room)]) == 0
    assert "optical" not in capsys.readouterr().err
    assert main(["validate", str(room), "--set",
                 "robots.0.sensors.camera.frame_id=camera_link"]) == 0
    err = capsys.readouterr().err
    assert ("warning: --set: robots[0].sensors.camera.frame_id: 'camera_link' is the camera "
            "link's own frame (+X forward)") in err
    assert "camera_link_optical" in err


@pytest.mark.parametrize(("change", "field", "words"), [
    ("routes:\n  go: {waypoints: [[-12, 0], [0, 6]]}\n", "routes.go.waypoints[1]",
     "(0, 6) is inside the shelf at (2, 6) (world.shelves[1]): a robot"),
    ("workers:\n  - {route: [[-4, -3], [-4, -6]]}\n", "workers[0].route[1]",
     "(-4, -6) is inside the shelf at (-6, -6) (world.shelves[2]): the worker"),
])
def test_waypoints_inside_a_shelf_are_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], change: str, field: str,
        words: str) -> None:
    """A route through a rack drives the robot into it; a worker walks through it (workers
    are kinematic): both refused before the run, naming the shelf."""
    path = _write(tmp_path, ROOM + change)
    code, _out, err = _validate(capsys, path)
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert f"{path}: {field}: " in err and words in err, err
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    assert words in capsys.readouterr().err


def test_waypoints_beside_a_shelf_and_a_disabled_worker_in_one_are_accepted(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, ROOM + "routes:\n  go: {waypoints: [[-12, 0], [0, 5]]}\n"
                  "workers:\n  - {route: [[-4, -3], [-4, -6]], enabled: false}\n")
    code, _out, err = _validate(capsys, path)
    assert code == 0, err


def test_a_worker_starting_after_the_run_ends_is_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, ROOM + "workers:\n  - {name: bob, route: [[4, 3], [4, -3]], "
                  "start_delay: 2}\n  - {route: [[2, 3], [2, -3]], start_delay: 1.5}\n")
    code, _out, err = _validate(capsys, path)
    assert code == 0, err
    mine = [line for line in err.splitlines() if "start_delay" in line]
    assert mine == [
        f"srr validate: warning: {path}: workers[0].start_delay: 2 s is not before the end of "
        "the run (duration 2 s): worker 'bob' stands at its first waypoint the whole run"], err
