"""RTSP multi-camera graph (/World/RTSPMultiGraph): one h264 RTSP stream per camera.

Seed 002's shape: one OnPlaybackTick and one IsaacSimulationGate (the rate divider that
throttles the tick to ``rtsp.fps``, so each stream carries one frame per gated tick and none
twice) fanning out to an IsaacCreateRenderProduct + RTSPCameraHelper pair per enabled camera
with a ``port``::

    OnPlaybackTick ─▶ IsaacSimulationGate ─┬▶ RP_<cam>    ─▶ RTSP_<cam>    (port, mount_path)
                                           └▶ RP_<cam2>   ─▶ RTSP_<cam2>   ...

Built only when ``rtsp.enabled``; adding a stream is adding ``port`` (and optionally
``mount_path``) to a camera. The URL is ``rtsp://<rtsp.host>:<port><mount_path>``.
"""

from __future__ import annotations

from typing import Any

from harness.builders.base import BuildContext, fresh_graph, gate_step
from harness.builders.cameras import h264_values
from harness.graph import Controller
from harness.scenario import CameraSpec, Scenario

__all__ = ["GRAPH_PATH", "build", "stream_cameras"]

GRAPH_PATH = "/World/RTSPMultiGraph"


def stream_cameras(scenario: Scenario) -> list[tuple[int, CameraSpec]]:
    """(index in ``cameras``, camera) of every camera the graph streams."""
    if not scenario.rtsp.enabled:
        return []
    return [(i, c) for i, c in enumerate(scenario.cameras) if c.enabled and c.port is not None]


def build(bc: BuildContext) -> str | None:
    spec = bc.scenario.rtsp
    cams = stream_cameras(bc.scenario)
    if not cams:
        return None
    hz = bc.scenario.physics.tick_hz
    step = gate_step(hz, spec.fps)
    nodes: list[tuple[str, str]] = [
        ("OnPlaybackTick", "omni.graph.action.OnPlaybackTick"),
        ("IsaacSimulationGate", "isaacsim.core.nodes.IsaacSimulationGate"),
    ]
    connect = [("OnPlaybackTick.outputs:tick", "IsaacSimulationGate.inputs:execIn")]
    values: list[tuple[str, Any]] = [("IsaacSimulationGate.inputs:step", step)]
    for i, cam in cams:
        rp, helper = f"RP_{cam.name}", f"RTSP_{cam.name}"
        nodes += [(rp, "isaacsim.core.nodes.IsaacCreateRenderProduct"),
                  (helper, "srr.RTSPCameraHelper")]
        connect += [
            ("IsaacSimulationGate.outputs:execOut", f"{rp}.inputs:execIn"),
            (f"{rp}.outputs:execOut", f"{helper}.inputs:execIn"),
            (f"{rp}.outputs:renderProductPath", f"{helper}.inputs:renderProductPath"),
        ]
        width, height = cam.resolution
        assert cam.port is not None
        values += [
            (f"{rp}.inputs:cameraPrim", [cam.prim]),
            (f"{rp}.inputs:width", width),
            (f"{rp}.inputs:height", height),
            (f"{helper}.inputs:port", cam.port),
            (f"{helper}.inputs:mountPath", cam.mount),
            (f"{helper}.inputs:host", spec.host),
            (f"{helper}.inputs:fps", hz / step),
            *h264_values(helper, spec.h264),
        ]
        bc.annotate(GRAPH_PATH, helper, f"cameras[{i}]")
    Controller.edit(fresh_graph(GRAPH_PATH), {
        Controller.Keys.CREATE_NODES: nodes,
        Controller.Keys.CONNECT: connect,
        Controller.Keys.SET_VALUES: values,
    })
    return GRAPH_PATH
