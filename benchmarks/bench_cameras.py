"""Camera benchmark: srr against the renderer's own limit and against a bare loop.

The scenario is ``scenarios/camera_publishing.yaml`` with its ``cameras:`` list replaced by
``--cameras`` cameras (the seed's floating camera first, the others on a circle around the
parked forklift, all looking at it) at ``--width`` x ``--height`` and ``--fps``, publishing
``--outputs``, for each render configuration of ``--configs`` (``off``: no shadows, the
default; ``on``: shadows with the default 1024² map; ``on4096``: shadows with a 4096² map;
reflections and lights at their defaults). Measured side by side in one process, alternating,
best of ``--repeats``:

* render-only: the renderer's own limit. ``World.build`` (same model, same render settings),
  then for every camera frame the run renders: ``mjv_updateScene`` + ``mjr_render`` +
  ``mjr_readPixels`` into the same buffers, one thread, nothing else (no physics, no
  conversion, no messages);
* bare: ``World.build``, then per tick: ``/clock`` and every camera's ``/tf``; on gated ticks
  each camera rendered with the same single-pass :class:`~harness.sim.render.Renderer`, its
  messages built, CDR-serialized (rosbags) and written to a rosbag2/MCAP file (rosbags'
  writer); then the physics substeps. No graphs, bus, digests or summary;
* srr: ``api.run_scenario`` on the same scenario (graphs, bus, render thread, recorder with
  digests, scoring, summary, report). Its *loop* throughput is camera sets per second of the
  tick loop (first to last tick: what rendering paces); *RTF* is simulated ÷ wall time of the
  whole run, fixed costs included.

Prints per configuration: render-only sets/s, srr loop sets/s and their ratio (target ≥ 0.85),
srr RTF (target ≥ 4 with shadows off, 4 × 640x480 at 30 Hz on the GPU machine), the bare
loop and the harness overhead srr ÷ bare. Each run's bag is deleted as soon as it is
measured. On the GPU machine (``benchmarks/gpu_rig.sh`` runs this and the memory benchmark)::

    MUJOCO_GL=egl python benchmarks/bench_cameras.py --cameras 4 --width 640 --height 480 \
        --fps 30 --duration 20 --configs off,on,on4096
"""

from __future__ import annotations

import argparse
import inspect
import json
import math
import os
import platform
import shutil
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported

import mujoco  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402

from harness import api  # noqa: E402
from harness.builders.camera_tf import OPTICAL_TO_WORLD_IJKR, world_frame  # noqa: E402
from harness.builders.cameras import gate_step  # noqa: E402
from harness.geometry import wxyz_to_xyzw  # noqa: E402
from harness.graph.nodes.camera import (  # noqa: E402
    CAMERA_TYPES,
    camera_info_message,
    depth_image_message,
    point_cloud_message,
    rgb_image_message,
)
from harness.graph.nodes.ros_bridge import frame_of, frame_pose  # noqa: E402
from harness.scenario import Scenario  # noqa: E402
from harness.serde.messages import (  # noqa: E402
    TYPESTORE,
    clock,
    serialize,
    tf_message,
    transform_stamped,
)
from harness.sim import World  # noqa: E402
from harness.sim.render import Renderer, points_from_depth  # noqa: E402

#: ``--configs`` name → ``render:`` overrides.
CONFIGS: dict[str, dict[str, Any]] = {
    "off": {"shadows": False},
    "on": {"shadows": True},
    "on4096": {"shadows": True, "shadow_size": 4096},
}

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


def load(args: argparse.Namespace, render: dict[str, Any] | None = None) -> Scenario:
    blocks = camera_blocks(args.cameras, args.width, args.height, args.fps, args.outputs)
    overrides = [f"cameras={json.dumps(blocks)}"]
    overrides += [f"render.{k}={json.dumps(v)}" for k, v in (render or {}).items()]
    return api.load(SCENARIO, duration=args.duration, overrides=overrides)


