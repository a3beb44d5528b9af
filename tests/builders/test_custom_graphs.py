"""``graphs:``: your own builders — loading, the context, idempotence and one-line errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.builders import BuildContext, build_all
from harness.builders.custom import RobotPrims
from harness.cli import main
from harness.graph import GraphStage, stage_to_dict
from harness.graph.errors import GraphError
from harness.scenario import load_scenario
from harness.sim import World
from tests.builders import graph_plugins

SCENE = """\
format_version: 1
name: t
duration: 1
world: {size: [6.0, 6.0], shelves: [], dock: {enabled: false}}
robots:
  - name: tb
    model: turtlebot3_waffle_pi
    sensors: {lidar: {graph: false}}
graphs:
"""
P = "tests.builders.graph_plugins"


def write(tmp_path: Path, graphs: str) -> Path:
    path = tmp_path / "scenario.yaml"
    path.write_text(SCENE + graphs)
    return path


def built(path: Path) -> tuple[GraphStage, BuildContext, list[str]]:
    sc = load_scenario(path)
    stage, bc = GraphStage(), BuildContext(sc, World.build(sc), source=str(path))
    with stage:
        return stage, bc, build_all(bc)


def test_builder_gets_its_path_params_and_robot_prims(tmp_path: Path) -> None:
    path = write(tmp_path, f"  - {{builder: '{P}:clock', params: {{topic: /clock2}}}}\n")
    stage, _, paths = built(path)
    assert paths[-1] == "/World/clockGraph" and paths[0] == "/World/ClockPublisherGraph"
    ctx = graph_plugins.SEEN[-1]
    assert (ctx.name, ctx.field, dict(ctx.params)) == ("clock", "graphs[0]", {"topic": "/clock2"})
    tb: RobotPrims = ctx.robot
    assert (tb.prim, tb.articulation_root) == ("/World/tb", "/World/tb/base_footprint")
    assert tb.link("base_scan") == "/World/tb/base_scan"
    assert tb.joint("wheel_left_joint") == "/World/tb/base_link/wheel_left_joint"
    assert tb.sensor("lidar") == "/World/tb/base_scan/lidar" and ctx.has_prim(tb.sensor("lidar"))
    assert "/World/tb_LidarGraph" not in paths  # graph: false mounts it without its graph
    with pytest.raises(GraphError, match=r"no link 'base_scn'.*base_scan"):
        tb.link("base_scn")
    node = stage.graph("/World/clockGraph").node("PublishClock")
    assert node.canonical_type == "srr.PublishClock"  # the real node type, not a stand-in


def test_building_twice_gives_the_same_stage(tmp_path: Path) -> None:
    stage, bc, paths = built(write(tmp_path, f"  - {{builder: '{P}:clock'}}\n"))
    first = stage_to_dict(stage)
    with stage:
        assert build_all(bc) == paths
    assert stage_to_dict(stage) == first


@pytest.mark.parametrize(("graphs", "field", "words"), [
    ("  - {builder: 'no_such_pkg.graphs:build'}\n", "graphs[0].builder",
     "cannot import module 'no_such_pkg.graphs'"),
    (f"  - {{builder: '{P}:nope'}}\n", "graphs[0].builder", f"module '{P}' has no 'nope'"),
    (f"  - {{builder: '{P}:NOT_A_FUNCTION'}}\n", "graphs[0].builder", "is not a function"),
    (f"  - {{builder: '{P}:raises'}}\n", "graphs[0].builder",
     "raised ValueError: no robot arm in this scene"),
    (f"  - {{builder: '{P}:unknown_node'}}\n", "graphs[0].builder",
     "raised GraphError: /World/unknown_nodeGraph/Pub: unknown node type"),
    (f"  - {{builder: '{P}:takes_the_clock_path'}}\n", "graphs[0].builder",
     "built /World/ClockPublisherGraph, a path already taken by the built-in clock graph"),
    (f"  - {{builder: '{P}:clock', name: ClockPublisher}}\n", "graphs[0].name",
     "graph path /World/ClockPublisherGraph is already taken by the built-in clock graph"),
    (f"  - {{builder: '{P}:clock', name: tb_Tf}}\n", "graphs[0].name",
     "the built-in tf tree graph of robots[0] (tb)"),
    (f"  - {{builder: '{P}:clock'}}\n  - {{builder: '{P}:clock', name: clock}}\n",
     "graphs[1].name", "duplicate graph name 'clock'"),
    ("  - {builder: 'no_colon'}\n", "graphs[0].builder", "expected 'module:function'"),
    (f"  - {{builder: '{P}:clock', robot: tb3}}\n", "graphs[0].robot", "did you mean 'tb'"),
], ids=["import", "missing", "not-callable", "raises", "unknown-node", "path-collision",
        "name-collision", "robot-graph-collision", "duplicate", "format", "robot"])
def test_bad_builder_is_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                        graphs: str, field: str, words: str) -> None:
    path = write(tmp_path, graphs)
    for command in ("validate", "run"):
        extra = ["--out", str(tmp_path / "out")] if command == "run" else []
        assert main([command, str(path), *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"srr {command}: {path}: {field}: ") and words in err, err
        assert len(err.splitlines()) == 1


@pytest.mark.parametrize(("node_type", "input_name"), [
    ("isaacsim.core.nodes.IsaacCreateRenderProduct", "cameraPrim"),
    ("isaacsim.ros2.bridge.ROS2PublishTransformTree", "targetPrims"),
    ("isaacsim.core.nodes.IsaacComputeOdometry", "chassisPrim"),
])
def test_a_prim_that_does_not_exist_is_refused_by_validate_as_by_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], node_type: str,
        input_name: str) -> None:
    # validate said ok and run stopped at its first tick, naming neither file nor entry
    path = write(tmp_path, f"  - {{builder: '{P}:missing_prim', name: Cam, params: "
                           f"{{type: {node_type}, input: {input_name}}}}}\n")
    out = tmp_path / "out"
    for command in ("validate", "run"):
        extra = ["--out", str(out)] if command == "run" else []
        assert main([command, str(path), *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert err == (f"srr {command}: {path}: graphs[0]: /World/CamGraph/Node.inputs:"
                       f"{input_name}: prim '/World/tb/no_such_camera' does not exist"), err
        assert not out.exists()
