"""Rendering on a background thread (``render.overlap``) against rendering on the loop's thread,
and the render settings: the same bytes, the same consumer behaviour, clear errors.

Real MuJoCo rendering (EGL), the real recorder and bag; digests are the recorder's per-topic
SHA-256 over (log time, CDR payload)."""

from __future__ import annotations

import sys
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness import api
from harness.bus import Bus, Deferred, Envelope
from harness.engine import Simulation
from harness.errors import SimulationError
from harness.frames import load_frames
from harness.graph.nodes.camera import RENDER_PRODUCTS, RenderProductTable
from harness.scenario.schema import (
    CameraSpec,
    DockSpec,
    Pose,
    RenderSpec,
    Scenario,
    WorkerSpec,
    WorldSpec,
)
from harness.sim import World
from harness.sim.render import Renderer, is_software_renderer
from harness.sim.render_pipeline import RenderThread

SCENE = """\
format_version: 1
name: overlap
duration: 1.0
seed: 3
world: {{size: [12.0, 10.0], shelves: [], dock: {{enabled: false}}}}
cameras:
  - name: cam_a
    spawn: {{position: [-4.0, 0.0, 1.5], rpy_deg: [0.0, 12.0, 0.0]}}
    resolution: [64, 48]
    fps: 30
    outputs: [rgb, depth, pointcloud, camera_info]
  - name: cam_b
    spawn: {{position: [4.0, 0.5, 2.0], rpy_deg: [0.0, 20.0, 180.0]}}
    resolution: [40, 30]
    fps: 20
    outputs: [rgb, depth]
workers:   # walks through both views, so every frame differs
  - route: [[-1.5, -3.0], [1.5, 3.0]]
    speed: 2.0
systems_under_test:   # consumes cam_a's depth in the tick it is published
  - name: perception
    plugin: harness.sut.perception:DepthPeopleTracker
    params:
      cameras: [cam_a]
      watch_area: [[-3.0, -4.0], [3.0, -4.0], [3.0, 4.0], [-3.0, 4.0]]
      min_hits: 1
render: {{overlap: {overlap}, shadows: {shadows}}}
"""


def _run(tmp_path: Path, name: str, *, overlap: bool, shadows: bool = False,
         overrides: tuple[str, ...] = ()) -> dict[str, Any]:
    path = tmp_path / f"{name}.yaml"
    path.write_text(SCENE.format(overlap=str(overlap).lower(), shadows=str(shadows).lower()))
    res = api.run_scenario(api.load(path, overrides=list(overrides)), source=str(path),
                           out=tmp_path / name, baselines=tmp_path / "no_baselines")
    topics: dict[str, Any] = res.summary["topics"]
    return topics


def _digests(topics: dict[str, Any]) -> dict[str, str]:
    return {t: v["sha256"] for t, v in topics.items()}


@pytest.mark.slow
def test_overlapped_rendering_gives_the_same_bytes_as_the_plain_loop(tmp_path: Path) -> None:
    plain = _run(tmp_path, "plain", overlap=False)
    overlapped = _run(tmp_path, "overlap_1", overlap=True)
    again = _run(tmp_path, "overlap_2", overlap=True)
    assert _digests(overlapped) == _digests(plain)
    assert _digests(again) == _digests(overlapped)  # and it is deterministic
    # the run really rendered and consumed images: 30 + 20 frames, tracks from the depth
    assert plain["/cam_a_rgb"]["count"] == 30 and plain["/cam_b_depth"]["count"] == 20
    assert plain["/cam_a_pointcloud"]["bytes"] > 30 * 12 * 64 * 48 // 2
    assert plain["/perception/tracks"]["count"] > 0
    for t, v in plain.items():
        assert v["count"] == v["published"], t  # nothing lost on the way through the threads


@pytest.mark.slow
def test_overlapped_rendering_into_a_ros1_recording_gives_the_plain_loop_bytes(
        tmp_path: Path) -> None:
    # the ROS 1 recorder builds deferred images on the caller's thread and converts them
    plain = _run(tmp_path, "ros1_plain", overlap=False, overrides=("output.ros=1",))
    overlapped = _run(tmp_path, "ros1_overlap", overlap=True, overrides=("output.ros=1",))
    assert _digests(overlapped) == _digests(plain)
    assert plain["/cam_a_rgb"]["count"] == 30 and plain["/cam_a_rgb"]["type"] == "sensor_msgs/Image"
    frames = load_frames(tmp_path / "ros1_overlap")
    assert int(frames.topics.set_index("name").loc["/cam_b_depth", "count"]) == 20


@pytest.mark.slow
def test_shadows_change_colour_but_not_depth(tmp_path: Path) -> None:
    off = _digests(_run(tmp_path, "off", overlap=True))
    on = _digests(_run(tmp_path, "on", overlap=True, shadows=True))
    assert on["/cam_a_rgb"] != off["/cam_a_rgb"] and on["/cam_b_rgb"] != off["/cam_b_rgb"]
    same = {t for t in off if not t.endswith("_rgb")}
    assert {t: on[t] for t in same} == {t: off[t] for t in same}