def render_only(sc: Scenario) -> tuple[float, int]:
    """Wall time and frame count of the renders and read-backs ``sc`` makes, alone."""
    world = World.build(sc)
    cams = [c for c in sc.cameras if c.enabled]
    ids = [world.prim_ref(c.prim).id for c in cams]
    steps = [gate_step(sc.physics.tick_hz, c.fps) for c in cams]
    with Renderer(world.model, world.data) as renderer:
        for c, cid in zip(cams, ids, strict=True):  # contexts and buffers made before timing
            renderer.draw(renderer.capture(cid, *c.resolution))
        frames = 0
        t0 = time.perf_counter()
        for k in range(sc.n_ticks):
            for c, cid, step in zip(cams, ids, steps, strict=True):
                if k % step == 0:
                    renderer.draw(renderer.capture(cid, *c.resolution))
                    frames += 1
        return time.perf_counter() - t0, frames


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


@dataclass
class SrrRun:
    wall: float  # the whole run_scenario
    loop: float  # first tick to last tick
    loop_ticks: int
    summary: dict[str, Any]
    # the loop's thread inside RenderThread.submit (capture, and waiting for a free scene:
    # the renderer paces) and inside Recorder.write (small messages' CDR, and waiting for
    # room in the writer's queue: the writer paces)
    in_submit: float = 0.0
    in_record: float = 0.0
    in_draw: float = 0.0  # Renderer.draw (mjr_render + mjr_readPixels), whichever thread
    # CPU seconds of the run's threads, by name (pool and lane numbers dropped)
    threads: dict[str, float] = field(default_factory=dict)


