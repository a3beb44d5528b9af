"""Running a scenario: check everything that can be checked before a run, build the
simulation, serve its live view and streams, then record it (:mod:`harness.run.record`);
``srr validate`` is the same checks without the run, and ``--repeat`` runs it ``n`` times."""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from harness.atomic import write_json_atomic
from harness.camera_topics import recorded_cameras
from harness.diskspace import FreeSpace, check_free_space, disk_free, large_bag_notice
from harness.engine import Joined, Simulation
from harness.errors import ScenarioError, SrrError
from harness.interrupt import INTERRUPTED_EXIT
from harness.live.view import LiveConfig, LiveView
from harness.output import OutputKind, check_output_topics, decide_output
from harness.run.baselines import baselines_dir
from harness.run.facts import default_run_dir, reproduce_command
from harness.run.graphs import graphs_of
from harness.run.judge import check_baseline
from harness.run.participants import LiveViewParticipant, RtspParticipant
from harness.run.record import Loop, Progress, RunResult, Started, prepare, record, unprepare
from harness.scenario import (
    Scenario,
    degree_warnings,
    rate_warnings,
    robot_warnings,
    tripwire_warnings,
    worker_warnings,
)
from harness.scoring import check_scoring
from harness.sim.world_file import map_json
from harness.sut.participant import Participant
from harness.wiring import check_wiring

if TYPE_CHECKING:  # the plan module is loaded where a plan is made
    from harness.wiring import Plan

__all__ = [
    "ROS2_BRIDGE",
    "Notice",
    "RepeatResult",
    "check_point",
    "check_suts",
    "check_video",
    "ros2_bridge",
    "run_repeat",
    "run_scenario",
    "start_streams",
    "validate",
]

Notice = Callable[[str], None]


@dataclass(frozen=True)
class RepeatResult:
    runs: tuple[RunResult, ...]
    identical: bool  # the finished runs' per-topic digests (an interrupted one is left out)
    differing_topics: tuple[str, ...]
    exit_code: int
    out_dir: Path

    @property
    def finished(self) -> tuple[RunResult, ...]:
        """The runs that were not interrupted: what the digests compare."""
        return _finished(self.runs)

    @property
    def interrupted(self) -> bool:
        """Whether Ctrl-C stopped a run (the last one: none was started after it)."""
        return len(self.finished) < len(self.runs)


def _finished(runs: Sequence[RunResult]) -> tuple[RunResult, ...]:
    return tuple(r for r in runs if r.verdict != "INTERRUPTED")


