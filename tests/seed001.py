"""Seed 001's ``publish_camera_tf`` as published, ported by changing imports only (``og`` is
``harness.graph``), and the Isaac helpers it calls. Shared by the graph and camera tests."""

from __future__ import annotations

from collections.abc import Callable

import harness.graph as og

__all__ = ["Camera", "extra_prims", "is_prim_path_valid", "publish_camera_tf",
           "set_target_prims"]


class Camera:
    """The bit of ``isaacsim.sensors.camera.Camera`` the helper reads."""

    def __init__(self, prim_path: str) -> None:
        self.prim_path = prim_path


# Prim look-ups besides graphs, e.g. a test world's ``has_prim``; graphs count as prims too.
extra_prims: list[Callable[[str], bool]] = []


def is_prim_path_valid(path: str) -> bool:
    """Stands in for ``isaacsim.core.utils.prims.is_prim_path_valid``."""
    return og.GraphStage.current().has_graph(path) or any(check(path) for check in extra_prims)


def set_target_prims(primPath: str, inputName: str, targetPrimPaths: list[str]) -> None:
    """Stands in for ``isaacsim.core.nodes.scripts.utils.set_target_prims``."""
    og.Controller.attribute(primPath + "." + inputName).set(targetPrimPaths)


# Seed 001's helper as published; only the imports differ.
def publish_camera_tf(camera: Camera):
    camera_prim = camera.prim_path

    if not is_prim_path_valid(camera_prim):
        raise ValueError(f"Camera path '{camera_prim}' is invalid.")

    try:
        # Generate the camera_frame_id. OmniActionGraph will use the last part of
        # the full camera prim path as the frame name, so we will extract it here
        # and use it for the pointcloud frame_id.
        camera_frame_id=camera_prim.split("/")[-1]

        # Generate an action graph associated with camera TF publishing.
        ros_camera_graph_path = "/CameraTFActionGraph"

        # If a camera graph is not found, create a new one.
        if not is_prim_path_valid(ros_camera_graph_path):
            (ros_camera_graph, _, _, _) = og.Controller.edit(  # noqa: RUF059
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
                    ]
                }
            )

        # Generate 2 nodes associated with each camera: TF from world to ROS camera convention, and world frame.  # noqa: E501
        og.Controller.edit(
            ros_camera_graph_path,
            {
                og.Controller.Keys.CREATE_NODES: [
                    ("PublishTF"+camera_frame_id, "isaacsim.ros2.bridge.ROS2PublishTransformTree"),
                    ("PublishRawTF"+camera_frame_id+"world", "isaacsim.ros2.bridge.ROS2PublishRawTransformTree"),  # noqa: E501
                ],
                og.Controller.Keys.SET_VALUES: [
                    ("PublishTF"+camera_frame_id+".inputs:topicName", "/tf"),
                    # Note if topic_name is changed to something else besides "/tf",
                    # it will not be captured by the ROS tf broadcaster.
                    ("PublishRawTF"+camera_frame_id+"world.inputs:topicName", "/tf"),
                    ("PublishRawTF"+camera_frame_id+"world.inputs:parentFrameId", camera_frame_id),
                    ("PublishRawTF"+camera_frame_id+"world.inputs:childFrameId", camera_frame_id+"world"),  # noqa: E501
                    # Static transform from ROS camera convention to world (+Z up, +X forward) convention:  # noqa: E501
                    ("PublishRawTF"+camera_frame_id+"world.inputs:rotation", [0.5, -0.5, 0.5, 0.5]),
                ],
                og.Controller.Keys.CONNECT: [
                    (ros_camera_graph_path+"/OnTick.outputs:tick",
                        "PublishTF"+camera_frame_id+".inputs:execIn"),
                    (ros_camera_graph_path+"/OnTick.outputs:tick",
                        "PublishRawTF"+camera_frame_id+"world.inputs:execIn"),
                    (ros_camera_graph_path+"/IsaacClock.outputs:simulationTime",
                        "PublishTF"+camera_frame_id+".inputs:timeStamp"),
                    (ros_camera_graph_path+"/IsaacClock.outputs:simulationTime",
                        "PublishRawTF_"+camera_frame_id+"world.inputs:timeStamp"),
                ],
            },
        )
    except Exception as e:
        print(e)

    # Add target prims for the USD pose. All other frames are static.
    set_target_prims(
        primPath=ros_camera_graph_path+"/PublishTF"+camera_frame_id,
        inputName="inputs:targetPrims",
        targetPrimPaths=[camera_prim],
    )
    return
