"""Camera benchmark: cost per camera frame and the harness overhead, srr against a bare loop.

The scenario is ``scenarios/camera_publishing.yaml`` with its ``cameras:`` list replaced by
``--cameras`` cameras (the seed's floating camera first, the others on a circle around the
parked forklift, all looking at it) at ``--width`` x ``--height`` and ``--fps``, publishing
``--outputs``. Measured side by side in one process, alternating, best of ``--repeats``:

* bare: ``World.build``, then per tick: ``/clock`` and every camera's ``/tf``; on gated ticks
  each camera rendered with the same single-pass :class:`~harness.sim.render.Renderer`, its
  messages built, CDR-serialized (rosbags) and written to a rosbag2/MCAP file (rosbags'
  writer, as the recorder uses); then the physics substeps. No graphs, bus, digests or summary.
* srr: ``api.run_scenario`` on the same scenario (graphs, bus, recorder with digests, summary).

Prints the cost per camera frame (render, message + serialization, write), real-time factors
and the ratio srr / bare (the DESIGN target is <= 1.15). On a GPU machine::

    MUJOCO_GL=egl python benchmarks/bench_cameras.py --cameras 4 --width 640 --height 480 \\
        --fps 30 --duration 10
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported

import mujoco
from rosbags.rosbag2 import StoragePlugin, Writer

from harness import api
from harness.builders.camera_tf import OPTICAL_TO_WORLD_IJKR, world_frame
from harness.builders.cameras import gate_step
from harness.bus.messages import (
    TYPESTORE,
    clock,
    serialize,
    tf_message,
    transform_stamped,
)
from harness.geometry import wxyz_to_xyzw
from harness.graph.nodes.camera import (
    CAMERA_TYPES,
    camera_info_message,
    depth_image_message,
    point_cloud_message,
    rgb_image_message,
)
from harness.graph.nodes.ros_bridge import frame_of, frame_pose
from harness.scenario import Scenario
from harness.sim import World
from harness.sim.render import Renderer, points_from_depth

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "camera_publishing.yaml"
TARGET = (1.5, -1.87, 0.8)  # the parked forklift
STREAM = {"rgb": "rgb", "depth": "depth", "pointcloud": "depth_pcl",
          "camera_info": "camera_info"}


def camera_blocks(n: int, width: int, height: int, fps: float,
                  outputs: list[str]) -> list[dict[str, Any]]:
    """The seed's floating camera, then cameras on a 5 m circle around the forklift."""
    blocks = []
    for i in range(n):
        if i == 0:
            name, pos = "floating_camera", (-3.11, -1.87, 1.0)
        else:
            a = math.pi + 2 * math.pi * i / n
            name = f"camera_{i}"
            pos = (TARGET[0] + 5 * math.cos(a), TARGET[1] + 5 * math.sin(a), 1.5 + 0.25 * i)
        dx, dy, dz = (t - p for t, p in zip(TARGET, pos, strict=True))
        yaw = math.degrees(math.atan2(dy, dx))
        pitch = math.degrees(math.atan2(-dz, math.hypot(dx, dy)))
        blocks.append({"name": name, "spawn": {"position": list(pos),
                                               "rpy_deg": [0.0, pitch, yaw]},
                       "resolution": [width, height], "fps": fps, "outputs": outputs})
    return blocks


def load(args: argparse.Namespace) -> Scenario:
    blocks = camera_blocks(args.cameras, args.width, args.height, args.fps, args.outputs)
    return api.load(SCENARIO, duration=args.duration,
                    overrides=[f"cameras={json.dumps(blocks)}"])


@dataclass
class Phases:
    """Bare-loop time per phase (seconds) and the number of camera frames."""

    render: float = 0.0
    serialize: float = 0.0
    write: float = 0.0
    frames: int = 0
    messages: dict[str, int] = field(default_factory=dict)