def run_scenario(scenario: Scenario, *, source: str = "<scenario>", out: Path | None = None,
                 progress: Progress | None = None, baselines: Path | None = None,
                 update_baseline: bool = False, update_reason: str = "updated with "
                 "--update-baseline", allow_failing: bool = False,
                 free_space: FreeSpace = disk_free,
                 live: LiveConfig | None = None, notice: Notice | None = None,
                 started: Started | None = None, video: bool = True) -> RunResult:
    """Build, run and record ``scenario``; write the run directory and return its verdict.

    ``free_space`` measures the free bytes on a path's filesystem (``shutil.disk_usage`` by
    default): the run refuses to start (:class:`~harness.errors.DiskSpaceError`) when it is
    below the estimated bag size plus ``recording.min_free_mb``, and stops at a tick boundary,
    INVALID, when it falls below ``recording.min_free_mb`` during the run.

    ``live`` serves the run over the Foxglove WebSocket protocol while it goes
    (:mod:`harness.live.view`): the server starts once the scene is built and wired (a port
    in use is refused then, before anything is written) and stops when the run ends, however
    it ends. It changes nothing that is recorded. ``notice`` receives its one-line messages
    for the user; ``started`` the run directory, once it is created and owned. ``video=False``
    leaves the camera videos out of the report (``srr run --no-video``)."""
    run_dir = Path(out) if out is not None else default_run_dir(scenario)
    user_baselines = baselines  # --baselines as given, for the command that reproduces it
    baselines = baselines_dir(source, baselines, scenario)  # a bad folder stops it here
    check_baseline(scenario, baselines)  # and a malformed baseline
    if scenario.baselines is not None:  # the run's scenario.yaml names it wherever it is read
        scenario = dataclasses.replace(scenario, baselines=str(baselines))
    made = prepare(run_dir)
    size_note = large_bag_notice(scenario, check_free_space(scenario, run_dir, free_space))
    if size_note is not None and notice is not None:
        notice(size_note)
    check_scoring(scenario, srr_gt=scenario.srr_gt, source=source)
    sim = Simulation(scenario, source=source, joined=ros2_bridge(scenario, run_dir, source))
    try:
        graphs = graphs_of(sim)  # as built, before any tick
        output = decide_output(scenario, sim.stage, sim.custom_graphs, source)
        if live is not None and output.ros == 1:
            raise SrrError(f"--foxglove: the live view serves ROS 2 messages, and this run "
                           f"records ROS 1 ({output.because})")
        plan = sim.plan()
        warnings = _built_warnings(sim, plan, output, scenario, source)
        # After the plan, so the server advertises every topic the run will publish at once.
        view = (LiveView.start(live, topics={t.topic: t.msgtype for t in plan.topics
                                             if t.kind == "pub"}, notice=notice)
                if live is not None else None)
    except BaseException as err:
        sim.close()
        unprepare(run_dir, made, err)
        raise
    # the run's own participants (harness.run.participants), shut down in reverse order
    participants: list[Participant] = ([LiveViewParticipant(view, sim.bus)]
                                       if view is not None else [])
    try:
        _, hub = _serve_streams(sim, scenario, source, notice)
        if hub is not None:
            participants.append(RtspParticipant(hub))
        world_map = (map_json(sim.world.world_file)  # the file's static geometry, for the map
                     if sim.world.world_file is not None else None)
    except BaseException as err:
        sim.close()
        for p in reversed(participants):
            p.shutdown()
        unprepare(run_dir, made, err)
        raise
    loop = Loop(sim.bus, sim.suts, sim.step_tick, sim.close, lambda: sim.tick_index,
                sim.srr_gt, command=reproduce_command(source, scenario, run_dir, user_baselines),
                warnings=tuple(warnings), graph_paths=tuple(sim.graph_paths),
                scene_files=dict(sim.world.scene_files), world_map=world_map, output=output,
                graphs=graphs)
    return record(scenario, loop, source=source, run_dir=run_dir, n_ticks=scenario.n_ticks,
                  progress=progress, baselines=baselines, update_baseline=update_baseline,
                  update_reason=update_reason, allow_failing=allow_failing,
                  free_space=free_space,
                  participants=participants, started=started, video=video, made=made)


def start_streams(sim: Simulation, scenario: Scenario, source: str = "<scenario>",
                  notice: Notice | None = None) -> list[str]:
    """Serve the scenario's RTSP streams (``rtsp.enabled``): bind every camera's port now, so
    a port in use stops the run before anything is written, then wait for clients
    (``rtsp.wait_s``). Returns the stream URLs. The servers stop with the simulation."""
    return _serve_streams(sim, scenario, source, notice)[0]


def _serve_streams(sim: Simulation, scenario: Scenario, source: str,
                   notice: Notice | None) -> tuple[list[str], Any]:
    """:func:`start_streams`, and the servers (an ``RtspHub``; None: no stream)."""
    from harness.builders.rtsp_cameras import stream_cameras
    from harness.graph.nodes.video import rtsp_hub
    from harness.video.errors import StreamError
    from harness.video.rtsp import StreamConfig

    cams = stream_cameras(scenario)
    if not cams:
        return [], None
    spec = scenario.rtsp
    try:
        hub = rtsp_hub(sim.ctx, rate=spec.rate)
    except StreamError as err:
        raise StreamError(f"{scenario.file_for('rtsp', source)}: rtsp.enabled: {err}") from err
    urls = []
    for i, cam in cams:
        assert cam.port is not None
        where = f"{scenario.file_for(f'cameras[{i}]', source)}: cameras[{i}].port"
        urls.append(hub.stream(StreamConfig(cam.port, cam.mount, spec.host, where)).url)
    say = notice or (lambda _text: None)
    say(f"rtsp: serving {', '.join(urls)}")
    if spec.wait_s:  # (0: start at once, as without a wait)
        say(f"rtsp: waiting up to {spec.wait_s:g} s for a client on every stream")
        missing = hub.wait_for_clients(spec.wait_s)
        if missing:
            say(f"rtsp: no client on {', '.join(missing)}; starting anyway")
    return urls, hub


