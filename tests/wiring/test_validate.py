"""Wiring collisions are refused before anything runs, by ``srr validate`` and ``srr run``
alike: exit 2 and one line naming the file and the scenario field (never a node attribute
path, never exit 3), and no run directory left behind."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from harness import api
from harness.cli import main

_SHOWWARNING = warnings.showwarning

HEAD = """\
format_version: 1
name: w
duration: 1
"""
FORKLIFT = """\
  - name: {name}
    model: forklift
    spawn: {{position: [{x}, {y}, 0.0]}}
"""
TB3 = """\
  - name: {name}
    model: turtlebot3_waffle_pi
    spawn: {{position: [{x}, {y}, 0.0]}}
"""
FOLLOWER = """\
  - name: follow_{robot}
    robot: {robot}
    plugin: harness.sut.teleop:ScriptedTeleop
    params: {{segments: [{{duration: 1.0, linear: 0.1}}]}}
"""


def robot(template: str, name: str, x: float = 0.0, y: float = 0.0, extra: str = "") -> str:
    return template.format(name=name, x=x, y=y) + extra


def scenario(*robots: str, suts: str = "", rest: str = "") -> str:
    text = HEAD + "robots:\n" + "".join(robots)
    if suts:
        text += "systems_under_test:\n" + suts
    return text + rest


def run_cli(capsys: pytest.CaptureFixture[str], tmp_path: Path, text: str,
            command: str = "validate") -> tuple[int, str, str]:
    path = tmp_path / "w.yaml"
    path.write_text(text)
    argv = [command, str(path)]
    if command == "run":
        argv += ["--out", str(tmp_path / "out"), "-q"]
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err.strip()


def drive(*names: str) -> str:
    return "".join(FOLLOWER.format(robot=n) for n in names)


CASES = {
    # one topic, two types: a robot's odometry on the clock's topic
    "two_types": (
        scenario(robot(FORKLIFT, "forklift", extra="    odometry: {odom_topic: /clock}\n"),
                 suts=drive("forklift")),
        "robots[0].odometry.odom_topic",
        ["/clock", "nav_msgs/msg/Odometry", "clock.clock_topic", "rosgraph_msgs/msg/Clock"]),
    # two robots in one namespace publish one odometry topic
    "two_publishers": (
        scenario(robot(FORKLIFT, "a", extra="    namespace: ''\n"),
                 robot(FORKLIFT, "b", y=3, extra="    namespace: ''\n"),
                 rest="systems_under_test:\n  - {name: t, plugin: 'harness.sut.teleop:"
                      "ScriptedTeleop', params: {segments: [{duration: 1, linear: 0.1}]}}\n"),
        "robots[1].odometry.odom_topic",
        ["/odom", "robots[0].odometry.odom_topic", "give each its own `namespace`"]),
    # two robots' graphs publish the same child frame (no frame prefixes)
    "same_child_frame": (
        scenario(robot(FORKLIFT, "a", extra="    frame_prefix: ''\n"),
                 robot(FORKLIFT, "b", y=3, extra="    frame_prefix: ''\n"),
                 suts=drive("a", "b")),
        "robots[1].odometry.base_frame",
        ["TF: frame 'base_link'", "2 sources", "robots[0].odometry.base_frame"]),
    # a forklift and a TurtleBot3 without prefixes: base_link gets two parents
    "two_parents": (
        scenario(robot(FORKLIFT, "lift", extra="    frame_prefix: ''\n"),
                 robot(TB3, "tb3", y=3, extra="    frame_prefix: ''\n"),
                 suts=drive("lift", "tb3")),
        "robots[1].tf_tree",
        ["TF: frame 'base_link' has 2 parents", "'odom' from robots[0].odometry.base_frame",
         "'base_footprint' from robots[1].tf_tree"]),
    # world frame named like the base frame: base_link → odom → base_link
    "cycle": (
        scenario(robot(FORKLIFT, "forklift", extra="    tf_tree: {world_frame: base_link}\n"),
                 suts=drive("forklift")),
        "robots[0].odometry.base_frame",
        ["TF: frames form a cycle", "base_link → odom → base_link"]),
    "leading_slash": (
        scenario(robot(FORKLIFT, "forklift", extra="    odometry: {odom_frame: /odom}\n")),
        "robots[0].odometry.odom_frame", ["'/odom' starts with '/'"]),
    "space_in_frame": (
        scenario(robot(TB3, "tb3", extra="    sensors: {imu: {frame_id: imu link}}\n")),
        "robots[0].sensors.imu.frame_id", ["'imu link' contains whitespace"]),
    "space_in_prefix": (
        scenario(robot(FORKLIFT, "forklift", extra="    frame_prefix: 'fork lift/'\n")),
        "robots[0].frame_prefix", ["contains whitespace"]),
    "empty_part_in_prefix": (
        scenario(robot(FORKLIFT, "forklift", extra="    frame_prefix: 'lift//'\n")),
        "robots[0].frame_prefix", ["has an empty part ('//')", "write 'lift/'"]),
    "one_prim": (
        scenario(robot(FORKLIFT, "a", extra="    articulation_prim: /World/lift\n"),
                 robot(FORKLIFT, "b", y=3, extra="    articulation_prim: /World/lift\n")),
        "robots[1].articulation_prim", ["/World/lift is also the prim of robots[0] (a)"]),
    "prim_inside_prim": (
        scenario(robot(FORKLIFT, "a", extra="    articulation_prim: /World/lift\n"),
                 robot(FORKLIFT, "b", y=3, extra="    articulation_prim: /World/lift/b\n")),
        "robots[1].articulation_prim", ["/World/lift/b lies inside /World/lift"]),
    # the story of issue 8: a second forklift, one unbound driver publishing /cmd_vel
    "unfed_cmd_vel": (
        scenario(robot(FORKLIFT, "forklift"), robot(FORKLIFT, "forklift_b", y=3),
                 rest="systems_under_test:\n  - {name: t, plugin: 'harness.sut.teleop:"
                      "ScriptedTeleop', params: {segments: [{duration: 1, linear: 0.1}]}}\n"),
        "robots[0].control.cmd_vel_topic",
        ["nothing publishes /forklift/cmd_vel", "published: /cmd_vel by systems_under_test[0]",
         "`robot: forklift`", "`control: {enabled: false}`"]),
    # scoring reads a topic nothing publishes (the driver moved into the robot's namespace)
    "scoring_reference": (
        scenario(robot(FORKLIFT, "forklift"), robot(FORKLIFT, "forklift_b", y=3),
                 suts=drive("forklift", "forklift_b"),
                 rest="scoring: {health: {sut_outputs: {/cmd_vel: 0.5}}}\n"),
        "scoring.health.sut_outputs./cmd_vel",
        ["nothing in the scenario publishes /cmd_vel, so it cannot be scored",
         "published: /forklift/cmd_vel, /forklift_b/cmd_vel"]),
    "scoring_type": (
        scenario(robot(FORKLIFT, "forklift"), suts=drive("forklift"),
                 rest="srr_gt: true\nscoring: {perception: {marker_topics: [/odom]}}\n"),
        "scoring.perception.marker_topics[0]",
        ["/odom carries nav_msgs/msg/Odometry", "needs visualization_msgs/msg/MarkerArray"]),
    "bad_namespace": (
        scenario(robot(FORKLIFT, "a", extra="    namespace: 9lives\n")),
        "robots[0].namespace", ["'9lives'", "must not start with a digit"]),
    "bad_sut_namespace": (
        scenario(robot(FORKLIFT, "a"), suts=drive("a") + "    namespace: 'x y'\n"),
        "systems_under_test[0].namespace", ["'x y'"]),
    "bad_remap": (
        scenario(robot(FORKLIFT, "a"), suts=drive("a") + "    remap: {cmd_vel: 'a//b'}\n"),
        "systems_under_test[0].remap.cmd_vel", ["'//'"]),
    "sut_robot_missing": (
        scenario(robot(FORKLIFT, "forklift"), suts=drive("forklfit")),
        "systems_under_test[0].robot", ["no enabled robot named 'forklfit'",
                                        "did you mean 'forklift'"]),
}


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("command", ["validate", "run"])
def test_each_collision_exits_2_naming_file_and_field(
        case: str, command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text, field, words = CASES[case]
    code, _, err = run_cli(capsys, tmp_path, text, command)
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"srr {command}: {tmp_path / 'w.yaml'}: {field}: "), err
    for w in words:
        assert w in err, err
    assert "/World/" not in err.split(":", 3)[2]  # the field is a scenario path, not a node
    assert not (tmp_path / "out").exists()  # nothing half-written


def test_an_error_in_an_included_file_names_that_file(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "fleet.yaml").write_text(
        "robots:\n" + robot(FORKLIFT, "a", extra="    frame_prefix: ''\n")
        + robot(FORKLIFT, "b", y=3, extra="    frame_prefix: ''\n"))
    code, _, err = run_cli(capsys, tmp_path, HEAD + "include: [fleet.yaml]\n"
                           "systems_under_test:\n" + drive("a", "b"))
    assert code == 2
    assert err.startswith(f"srr validate: {tmp_path / 'fleet.yaml'}: "
                          "robots[1].odometry.base_frame: TF: "), err


def test_unfed_inputs_of_systems_under_test_are_warnings(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = scenario(robot(FORKLIFT, "forklift"), suts=drive("forklift") + (
        "  - {name: monitor, robot: forklift, plugin: 'harness.sut.safety_monitor:SafetyMonitor',"
        " params: {roi: [[0, 0], [1, 0], [1, 1]], tripwire: [[2, 1], [2, 0]]}}\n"))
    code, out, err = run_cli(capsys, tmp_path, text)
    assert code == 0, err
    assert "ok" in out and "1 warning(s)" in out
    (line,) = err.splitlines()
    assert line.startswith(f"srr validate: warning: {tmp_path / 'w.yaml'}: "
                           "systems_under_test[1]: systems_under_test[1] (monitor) subscribes "
                           "to /perception/tracks"), line


def test_a_parked_robot_nothing_drives_is_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run_cli(capsys, tmp_path, scenario(robot(FORKLIFT, "forklift")))
    assert code == 0
    assert "robots[0].control.cmd_vel_topic: this graph subscribes to /cmd_vel" in err
    assert "(the robot will not be driven)" in err
    # switching the graph off says it on purpose: no warning
    code, _, err = run_cli(capsys, tmp_path, scenario(robot(
        FORKLIFT, "forklift", extra="    control: {enabled: false}\n")))
    assert code == 0 and err == ""


@pytest.mark.parametrize(("base", "warned"), [("base", True), ("base_footprint", False)])
def test_a_base_frame_outside_the_link_tree_is_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], base: str, warned: bool) -> None:
    """odom → a frame the robot's link tree does not have joins nothing: tf2 takes the
    forest, but nothing looking up from odom finds the links."""
    extra = f"    odometry: {{base_frame: {base}}}\n"
    code, _, err = run_cli(capsys, tmp_path, scenario(robot(TB3, "tb3", extra=extra),
                                                      suts=drive("tb3")))
    assert code == 0, err
    said = (f"srr validate: warning: {tmp_path / 'w.yaml'}: robots[0].odometry.base_frame: "
            "'base' is no frame of the robot's link tree (its root: 'base_footprint'), so "
            "odom → base joins nothing and the links hang from a root of their own, where "
            "nothing looking up from odom finds them; name 'base_footprint' or leave the "
            "field out")
    assert (said in err.splitlines()) is warned, err


def test_a_library_s_warnings_are_one_line_each(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A Python warning and a harness log record raised while a command runs are said as
    the command's warnings are: one line each, not a file, a line and a source line."""
    code, _, err = run_cli(capsys, tmp_path, scenario(
        robot(FORKLIFT, "forklift", extra="    control: {enabled: false}\n"),
        suts="  - {name: w, plugin: 'tests.wiring.plugins:WarnsInSetup'}\n"))
    assert code == 0, err
    assert err.splitlines() == [
        "srr validate: warning: Inertia matrix is too close to singular\\x1b",
        "srr validate: warning: MuJoCo: contact buffer is full"]
    assert warnings.showwarning is _SHOWWARNING  # put back after the command


def test_bundled_scenarios_validate(scenarios_dir: Path) -> None:
    for path in sorted(scenarios_dir.glob("*.yaml")) + sorted(
            scenarios_dir.glob("regressions/*.yaml")):
        api.validate(api.load(path), source=str(path))
