# mypy: disable-error-code="no-untyped-def, list-item"
"""Isaac Sim builder snippets from the seeds, ported by changing imports only.

* ``000``: the clock graph (OnPlaybackTick + IsaacReadSimulationTime + ROS1PublishClock) and
  the ``add_tf`` helper (``graph.get_path_to_graph``, ``create_node``, ``connect``,
  ``attribute(...).set``);
* ``001``: ``publish_camera_tf`` -- a ``/CameraTFActionGraph`` created from a config dict, then
  extended by string path with absolute connection paths.

The ROS publisher types are the fakes of ``conftest.py`` (same Isaac names). Seed 000's six
helpers run end to end with the real node types, the bus and the recorder in
``tests/e2e/test_seed000_graphs.py``.
"""

from __future__ import annotations

from typing import List, Optional  # noqa: UP035  (kept as the seed wrote it)

import pytest

import harness.graph as og
from harness.graph import usdrt
from harness.graph.errors import GraphError
from tests.seed001 import Camera, is_prim_path_valid, publish_camera_tf, set_target_prims

from .conftest import Ctx, run_ticks

controller = og.Controller
keys = controller.Keys


# --- seed 000: the simplest graph, verbatim -------------------------------------------------


def build_clock_graph() -> og.Graph:
    graph_config = {"graph_path": "/ActionGraph", "evaluator_name": "execution"}
    graph, _, _, _ = controller.edit(
        graph_config,
        {
            keys.CREATE_NODES: [
                ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
                ("ReadSimTime", "omni.isaac.core_nodes.IsaacReadSimulationTime"),
                ("PublishClock", "omni.isaac.ros_bridge.ROS1PublishClock"),
            ],
            og.Controller.Keys.CONNECT: [
                ("OnPlaybackTick.outputs:tick", "PublishClock.inputs:execIn"),
                ("ReadSimTime.outputs:simulationTime", "PublishClock.inputs:timeStamp"),
            ],
            og.Controller.Keys.SET_VALUES: [
                ("PublishClock.inputs:topicName", "/clock"),
            ]
        }
    )
    return graph


def add_tf(graph, ogn_node_name, target_prims: List[str], topic_name = "tf", parent_prim: Optional[str] = None, namespace: Optional[str] = None):  # noqa: E501, UP006, UP045
    graph_path = graph.get_path_to_graph()
    tick_node_path = graph_path + '/OnPlaybackTick'
    ros_clock_node_path = graph_path + '/ReadSimTime'
    publish_tf_path = graph_path + '/' + ogn_node_name
    controller = og.Controller
    controller.create_node(publish_tf_path, "omni.isaac.ros_bridge.ROS1PublishTransformTree")
    controller.connect(tick_node_path+'.outputs:tick',publish_tf_path+'.inputs:execIn')
    controller.connect(ros_clock_node_path+'.outputs:simulationTime', publish_tf_path+'.inputs:timeStamp')  # noqa: E501
    controller.attribute(publish_tf_path+'.inputs:targetPrims').set(target_prims)
    if(namespace is not None):
        controller.attribute(publish_tf_path+'.inputs:nodeNamespace').set(namespace)
    if(parent_prim is not None):
        controller.attribute(publish_tf_path+'.inputs:parentPrim').set(parent_prim)


def test_clock_graph_structure(stage: og.GraphStage) -> None:
    graph = build_clock_graph()
    assert graph is stage.graph("/ActionGraph")
    assert [n.name for n in graph.nodes] == ["OnPlaybackTick", "ReadSimTime", "PublishClock"]
    assert [n.canonical_type for n in graph.nodes] == [
        "srr.OnPlaybackTick", "srr.ReadSimulationTime", "test.PublishClock",
    ]
    assert graph.node("ReadSimTime").type_name == "omni.isaac.core_nodes.IsaacReadSimulationTime"
    assert [(c.src, c.dst, c.kind) for c in graph.connections] == [
        ("OnPlaybackTick.outputs:tick", "PublishClock.inputs:execIn", "exec"),
        ("ReadSimTime.outputs:simulationTime", "PublishClock.inputs:timeStamp", "data"),
    ]
    assert dict(graph.node("PublishClock").values) == {"inputs:topicName": "/clock"}