ROS2_BRIDGE = "ros2_bridge"


def ros2_bridge(scenario: Scenario, run_dir: Path | None,
                source: str = "<scenario>") -> tuple[Joined, ...]:
    """The ROS 2 bridge (:mod:`harness.ros2.bridge`) when ``ros2.enabled``, to join the
    simulation after the scenario's systems under test (it stands for the external nodes,
    and is listed with them as ``ros2_bridge``); none otherwise. Without ``run_dir`` the
    bridge only checks (``srr validate``)."""
    if not scenario.ros2.enabled:
        return ()
    from harness.ros2.bridge import Ros2Bridge

    params: dict[str, Any] = ({"run_dir": str(run_dir)} if run_dir is not None
                              else {"check_only": True})
    # named like the entry after the scenario's own, as the wiring checks list it
    field = f"{source}: systems_under_test[{len(scenario.systems_under_test)}]"
    return (Joined(ROS2_BRIDGE, Ros2Bridge(), field, params),)


def run_repeat(scenario: Scenario, n: int, *, source: str = "<scenario>",
               out: Path | None = None, progress: Progress | None = None,
               baselines: Path | None = None, started: Started | None = None) -> RepeatResult:
    """Run ``n`` times (``run_1`` … ``run_n`` under one directory) and compare digests. A
    run that Ctrl-C interrupts is the last one started, and its shorter recording is left out
    of the comparison (exit 130)."""
    if n < 1:
        raise SrrError(f"--repeat: must be >= 1, got {n}")
    out_dir = Path(out) if out is not None else default_run_dir(scenario)
    runs: list[RunResult] = []
    for i in range(n):
        runs.append(run_scenario(scenario, source=source, out=out_dir / f"run_{i + 1}",
                                 progress=progress, baselines=baselines, started=started))
        if runs[-1].verdict == "INTERRUPTED":
            break
    finished = _finished(runs)
    first = finished[0].summary["topics"] if finished else {}
    differing = sorted({t for r in finished[1:] for t in set(first) | set(r.summary["topics"])
                        if first.get(t, {}).get("sha256")
                        != r.summary["topics"].get(t, {}).get("sha256")})
    identical = not differing
    interrupted = len(finished) < len(runs)
    report = {
        "runs": [str(r.run_dir) for r in runs],
        "identical": identical,
        "differing_topics": differing,
        "digests": [r.summary["digest"] for r in runs],
        "interrupted": interrupted,
    }
    write_json_atomic(out_dir / "determinism.json", report)
    worst = max(r.exit_code for r in runs)
    code = INTERRUPTED_EXIT if interrupted else worst if identical else max(worst, 1)
    return RepeatResult(tuple(runs), identical, tuple(differing), code, out_dir)


def check_suts(scenario: Scenario, source: str = "<scenario>") -> None:
    """Load and set up ``scenario``'s systems under test on a bus of their own (their
    parameters are read in set-up), and shut them down: a part of :func:`validate`, without
    building the world or the graphs."""
    from harness.bus import Bus
    from harness.sut.base import load_suts, setup_suts

    suts = load_suts(scenario, Bus(lambda: 0), source)
    try:
        setup_suts(suts)
    finally:
        for _, sut, _ in suts:
            with contextlib.suppress(Exception):  # one not set up may not shut down
                sut.shutdown()


def check_point(scenario: Scenario, source: str = "<scenario>", *,
                scene: bool) -> tuple[str, ...]:
    """The part of :func:`validate` that a sweep point after the first may differ in, without
    building its graphs again: its systems under test's set-up, where things are
    (:func:`~harness.sim.layout.check_layout`; with ``scene``, for a point that moves a robot
    or a camera or changes the world, the world built again), and the scenario's own
    warnings. Raises the first error; returns the warnings."""
    from harness.sim import World
    from harness.sim.layout import check_layout

    check_suts(scenario, source)
    if scene:
        built = World.build(scenario, source).warnings
    else:
        check_layout(scenario, source)
        built = ()
    return (*built, *scenario_warnings(scenario, source))