def _hall(render: RenderSpec) -> World:
    cams = (CameraSpec(name="cam", spawn=Pose(position=(0.0, 0.0, 1.5), rpy_deg=(0.0, 30.0, 0.0)),
                       resolution=(32, 24), outputs=("rgb", "depth")),)
    world = WorldSpec(size=(12.0, 10.0), shelves=(), dock=DockSpec(enabled=False))
    workers = (WorkerSpec(route=((3.0, 0.0), (3.0, 1.0))),)
    return World.build(Scenario(format_version=1, name="hall", world=world, cameras=cams,
                                workers=workers, render=render))


def test_render_settings_go_into_the_model() -> None:
    cheap = _hall(RenderSpec()).model
    assert not cheap.light_castshadow.any() and not cheap.mat_reflectance.any()
    assert cheap.vis.quality.shadowsize == 1024
    lit = cheap.light_active[cheap.light_type != 1]  # spot lights: off with lights: sun
    assert lit.size and not lit.any()
    full = _hall(RenderSpec(shadows=True, shadow_size=2048, reflections=True, lights="all")).model
    assert full.light_castshadow.any() and full.mat_reflectance.any() and full.light_active.all()
    assert full.vis.quality.shadowsize == 2048


def test_render_thread_draws_what_the_plain_renderer_draws() -> None:
    world = _hall(RenderSpec(shadows=True))
    cam = world.prim_ref("/World/cam").id
    with Renderer(world.model, world.data) as plain:
        expected = [plain.render(cam, 32, 24) for _ in range(2)]
    switch = sys.getswitchinterval()
    thread = RenderThread(Renderer(world.model, world.data), in_flight=2)
    try:
        assert sys.getswitchinterval() < switch
        pending = [thread.submit(cam, 32, 24) for _ in range(3)]  # the third waits for a scene
        for p, e in zip(pending, expected, strict=False):
            np.testing.assert_array_equal(p.rgb(), e.rgb)
            np.testing.assert_array_equal(p.depth(), e.depth)
            assert p.rgb() is p.rgb() and not p.depth().flags.writeable
        with pytest.raises(SimulationError, match="no camera with id 99"):
            thread.submit(99, 32, 24)
        with pytest.raises(SimulationError, match="image size must be positive"):
            thread.submit(cam, 0, 24)
    finally:
        thread.close()
        thread.close()
    assert sys.getswitchinterval() == switch
    assert thread.renderer.renders == 3
    with pytest.raises(SimulationError, match="closed"):
        thread.submit(cam, 32, 24)


def test_overlap_publishes_deferred_images_to_the_recorder_only() -> None:
    """A tap that takes Deferred messages (the recorder) gets them as they are and subscribers
    the built message; once a tap that does not take them is added, the bus builds every
    message at publish time."""
    sc = Scenario(format_version=1, name="hall", world=WorldSpec(size=(12.0, 10.0), shelves=(),
                                                                 dock=DockSpec(enabled=False)),
                  cameras=(CameraSpec(name="cam", resolution=(16, 12), outputs=("rgb",)),),
                  render=RenderSpec(overlap=True))
    sim = Simulation(sc)
    seen: list[Any] = []

    class Aware:
        takes_deferred = True

        def __call__(self, env: Envelope) -> None:
            seen.append(env.msg)

    got: list[Any] = []
    sim.add_tap(Aware())
    sim.bus.subscribe("/cam_rgb", "sensor_msgs/msg/Image", got.append)
    try:
        sim.run(1)
        table = sim.ctx.extras[RENDER_PRODUCTS]
        assert isinstance(table, RenderProductTable) and table.overlap
        (deferred,) = [m for m in seen if type(m) is Deferred]
        assert got and got[0] is deferred.resolve() and got[0].width == 16
        sim.add_tap(lambda env: seen.append(env.msg))  # not Deferred-aware
        sim.run(2)
        assert type(seen[-2]) is not Deferred and seen[-2] is seen[-1]
    finally:
        sim.close()


def test_deferred_resolves_once_across_threads() -> None:
    calls: list[int] = []
    d = Deferred(lambda: calls.append(1) or len(calls))
    threads = [threading.Thread(target=d.resolve) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert d.resolve() == 1 and calls == [1]
    bus = Bus(lambda: 0)
    out: list[Any] = []
    bus.subscribe("/x", "std_msgs/msg/Bool", out.append)
    bus.publish("/x", "std_msgs/msg/Bool", Deferred(lambda: "built"))
    bus.spin()
    assert out == ["built"]


def test_auto_overlaps_with_a_gpu_and_not_with_a_software_renderer() -> None:
    assert is_software_renderer("llvmpipe (LLVM 15.0.6, 256 bits)")
    assert is_software_renderer("softpipe") and is_software_renderer("Mesa X11 swrast")
    assert not is_software_renderer("NVIDIA H100 80GB HBM3/PCIe/SSE2")
    world = _hall(RenderSpec())
    with Renderer(world.model, world.data) as probe:
        name = probe.gl_renderer()
    assert name  # the context says what it is
    sim = Simulation(world.scenario)
    try:
        sim.run(1)
        table = sim.ctx.extras[RENDER_PRODUCTS]
        assert isinstance(table, RenderProductTable)
        assert table.overlap is not is_software_renderer(name)
    finally:
        sim.close()