def bare(sc: Scenario, out: Path, phases: Phases | None = None) -> float:
    """Wall time of the bare loop; fills ``phases`` when given."""
    ph = phases if phases is not None else Phases()
    t0 = time.perf_counter()
    world = World.build(sc)
    renderer = Renderer(world.model, world.data)
    writer = Writer(out, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    conns: dict[str, Any] = {}

    def write(topic: str, msgtype: str, msg: Any, ns: int) -> None:
        t1 = time.perf_counter()
        data = serialize(msg, msgtype)
        t2 = time.perf_counter()
        if topic not in conns:
            conns[topic] = writer.add_connection(topic, msgtype, typestore=TYPESTORE)
        writer.write(conns[topic], ns, data)
        ph.serialize += t2 - t1
        ph.write += time.perf_counter() - t2
        ph.messages[topic] = ph.messages.get(topic, 0) + 1

    cams = [c for c in sc.cameras if c.enabled]
    ids = [world.prim_ref(c.prim).id for c in cams]
    steps = [gate_step(sc.physics.tick_hz, c.fps) for c in cams]
    tf_type = "tf2_msgs/msg/TFMessage"
    for c in cams:
        f = frame_of(c.prim)
        static = transform_stamped(0, f, world_frame(f), (0.0, 0.0, 0.0), OPTICAL_TO_WORLD_IJKR)
        write("/tf_static", tf_type, tf_message([static]), 0)
    for k in range(sc.n_ticks):
        ns = k * 1_000_000_000 // sc.physics.tick_hz
        write("/clock", "rosgraph_msgs/msg/Clock", clock(ns), ns)
        for c in cams:  # one message per camera, as one PublishTransformTree each
            pos, q = frame_pose(world, c.prim)
            tf = transform_stamped(ns, "world", frame_of(c.prim), pos, wxyz_to_xyzw(q))
            write("/tf", tf_type, tf_message([tf]), ns)
        for c, cid, step in zip(cams, ids, steps, strict=True):
            if k % step:
                continue
            t1 = time.perf_counter()
            frame = renderer.render(cid, *c.resolution)
            ph.render += time.perf_counter() - t1
            ph.frames += 1
            fid = frame_of(c.prim)
            for out_name in c.outputs:
                t1 = time.perf_counter()
                stream = STREAM[out_name]
                if stream == "rgb":
                    msg = rgb_image_message(ns, fid, frame.rgb)
                elif stream == "depth":
                    msg = depth_image_message(ns, fid, frame.depth)
                elif stream == "depth_pcl":
                    msg = point_cloud_message(ns, fid,
                                              points_from_depth(frame.depth, frame.intrinsics))
                else:
                    msg = camera_info_message(ns, fid, frame.intrinsics)
                ph.serialize += time.perf_counter() - t1
                write(f"/{c.name}_{out_name}", CAMERA_TYPES[stream], msg, ns)
        world.step(sc.physics.substeps)
    writer.close()
    renderer.close()
    return time.perf_counter() - t0


def harness_run(sc: Scenario, out: Path) -> tuple[float, dict[str, Any]]:
    t0 = time.perf_counter()
    res = api.run_scenario(sc, source=str(SCENARIO), out=out)
    return time.perf_counter() - t0, res.summary


def gl_renderer_name() -> str:
    """The OpenGL renderer string (e.g. llvmpipe or the GPU), for the report."""
    try:
        from OpenGL import GL

        model = mujoco.MjModel.from_xml_string(
            "<mujoco><worldbody><camera name='c'/></worldbody></mujoco>")
        with Renderer(model, mujoco.MjData(model)) as r:
            r.render(0, 8, 8)
            name = GL.glGetString(GL.GL_RENDERER)
        return name.decode() if isinstance(name, bytes) else str(name)
    except Exception as err:  # informational only
        return f"unknown ({type(err).__name__})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cameras", type=int, default=1)
    ap.add_argument("--width", type=int, default=256)
    ap.add_argument("--height", type=int, default=256)
    ap.add_argument("--fps", type=float, default=30.0)
    ap.add_argument("--duration", type=float, default=2.0, help="simulated seconds")
    ap.add_argument("--outputs", type=lambda s: s.split(","), default=["rgb", "depth"],
                    help="comma-separated: rgb,depth,pointcloud,camera_info")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--profile", action="store_true",
                    help="also profile one srr run (cProfile, top functions by own time)")
    args = ap.parse_args()
    sc = load(args)
    tb, th = [], []
    phases = Phases()
    summary: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.repeats):
            ph = Phases()
            tb.append(bare(sc, Path(tmp) / f"bare{i}", ph))
            if tb[-1] == min(tb):
                phases = ph
            t, summary = harness_run(sc, Path(tmp) / f"srr{i}")
            th.append(t)
    b, h = min(tb), min(th)
    frames = phases.frames
    step = gate_step(sc.physics.tick_hz, args.fps)
    srr_counts = {t: v["count"] for t, v in summary["topics"].items()}
    assert srr_counts == phases.messages, (srr_counts, phases.messages)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"python {platform.python_version()}, mujoco {mujoco.__version__}, "
          f"MUJOCO_GL={os.environ.get('MUJOCO_GL')}, GL renderer: {gl_renderer_name()}")
    print(f"scenario: {args.cameras} camera(s) {args.width}x{args.height} at {args.fps:g} fps "
          f"(gate step {step}), outputs {','.join(args.outputs)}; {args.duration:g} s simulated "
          f"= {sc.n_ticks} ticks, {frames} camera frames; best of {args.repeats}")
    print(f"per camera frame (bare loop): render {phases.render / frames * 1e3:.2f} ms, "
          f"messages+serialize {phases.serialize / frames * 1e3:.2f} ms, "
          f"MCAP write {phases.write / frames * 1e3:.2f} ms")
    print(f"bare loop : {b:7.3f} s  RTF {args.duration / b:6.2f}  "
          f"({frames / b:6.1f} camera frames/s, {frames / args.cameras / b:5.1f} sets/s)")
    print(f"srr run   : {h:7.3f} s  RTF {args.duration / h:6.2f}  "
          f"({frames / h:6.1f} camera frames/s, {frames / args.cameras / h:5.1f} sets/s)")
    print(f"harness overhead ratio srr / bare: {h / b:.3f} (all runs: bare "
          f"{', '.join(f'{t:.2f}' for t in tb)}; srr {', '.join(f'{t:.2f}' for t in th)})")
    if args.profile:
        import cProfile
        import pstats

        with tempfile.TemporaryDirectory() as tmp:
            prof = cProfile.Profile()
            prof.enable()
            harness_run(sc, Path(tmp) / "profiled")
            prof.disable()
        pstats.Stats(prof).sort_stats("tottime").print_stats(15)


if __name__ == "__main__":
    main()