def scenario_warnings(scenario: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """The warnings read off the scenario alone: its sensor rates, its robots' blocks, its
    degree fields, its workers and its tripwires."""
    return (*rate_warnings(scenario, source), *robot_warnings(scenario, source),
            *degree_warnings(scenario, source), *worker_warnings(scenario, source),
            *tripwire_warnings(scenario, source))


def validate(scenario: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """Every check that can be made without running (``srr validate``): the scenario itself
    (done by loading it), the scoring block, building the world and the graphs, loading and
    setting up the systems under test, and the wiring (topics and TF). Raises the first error;
    returns the warnings."""
    check_scoring(scenario, srr_gt=scenario.srr_gt, source=source)
    # a baselines: path that is not a folder, a malformed baseline
    check_baseline(scenario, baselines_dir(source, None, scenario))
    busy = check_video(scenario, source)
    sim = Simulation(scenario, source=source, joined=ros2_bridge(scenario, None, source))
    try:
        output = decide_output(scenario, sim.stage, sim.custom_graphs, source)
        plan = sim.plan()
        size_note = large_bag_notice(scenario)
        return (*_built_warnings(sim, plan, output, scenario, source), *busy,
                *([f"{source}: {size_note}"] if size_note else []))
    finally:
        sim.close()


def _built_warnings(sim: Simulation, plan: Plan, output: OutputKind, scenario: Scenario,
                    source: str) -> tuple[str, ...]:
    """The warnings of a scenario built and wired (a run's and ``srr validate``'s alike): its
    model files and fixed cameras, its sensor rates, its robots' blocks, its degree fields,
    its workers, its tripwires, its wiring and its output topics."""
    return (*sim.world.warnings, *scenario_warnings(scenario, source),
            *check_wiring(plan, scenario, source),
            *check_output_topics(output, plan.topics, scenario, source))


def check_video(scenario: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """What ``srr validate`` can know of the video settings before a run: every h264 encoder
    the scenario asks for opens here (NVENC needs an NVIDIA GPU with an encoder), and, with
    ``rtsp.enabled``, GStreamer's RTSP server loads. Raises the first error; returns warnings
    for stream ports another program holds now (a run would stop on them)."""
    import socket

    from harness.builders.rtsp_cameras import stream_cameras
    from harness.video import gst
    from harness.video.codec import check_encoder, settings_of
    from harness.video.errors import StreamError, VideoError

    wanted = [(f"{c.field}.record.h264", c.record.h264)
              for c in recorded_cameras(scenario) if "h264" in c.record.rgb]
    cams = stream_cameras(scenario)
    if cams:
        wanted.append(("rtsp.h264", scenario.rtsp.h264))
    for field, spec in wanted:
        try:
            check_encoder(settings_of(spec))
        except VideoError as err:
            raise ScenarioError(scenario.file_for(field.split(".")[0], source), field,
                                str(err)) from err
    if not cams:
        return ()
    try:
        gst.load()
    except StreamError as err:
        raise ScenarioError(scenario.file_for("rtsp", source), "rtsp.enabled",
                            str(err)) from err
    # cameras may share a port (one server, a mount path each): each port is tried once
    users: dict[int, list[int]] = {}
    for i, cam in cams:
        users.setdefault(cam.port or 0, []).append(i)
    warnings = []
    for port, (i, *others) in users.items():
        with socket.socket(socket.AF_INET6 if ":" in scenario.rtsp.host
                           else socket.AF_INET) as probe:
            try:
                probe.bind((scenario.rtsp.host, port))
            except OSError as err:
                also = (" (the port of " + ", ".join(f"cameras[{j}]" for j in others) + " too)"
                        if others else "")
                warnings.append(f"{scenario.file_for(f'cameras[{i}]', source)}: "
                                f"cameras[{i}].port: {scenario.rtsp.host}:{port} cannot "
                                f"be bound now ({err.strerror or err}); a run would stop "
                                f"there{also}")
    return tuple(warnings)
