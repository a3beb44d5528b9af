"""Camera nodes and builders on a real Simulation: streams, rates, renders, errors, robot camera.

Messages are taken from the bus (the recorder's tap) and round-tripped through CDR, so what is
checked is what a bag holds.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import harness.graph as og
from harness.builders import camera_tf, cameras
from harness.bus import Envelope
from harness.engine import Simulation
from harness.graph.errors import GraphError
from harness.graph.nodes.camera import RENDER_PRODUCTS, RenderProductTable
from harness.scenario.schema import (
    CameraSpec,
    ClockSpec,
    DockSpec,
    Pose,
    RobotCameraSpec,
    RobotSpec,
    Scenario,
    SensorsSpec,
    WorldSpec,
)
from harness.serde.messages import deserialize, serialize

HALL = WorldSpec(size=(30.0, 20.0), wall_height=4.0, shelves=(), dock=DockSpec(enabled=False))
ALL = ("rgb", "depth", "pointcloud", "camera_info")


def scenario(*cams: CameraSpec, robots: tuple[RobotSpec, ...] = (),
             clock: bool = False) -> Scenario:
    return Scenario(format_version=1, name="cams", world=HALL, cameras=cams, robots=robots,
                    clock=ClockSpec(enabled=clock))


def camera(name: str, fps: float = 30.0, outputs: tuple[str, ...] = ALL,
           size: tuple[int, int] = (32, 24), **kw: Any) -> CameraSpec:
    kw.setdefault("spawn", Pose(position=(10.0, 0.0, 1.5), rpy_deg=(0.0, 20.0, 0.0)))
    return CameraSpec(name=name, fps=fps, outputs=outputs, resolution=size,  # type: ignore[arg-type]
                      **kw)


class Taps:
    """Every published message, CDR round-tripped, by topic."""

    def __init__(self, sim: Simulation) -> None:
        self.by_topic: dict[str, list[tuple[int, Any]]] = defaultdict(list)
        sim.add_tap(self)

    def __call__(self, env: Envelope) -> None:
        msg = deserialize(serialize(env.msg, env.msgtype), env.msgtype)
        self.by_topic[env.topic].append((env.stamp_ns, msg))

    def msgs(self, topic: str) -> list[Any]:
        return [m for _, m in self.by_topic[topic]]


@pytest.fixture
def sims() -> Iterator[list[Simulation]]:
    made: list[Simulation] = []
    yield made
    for sim in made:
        sim.close()


def run(sims: list[Simulation], sc: Scenario, ticks: int) -> tuple[Simulation, Taps]:
    sim = Simulation(sc)
    sims.append(sim)
    taps = Taps(sim)
    sim.run(ticks)
    return sim, taps


def table(sim: Simulation) -> RenderProductTable:
    t = sim.ctx.extras[RENDER_PRODUCTS]
    assert isinstance(t, RenderProductTable)
    return t


# ----------------------------------------------------------------------------- streams

def test_streams_carry_the_documented_encodings_frames_and_stamps(sims: list[Simulation]) -> None:
    sim, taps = run(sims, scenario(camera("cam")), 3)
    stamps = [s for s, _ in taps.by_topic["/cam_rgb"]]
    assert stamps == [0, 2 * 1_000_000_000 // 60]  # gate step 2: ticks 0 and 2
    rgb, depth = taps.msgs("/cam_rgb")[0], taps.msgs("/cam_depth")[0]
    cloud, info = taps.msgs("/cam_pointcloud")[0], taps.msgs("/cam_camera_info")[0]
    for msg in (rgb, depth, cloud, info):
        assert msg.header.frame_id == "cam"
        assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 0)
    assert (rgb.encoding, rgb.height, rgb.width, rgb.step, len(rgb.data)) == (
        "rgb8", 24, 32, 96, 32 * 24 * 3)
    assert (depth.encoding, depth.step, depth.is_bigendian) == ("32FC1", 128, 0)
    d = np.frombuffer(bytes(depth.data), "<f4").reshape(24, 32)
    assert np.isfinite(d).all() and (d > 0).all()
    assert [(f.name, f.offset, f.datatype, f.count) for f in cloud.fields] == [
        ("x", 0, 7, 1), ("y", 4, 7, 1), ("z", 8, 7, 1)]
    assert (cloud.height, cloud.width, cloud.point_step, cloud.is_dense) == (1, 32 * 24, 12, True)
    pts = np.frombuffer(bytes(cloud.data), "<f4").reshape(-1, 3)
    np.testing.assert_array_equal(pts[:, 2], d.reshape(-1))  # z is the depth, row-major
    frame = table(sim).frame(table(sim)["/Render/World/cam_CameraGraph/CreateRenderProduct"],
                             sim.ctx.tick, "test")
    assert frame.rgb.shape == (24, 32, 3)


def test_camera_info_fits_image_size_and_fovy(sims: list[Simulation]) -> None:
    sim, taps = run(sims, scenario(camera("cam", outputs=("camera_info",), size=(64, 48),
                                          fovy_deg=50.0)), 1)
    (info,) = taps.msgs("/cam_camera_info")
    f = 24.0 / math.tan(math.radians(25.0))
    assert (info.width, info.height, info.distortion_model) == (64, 48, "plumb_bob")
    np.testing.assert_allclose(info.k, [f, 0, 31.5, 0, f, 23.5, 0, 0, 1])
    np.testing.assert_allclose(info.p, [f, 0, 31.5, 0, 0, f, 23.5, 0, 0, 0, 1, 0])
    np.testing.assert_allclose(info.r, np.eye(3).reshape(-1))
    np.testing.assert_array_equal(info.d, np.zeros(5))
    assert table(sim).renderer is None  # camera_info alone never renders


def test_gate_step_2_halves_the_count_and_each_camera_renders_once_per_published_tick(
        sims: list[Simulation]) -> None:
    sc = scenario(camera("fast", fps=60.0), camera("slow", fps=30.0))
    sim, taps = run(sims, sc, 12)
    for out in ALL:
        assert len(taps.msgs(f"/fast_{out}")) == 12
        assert len(taps.msgs(f"/slow_{out}")) == 6
    renderer = table(sim).renderer
    assert renderer is not None and renderer.renders == 12 + 6  # not x3 for rgb/depth/cloud
    assert sim.stage.graph("/World/slow_CameraGraph").node("IsaacSimulationGate") \
        .values["inputs:step"] == 2
    assert cameras.gate_step(60, 20.0) == 3 and cameras.gate_step(60, 100.0) == 1


def test_point_cloud_reprojects_onto_its_pixels(sims: list[Simulation]) -> None:
    _, taps = run(sims, scenario(camera("cam", outputs=("pointcloud", "camera_info"))), 1)
    info, cloud = taps.msgs("/cam_camera_info")[0], taps.msgs("/cam_pointcloud")[0]
    pts = np.frombuffer(bytes(cloud.data), "<f4").reshape(-1, 3).astype(np.float64)
    fx, cx, fy, cy = info.k[0], info.k[2], info.k[4], info.k[5]
    u = fx * pts[:, 0] / pts[:, 2] + cx
    v = fy * pts[:, 1] / pts[:, 2] + cy
    vv, uu = np.mgrid[0:24, 0:32]
    np.testing.assert_allclose(u, uu.reshape(-1), atol=1e-3)
    np.testing.assert_allclose(v, vv.reshape(-1), atol=1e-3)


# ----------------------------------------------------------------------------- builders

def test_builders_make_the_documented_graphs(sims: list[Simulation]) -> None:
    sc = scenario(camera("cam", outputs=("rgb", "camera_info")),
                  camera("off", enabled=False, spawn=Pose(position=(0.0, 0.0, 2.0))))
    sim = Simulation(sc)
    sims.append(sim)
    assert "/World/cam_CameraGraph" in sim.graph_paths
    assert "/World/off_CameraGraph" not in sim.graph_paths
    graph = sim.stage.graph("/World/cam_CameraGraph")
    assert [n.name for n in graph.nodes] == [
        "OnPlaybackTick", "ROS2Context", "IsaacSimulationGate", "CreateRenderProduct",
        "CameraHelperRgb", "CameraHelperInfo"]
    assert graph.node("CameraHelperRgb").canonical_type == "srr.CameraHelper"
    assert graph.node("CameraHelperInfo").canonical_type == "srr.CameraInfoHelper"
    assert graph.node("CreateRenderProduct").values["inputs:cameraPrim"] == ("/World/cam",)
    tf = sim.stage.graph(camera_tf.GRAPH_PATH)
    assert [n.name for n in tf.nodes] == ["OnTick", "IsaacClock", "PublishTFcam",
                                          "PublishRawTFcam_world"]
    raw = tf.node("PublishRawTFcam_world").values
    assert raw["inputs:rotation"] == (0.5, -0.5, 0.5, 0.5)
    assert raw["inputs:childFrameId"] == "cam_world" and raw["inputs:staticPublisher"]
    with sim.stage:  # idempotent: rebuilding replaces, never duplicates
        cameras.build(_bc(sim), sc.cameras[0])
    assert len([g for g in sim.stage.graphs() if g.path == "/World/cam_CameraGraph"]) == 1


def _bc(sim: Simulation) -> Any:
    from harness.builders import BuildContext

    return BuildContext(sim.scenario, sim.world)


def test_frame_skip_and_disabled_render_product(sims: list[Simulation]) -> None:
    sim = Simulation(scenario(camera("cam", fps=60.0, outputs=("rgb", "depth"))))
    sims.append(sim)
    taps = Taps(sim)
    g = "/World/cam_CameraGraph"
    with sim.stage:
        og.Controller.set(f"{g}/CameraHelperDepth.inputs:frameSkipCount", 1)
    sim.run(4)
    assert len(taps.msgs("/cam_rgb")) == 4 and len(taps.msgs("/cam_depth")) == 2
    with sim.stage:
        og.Controller.set(f"{g}/CreateRenderProduct.inputs:enabled", False)
    sim.run(2)
    assert len(taps.msgs("/cam_rgb")) == 4


def _add(sim: Simulation, nodes: list[tuple[str, str]], values: list[tuple[str, Any]],
         connect: list[tuple[str, str]] | None = None) -> None:
    keys = og.Controller.Keys
    base = [("OnTick", "omni.graph.action.OnPlaybackTick"),
            ("Product", "isaacsim.core.nodes.IsaacCreateRenderProduct")]
    with sim.stage:
        og.Controller.edit("/World/Extra", {
            keys.CREATE_NODES: base + nodes,
            keys.CONNECT: [("OnTick.outputs:tick", "Product.inputs:execIn")] + [
                ("Product.outputs:execOut", f"{n}.inputs:execIn") for n, _ in nodes] + [
                ("Product.outputs:renderProductPath", f"{n}.inputs:renderProductPath")
                for n, _ in nodes] + (connect or []),
            keys.SET_VALUES: values,
        })


@pytest.mark.parametrize(("settings", "message"), [
    ({"Helper.inputs:useSystemTime": True}, "useSystemTime: must be false"),
    ({"Helper.inputs:type": "semantic_segmentation"}, "'semantic_segmentation' is not supported"),
    ({"Product.inputs:cameraPrim": ["/World/Warehouse/Floor"]}, "a geom, not a camera"),
    ({"Product.inputs:cameraPrim": ["/World/nowhere"]}, "'/World/nowhere' does not exist"),
    ({"Product.inputs:cameraPrim": []}, "cameraPrim: no prim set"),
])
def test_bad_settings_are_graph_errors(sims: list[Simulation], settings: dict[str, Any],
                                       message: str) -> None:
    sim = Simulation(scenario(camera("cam", outputs=("rgb",))))
    sims.append(sim)
    values: dict[str, Any] = {"Product.inputs:cameraPrim": ["/World/cam"],
                              "Helper.inputs:topicName": "extra", "Helper.inputs:type": "rgb"}
    values.update(settings)
    _add(sim, [("Helper", "isaacsim.ros2.bridge.ROS2CameraHelper")],
         [(k, v) for k, v in values.items()])
    with pytest.raises(GraphError, match=message):
        sim.step_tick()


def test_unconnected_render_product_path_names_the_node(sims: list[Simulation]) -> None:
    sim = Simulation(scenario(camera("cam", outputs=("rgb",))))
    sims.append(sim)
    keys = og.Controller.Keys
    with sim.stage:
        og.Controller.edit("/World/Lonely", {
            keys.CREATE_NODES: [("OnTick", "omni.graph.action.OnPlaybackTick"),
                                ("Helper", "omni.isaac.ros_bridge.ROS1CameraHelper")],
            keys.CONNECT: [("OnTick.outputs:tick", "Helper.inputs:execIn")],
        })
    with pytest.raises(GraphError, match=r"/World/Lonely/Helper\.inputs:renderProductPath"):
        sim.step_tick()


def test_isaac_aliases_resolve() -> None:
    for name in ("omni.isaac.ros_bridge.ROS1CameraHelper", "isaacsim.ros2.bridge.ROS2CameraHelper",
                 "omni.isaac.ros2_bridge.ROS2CameraHelper"):
        assert og.canonical_name(name) == "srr.CameraHelper"
    for name in ("isaacsim.ros2.bridge.ROS2CameraInfoHelper",
                 "omni.isaac.ros2_bridge.ROS2CameraInfoHelper"):
        assert og.canonical_name(name) == "srr.CameraInfoHelper"
    for name in ("omni.isaac.core_nodes.IsaacCreateRenderProduct",
                 "isaacsim.core.nodes.IsaacCreateRenderProduct"):
        assert og.canonical_name(name) == "srr.CreateRenderProduct"


# ----------------------------------------------------------------------------- robot camera

def tb3(**camera_kw: Any) -> RobotSpec:
    cam = RobotCameraSpec(resolution=(32, 24), fps=30.0, **camera_kw)
    return RobotSpec(name="tb3", model="turtlebot3_waffle_pi", namespace="tb3",
                     spawn=Pose(position=(0.0, 0.0, 0.0), rpy_deg=(0.0, 0.0, 90.0)),
                     sensors=SensorsSpec(camera=cam))


def test_robot_camera_publishes_color_info_depth_and_its_optical_frame(
        sims: list[Simulation]) -> None:
    sim, taps = run(sims, scenario(robots=(tb3(depth_topic="camera/depth"),)), 3)
    assert "/World/tb3_CameraGraph" in sim.graph_paths
    color, info = taps.msgs("/tb3/camera/color"), taps.msgs("/tb3/camera/camera_info")
    depth = taps.msgs("/tb3/camera/depth")
    assert len(color) == len(info) == len(depth) == 2  # 30 fps: ticks 0 and 2
    assert (color[0].width, color[0].height, color[0].encoding) == (32, 24, "rgb8")
    assert depth[0].encoding == "32FC1" and info[0].width == 32
    assert {m.header.frame_id for m in (color[0], info[0], depth[0])} == {"camera"}
    # The robot's topics live in its namespace; TF stays on the root /tf_static (tf2_ros).
    statics = [t for m in taps.msgs("/tf_static") for t in m.transforms
               if t.child_frame_id == "camera"]
    assert len(statics) == 1 and statics[0].header.frame_id == "camera_link"
    q = statics[0].transform.rotation
    # camera_link looks along its +X: the optical frame is the standard ROS
    # rpy = (-90, 0, -90) deg rotation of it, (x, y, z, w) = (-0.5, 0.5, -0.5, 0.5).
    expected = Rotation.from_euler("xyz", [-90, 0, -90], degrees=True)
    got = Rotation.from_quat([q.x, q.y, q.z, q.w])
    assert (got.inv() * expected).magnitude() < 1e-6
    t = statics[0].transform.translation
    assert max(abs(t.x), abs(t.y), abs(t.z)) < 1e-9  # the camera sits at the link origin


def test_robot_camera_in_the_link_frame_publishes_no_self_transform(
        sims: list[Simulation]) -> None:
    _, taps = run(sims, scenario(robots=(tb3(frame_id="camera_link"),)), 1)
    assert taps.msgs("/tb3/camera/color")[0].header.frame_id == "camera_link"
    assert not [t for m in taps.msgs("/tb3/tf_static") for t in m.transforms
                if t.child_frame_id == t.header.frame_id]