class ThreadCpu:
    """Samples the CPU time of every Python thread of this process (Linux: utime + stime of
    /proc/self/task/<tid>/stat) every 20 ms while it runs; :meth:`stop` gives CPU seconds per
    thread name, with trailing pool and lane numbers dropped (``srr-cdr_0`` → ``srr-cdr``),
    so a saturated thread (CPU ≈ the loop's wall time) shows."""

    def __init__(self) -> None:
        self._last: dict[int, tuple[str, float]] = {}
        self._stop = threading.Event()
        self._tick = os.sysconf("SC_CLK_TCK")
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._sample()
        self._base = {tid: cpu for tid, (_, cpu) in self._last.items()}  # before the run
        self._thread.start()

    def _sample(self) -> None:
        for t in threading.enumerate():
            tid = t.native_id
            if tid is None or t is self._thread:
                continue
            try:
                fields = Path(f"/proc/self/task/{tid}/stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            self._last[tid] = (t.name, (int(fields[11]) + int(fields[12])) / self._tick)

    def _run(self) -> None:
        while not self._stop.wait(0.02):
            self._sample()

    def stop(self) -> dict[str, float]:
        self._sample()
        self._stop.set()
        self._thread.join()
        groups: dict[str, float] = {}
        for tid, (name, cpu) in self._last.items():
            cpu -= self._base.get(tid, 0.0)
            key = name.rstrip("0123456789").rstrip("_-")
            groups[key] = groups.get(key, 0.0) + cpu
        return dict(sorted(groups.items(), key=lambda kv: -kv[1]))


def _timed(cls: Any, name: str, acc: list[float]) -> Any:
    """Wrap ``cls.name`` to add its wall time on the calling thread to ``acc[0]``."""
    orig = getattr(cls, name)

    def wrapper(*a: Any, **k: Any) -> Any:
        t = time.perf_counter()
        try:
            return orig(*a, **k)
        finally:
            acc[0] += time.perf_counter() - t
    setattr(cls, name, wrapper)
    return orig


def harness_run(sc: Scenario, out: Path) -> SrrRun:
    from harness.recording.recorder import Recorder
    from harness.sim.render_pipeline import RenderThread

    marks: dict[int, float] = {}

    def progress(k: int, n: int) -> None:
        if k in (1, n):
            marks[k] = time.perf_counter()

    submit, record, draw = [0.0], [0.0], [0.0]
    orig_submit = _timed(RenderThread, "submit", submit)
    # The bus calls the recorder itself; where __call__ is write (not a method calling it),
    # that is the attribute to time.
    tap = "__call__" if Recorder.__dict__.get("__call__") is Recorder.__dict__["write"] else "write"
    orig_write = _timed(Recorder, tap, record)
    orig_draw = _timed(Renderer, "draw", draw)
    cpu = ThreadCpu() if sys.platform == "linux" else None
    try:
        t0 = time.perf_counter()
        # The report's camera videos (VP9, encoded after the loop) are left out where srr
        # makes them: the whole-run RTF stays the recording's, comparable across versions.
        no_video = ({"video": False} if "video" in inspect.signature(api.run_scenario).parameters
                    else {})
        res = api.run_scenario(sc, source=str(SCENARIO), out=out, progress=progress,
                               **no_video)
        wall = time.perf_counter() - t0
    finally:
        threads = cpu.stop() if cpu is not None else {}
        RenderThread.submit = orig_submit  # type: ignore[method-assign]
        setattr(Recorder, tap, orig_write)
        Renderer.draw = orig_draw  # type: ignore[method-assign]
    return SrrRun(wall, marks[sc.n_ticks] - marks[1], sc.n_ticks - 1, res.summary,
                  submit[0], record[0], draw[0], threads)


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


@dataclass
class Result:
    config: str
    render_only: float
    frames: int
    bare: float
    srr: SrrRun
    phases: Phases
    all_render: list[float]
    all_bare: list[float]
    all_srr: list[float]


def measure(args: argparse.Namespace, config: str, tmp: Path) -> Result:
    sc = load(args, {**CONFIGS[config], "overlap": args.overlap})
    t_render: list[float] = []
    t_bare: list[float] = []
    runs: list[SrrRun] = []
    phases = Phases()
    frames = 0
    for i in range(args.repeats):
        t, frames = render_only(sc)
        t_render.append(t)
        if not args.skip_bare:
            ph = Phases()
            out = tmp / f"bare_{config}_{i}"
            t_bare.append(bare(sc, out, ph))
            shutil.rmtree(out, ignore_errors=True)
            if t_bare[-1] == min(t_bare):
                phases = ph
        out = tmp / f"srr_{config}_{i}"
        runs.append(harness_run(sc, out))
        shutil.rmtree(out, ignore_errors=True)
    srr = min(runs, key=lambda r: r.loop)
    srr_counts = {t: v["count"] for t, v in srr.summary["topics"].items()}
    if t_bare:
        assert srr_counts == phases.messages, (srr_counts, phases.messages)
    assert srr.summary["verdict"] != "INVALID", srr.summary["reasons"]
    return Result(config, min(t_render), frames, min(t_bare, default=math.nan), srr, phases,
                  t_render, t_bare, [r.loop for r in runs])


def report(args: argparse.Namespace, r: Result) -> dict[str, Any]:
    n = args.cameras
    sets = r.frames / n
    limit = sets / r.render_only
    loop_sets = sets * r.srr.loop_ticks / max(1, round(args.duration * 60)) / r.srr.loop
    ph = r.phases
    out = {
        "config": r.config, "render": CONFIGS[r.config], "frames": r.frames,
        "render_only_sets_per_s": limit,
        "render_only_ms_per_frame": r.render_only / r.frames * 1e3,
        "srr_loop_sets_per_s": loop_sets, "srr_over_render_only": loop_sets / limit,
        "srr_wall_s": r.srr.wall, "srr_rtf": args.duration / r.srr.wall,
        "srr_loop_rtf": loop_sets / args.fps,
        "srr_loop_thread_s": {"loop": r.srr.loop, "in_render_submit": r.srr.in_submit,
                              "in_recorder_write": r.srr.in_record},
        "srr_draw_ms_per_frame": r.srr.in_draw / r.frames * 1e3,
        "srr_thread_cpu_s": r.srr.threads,
        "bare_wall_s": r.bare, "bare_rtf": args.duration / r.bare,
        "overhead_srr_over_bare": r.srr.wall / r.bare,
        "bare_ms_per_frame": {"render": ph.render / max(ph.frames, 1) * 1e3,
                              "messages_serialize": ph.serialize / max(ph.frames, 1) * 1e3,
                              "mcap_write": ph.write / max(ph.frames, 1) * 1e3},
        "runs": {"render_only": r.all_render, "bare": r.all_bare, "srr_loop": r.all_srr},
    }
    print(f"[{r.config}] render {json.dumps(CONFIGS[r.config])}: {r.frames} frames, "
          f"best of {args.repeats}")
    print(f"  render-only : {limit:7.1f} sets/s  ({out['render_only_ms_per_frame']:.2f} ms "
          "per camera frame: mjv_updateScene + mjr_render + mjr_readPixels)")
    print(f"  srr loop    : {loop_sets:7.1f} sets/s  ratio srr / render-only "
          f"{out['srr_over_render_only']:.3f} (target >= 0.85); loop RTF "
          f"{out['srr_loop_rtf']:.2f}")
    print(f"  srr run     : {r.srr.wall:7.2f} s  RTF {out['srr_rtf']:.2f} (whole run: build, "
          "loop, scoring, report)")
    print(f"  srr loop    : {r.srr.loop:7.2f} s, of which the loop's thread spent "
          f"{r.srr.in_submit:.2f} s submitting renders (capture + waiting for the renderer) "
          f"and {r.srr.in_record:.2f} s handing messages to the recorder (small messages' "
          "CDR + waiting for the writer); a draw took "
          f"{out['srr_draw_ms_per_frame']:.2f} ms a frame in srr (render-only: "
          f"{out['render_only_ms_per_frame']:.2f} ms with the capture)")
    if r.srr.threads:
        print(f"  srr threads : CPU s over the {r.srr.wall:.2f} s run: " + ", ".join(
            f"{name} {cpu:.2f}" for name, cpu in r.srr.threads.items()))
    if math.isnan(r.bare):
        return out
    print(f"  bare loop   : {r.bare:7.2f} s  RTF {out['bare_rtf']:.2f}; srr / bare "
          f"{out['overhead_srr_over_bare']:.3f}; per frame render "
          f"{out['bare_ms_per_frame']['render']:.2f} ms, messages+serialize "
          f"{out['bare_ms_per_frame']['messages_serialize']:.2f} ms, MCAP write "
          f"{out['bare_ms_per_frame']['mcap_write']:.2f} ms")
    return out


def scene_args(ap: argparse.ArgumentParser, *, cameras: int = 1, width: int = 256,
               height: int = 256, duration: float = 2.0) -> None:
    """The arguments :func:`load` reads (this benchmark's and the others' on its scene)."""
    ap.add_argument("--cameras", type=int, default=cameras)
    ap.add_argument("--width", type=int, default=width)
    ap.add_argument("--height", type=int, default=height)
    ap.add_argument("--fps", type=float, default=30.0)
    ap.add_argument("--duration", type=float, default=duration, help="simulated seconds")
    ap.add_argument("--outputs", type=lambda s: s.split(","), default=["rgb", "depth"],
                    help="comma-separated: rgb,depth,pointcloud,camera_info")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    scene_args(ap)
    ap.add_argument("--configs", type=lambda s: s.split(","), default=["off"],
                    help=f"comma-separated render configurations: {', '.join(CONFIGS)}")
    ap.add_argument("--overlap", type=lambda s: {"true": True, "false": False}.get(s, s),
                    default="auto", help="render.overlap for srr: auto (default), true, false")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--skip-bare", action="store_true", help="measure no bare loop")
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    ap.add_argument("--profile", action="store_true",
                    help="also profile one srr run (cProfile, top functions by own time)")
    args = ap.parse_args()
    unknown = [c for c in args.configs if c not in CONFIGS]
    if unknown:
        ap.error(f"--configs: unknown {', '.join(unknown)} (known: {', '.join(CONFIGS)})")
    sc = load(args)
    step = gate_step(sc.physics.tick_hz, args.fps)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"python {platform.python_version()}, mujoco {mujoco.__version__}, "
          f"MUJOCO_GL={os.environ.get('MUJOCO_GL')}, GL renderer: {gl_renderer_name()}")
    print(f"scenario: {args.cameras} camera(s) {args.width}x{args.height} at {args.fps:g} fps "
          f"(gate step {step}), outputs {','.join(args.outputs)}; {args.duration:g} s simulated "
          f"= {sc.n_ticks} ticks; srr with render.overlap={args.overlap}")
    figures = []
    with tempfile.TemporaryDirectory() as tmp:
        for config in args.configs:
            figures.append(report(args, measure(args, config, Path(tmp))))
    if args.json is not None:
        args.json.write_text(json.dumps({"args": {k: str(v) for k, v in vars(args).items()},
                                         "configs": figures}, indent=2))
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
