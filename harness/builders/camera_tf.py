"""Camera TF graph (/World/CameraTFActionGraph): seed 001's ``publish_camera_tf`` for every
enabled fixed camera.

Per camera, with ``<cam>`` the last component of its prim path (the frame id its images and
point clouds carry):

* ``PublishTF<cam>`` (ROS2PublishTransformTree, target = the camera prim) → ``/tf``:
  ``world → <cam>``, the camera's pose in the ROS optical convention (+Z forward, +X right,
  +Y down; the transform-tree publisher turns camera prims into their optical frame, as
  Isaac's does), every tick;
* ``PublishRawTF<cam>_world`` (ROS2PublishRawTransformTree) → ``/tf_static`` (transient
  local, ``staticPublisher``): ``<cam> → <cam>_world``, zero translation and the seed's
  rotation ``[0.5, -0.5, 0.5, 0.5]`` set on the quatd input — Isaac's IJKR order, so
  x = 0.5, y = -0.5, z = 0.5, w = 0.5. That is the rotation that carries the optical frame onto
  the world axes convention (+X forward, +Z up), so ``<cam>_world`` is the camera's true pose.
  (Seed 001's prose calls the list ``[w, x, y, z]``; read that way it would point
  ``<cam>_world``'s +X backwards.)

Differences from the seed: the graph lives under ``/World``, the static frame goes to
``/tf_static`` instead of ``/tf``, the name is ``PublishRawTF<cam>_world`` (the seed's
connection names a ``PublishRawTF_<cam>world`` node that does not exist, a typo Isaac rejects)
and there is no clock publisher in it (the clock graph publishes ``/clock``; a second one would
double every ``/clock`` message).
"""

from __future__ import annotations

from typing import Any

from harness.builders.base import BuildContext, fresh_graph
from harness.graph import Controller
from harness.scenario.prims import frame_of

__all__ = ["GRAPH_PATH", "OPTICAL_TO_WORLD_IJKR", "build", "world_frame"]

GRAPH_PATH = "/World/CameraTFActionGraph"

#: Seed 001's static rotation, as set on the quatd input (x, y, z, w).
OPTICAL_TO_WORLD_IJKR = (0.5, -0.5, 0.5, 0.5)


def world_frame(camera_frame: str) -> str:
    """Name of the camera's world-axes-convention frame: ``<cam>_world``."""
    return f"{camera_frame}_world"


def build(bc: BuildContext) -> str | None:
    cameras = [c for c in bc.scenario.cameras if c.enabled]
    if not cameras:
        return None
    keys = Controller.Keys
    nodes: list[tuple[str, str]] = [
        ("OnTick", "omni.graph.action.OnTick"),
        ("IsaacClock", "isaacsim.core.nodes.IsaacReadSimulationTime"),
    ]
    connect: list[tuple[str, str]] = []
    values: list[tuple[str, Any]] = []
    for camera in cameras:
        frame = frame_of(camera.prim)
        tf, raw = f"PublishTF{frame}", f"PublishRawTF{frame}_world"
        where = f"cameras[{bc.scenario.cameras.index(camera)}]"
        bc.annotate(GRAPH_PATH, tf, where, targetPrims="camera_prim")
        bc.annotate(GRAPH_PATH, raw, where, parentFrameId="camera_prim",
                    childFrameId="camera_prim")
        nodes += [
            (tf, "isaacsim.ros2.bridge.ROS2PublishTransformTree"),
            (raw, "isaacsim.ros2.bridge.ROS2PublishRawTransformTree"),
        ]
        connect += [
            ("OnTick.outputs:tick", f"{tf}.inputs:execIn"),
            ("OnTick.outputs:tick", f"{raw}.inputs:execIn"),
            ("IsaacClock.outputs:simulationTime", f"{tf}.inputs:timeStamp"),
            ("IsaacClock.outputs:simulationTime", f"{raw}.inputs:timeStamp"),
        ]
        values += [
            (f"{tf}.inputs:topicName", "/tf"),
            (f"{tf}.inputs:targetPrims", [camera.prim]),
            (f"{raw}.inputs:topicName", "/tf_static"),
            (f"{raw}.inputs:staticPublisher", True),
            (f"{raw}.inputs:parentFrameId", frame),
            (f"{raw}.inputs:childFrameId", world_frame(frame)),
            (f"{raw}.inputs:rotation", list(OPTICAL_TO_WORLD_IJKR)),
        ]
    Controller.edit(fresh_graph(GRAPH_PATH), {
        keys.CREATE_NODES: nodes,
        keys.CONNECT: connect,
        keys.SET_VALUES: values,
    })
    return GRAPH_PATH