def test_clock_graph_publishes_sim_time_each_tick(stage: og.GraphStage) -> None:
    build_clock_graph()
    ctx = run_ticks(stage, 4)
    assert [p["topic"] for p in ctx.published] == ["/clock"] * 4
    assert [p["stamp"] for p in ctx.published] == pytest.approx([k / 60 for k in range(4)])


def test_add_tf_helper_extends_the_clock_graph(stage: og.GraphStage) -> None:
    graph = build_clock_graph()
    add_tf(graph, "PubTF", target_prims=["/World/robot/base_link"])
    add_tf(graph, "PubTFStatic", [usdrt.Sdf.Path("/World/robot/imu_link")], "tf_static",
           "/World/robot/base_link", namespace="robot")
    assert [n.name for n in graph.nodes][-2:] == ["PubTF", "PubTFStatic"]
    assert graph.node("PubTFStatic").values["inputs:parentPrim"] == ("/World/robot/base_link",)
    assert graph.node("PubTFStatic").values["inputs:nodeNamespace"] == "robot"
    ctx = run_ticks(stage, 2)
    tf = [p for p in ctx.published if p["node"].startswith("/ActionGraph/PubTF")]
    assert [p["node"] for p in tf] == ["/ActionGraph/PubTF", "/ActionGraph/PubTFStatic"] * 2
    assert tf[1]["targetPrims"] == ("/World/robot/imu_link",)
    assert tf[3]["stamp"] == pytest.approx(1 / 60)


# --- seed 001: publish_camera_tf ------------------------------------------------------------


@pytest.fixture
def camera_stage(stage: og.GraphStage) -> og.GraphStage:
    """The camera helper checks the camera prim exists; stand the camera prims in as graphs."""
    stage.create_graph("/World/floating_camera")
    stage.create_graph("/World/cam2")
    return stage


def test_camera_tf_seed_verbatim(camera_stage: og.GraphStage,
                                 capsys: pytest.CaptureFixture[str]) -> None:
    """The seed has a typo (``PublishRawTF_`` in the last connection): the edit stops there with
    a GraphError naming the node and suggesting the right one; the seed prints it and goes on.
    Operations run in the fixed order DELETE, CREATE_NODES, CREATE_ATTRIBUTES, CONNECT,
    DISCONNECT, SET_VALUES, so the nodes and first three connections exist, the values do not.
    """
    publish_camera_tf(Camera("/World/floating_camera"))
    printed = capsys.readouterr().out
    assert "PublishRawTF_floating_cameraworld" in printed
    assert "did you mean 'PublishRawTFfloating_cameraworld'" in printed
    assert "/CameraTFActionGraph" in printed

    graph = camera_stage.graph("/CameraTFActionGraph")
    assert graph.pipeline_stage is og.GraphPipelineStage.GRAPH_PIPELINE_STAGE_SIMULATION
    assert [n.name for n in graph.nodes] == [
        "OnTick", "IsaacClock", "RosPublisher",
        "PublishTFfloating_camera", "PublishRawTFfloating_cameraworld",
    ]
    assert [(c.src, c.dst) for c in graph.connections] == [
        ("OnTick.outputs:tick", "RosPublisher.inputs:execIn"),
        ("IsaacClock.outputs:simulationTime", "RosPublisher.inputs:timeStamp"),
        ("OnTick.outputs:tick", "PublishTFfloating_camera.inputs:execIn"),
        ("OnTick.outputs:tick", "PublishRawTFfloating_cameraworld.inputs:execIn"),
        ("IsaacClock.outputs:simulationTime", "PublishTFfloating_camera.inputs:timeStamp"),
    ]
    assert dict(graph.node("PublishRawTFfloating_cameraworld").values) == {}
    assert og.Controller.get(
        "/CameraTFActionGraph/PublishTFfloating_camera.inputs:targetPrims"
    ) == ("/World/floating_camera",)


def publish_camera_tf_fixed(camera: Camera) -> None:
    """The seed's helper with the typo fixed; otherwise the same calls."""
    camera_frame_id = camera.prim_path.split("/")[-1]
    ros_camera_graph_path = "/CameraTFActionGraph"
    if not is_prim_path_valid(ros_camera_graph_path):
        og.Controller.edit(
            {
                "graph_path": ros_camera_graph_path,
                "evaluator_name": "execution",
                "pipeline_stage": og.GraphPipelineStage.GRAPH_PIPELINE_STAGE_SIMULATION,
            },
            {
                og.Controller.Keys.CREATE_NODES: [
                    ("OnTick", "omni.graph.action.OnTick"),
                    ("IsaacClock", "isaacsim.core.nodes.IsaacReadSimulationTime"),
                    ("RosPublisher", "isaacsim.ros2.bridge.ROS2PublishClock"),
                ],
                og.Controller.Keys.CONNECT: [
                    ("OnTick.outputs:tick", "RosPublisher.inputs:execIn"),
                    ("IsaacClock.outputs:simulationTime", "RosPublisher.inputs:timeStamp"),
                ],
            },
        )
    tf, raw = "PublishTF" + camera_frame_id, "PublishRawTF" + camera_frame_id + "world"
    og.Controller.edit(
        ros_camera_graph_path,
        {
            og.Controller.Keys.CREATE_NODES: [
                (tf, "isaacsim.ros2.bridge.ROS2PublishTransformTree"),
                (raw, "isaacsim.ros2.bridge.ROS2PublishRawTransformTree"),
            ],
            og.Controller.Keys.SET_VALUES: [
                (tf + ".inputs:topicName", "/tf"),
                (raw + ".inputs:topicName", "/tf"),
                (raw + ".inputs:parentFrameId", camera_frame_id),
                (raw + ".inputs:childFrameId", camera_frame_id + "world"),
                (raw + ".inputs:rotation", [0.5, -0.5, 0.5, 0.5]),
            ],
            og.Controller.Keys.CONNECT: [
                (ros_camera_graph_path + "/OnTick.outputs:tick", tf + ".inputs:execIn"),
                (ros_camera_graph_path + "/OnTick.outputs:tick", raw + ".inputs:execIn"),
                (ros_camera_graph_path + "/IsaacClock.outputs:simulationTime",
                 tf + ".inputs:timeStamp"),
                (ros_camera_graph_path + "/IsaacClock.outputs:simulationTime",
                 raw + ".inputs:timeStamp"),
            ],
        },
    )
    set_target_prims(
        primPath=ros_camera_graph_path + "/" + tf,
        inputName="inputs:targetPrims",
        targetPrimPaths=[camera.prim_path],
    )


def test_camera_tf_two_cameras_share_one_graph(camera_stage: og.GraphStage) -> None:
    publish_camera_tf_fixed(Camera("/World/floating_camera"))
    publish_camera_tf_fixed(Camera("/World/cam2"))
    graph = camera_stage.graph("/CameraTFActionGraph")
    assert [n.name for n in graph.nodes] == [
        "OnTick", "IsaacClock", "RosPublisher",
        "PublishTFfloating_camera", "PublishRawTFfloating_cameraworld",
        "PublishTFcam2", "PublishRawTFcam2world",
    ]
    assert len(graph.connections) == 2 + 4 + 4

    ctx = run_ticks(camera_stage, 2, Ctx())
    tick1 = [p for p in ctx.published if p["stamp"] > 0]
    assert [p["node"].rsplit("/", 1)[1] for p in tick1] == [
        "RosPublisher", "PublishTFfloating_camera", "PublishRawTFfloating_cameraworld",
        "PublishTFcam2", "PublishRawTFcam2world",
    ]
    assert all(p["stamp"] == (1_000_000_000 // 60) / 1e9 for p in tick1)
    raw = tick1[2]
    assert raw["topic"] == "/tf"
    assert raw["parentFrameId"] == "floating_camera"
    assert raw["childFrameId"] == "floating_cameraworld"
    assert raw["rotation"] == (0.5, -0.5, 0.5, 0.5)
    assert tick1[3]["targetPrims"] == ("/World/cam2",)


def test_camera_tf_second_create_of_same_camera_is_refused(camera_stage: og.GraphStage) -> None:
    publish_camera_tf_fixed(Camera("/World/floating_camera"))
    with pytest.raises(GraphError, match="PublishTFfloating_camera' already exists"):
        publish_camera_tf_fixed(Camera("/World/floating_camera"))
