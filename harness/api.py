"""The Python API: everything the CLI does is a call here.

``run_scenario`` loads and validates a scenario, builds and runs it, records the bag, checks
that every published message was recorded, and writes the run directory:

    scenario.yaml   resolved scenario (includes expanded, defaults and overrides applied)
    bag/            rosbag2 directory: metadata.yaml + one .mcap (ROS 2); or, for a run that
                    records ROS 1 (harness.output), bag/bag.bag or bag/bag.mcap (ros1 profile)
    summary.json    verdict and reasons, health gates, metrics, baseline comparison,
                    per-topic count/rate/bytes/sha256, versions, seed, command to reproduce
    junit.xml       health gates and metric comparisons as test cases, for CI systems
    graphs.json     the action graphs as built (``srr graph --format json``), and
    graphs.mmd      as Mermaid (``srr graph``): the report draws them from here
    report.html     the reviewer's page (harness.report), written last
    incomplete.json only while the run has not finished (harness.runmarker): a killed run
                    keeps it, and ``recover`` turns such a directory back into a valid one
    run.lock        only while a process writes the directory (harness.runlock): its lock
                    says the run is live, and every command that reads a run refuses it then
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import platform
import shutil
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

from harness import __version__, runlock, runmarker, yamlio
from harness.atomic import write_json_atomic
from harness.bus import Bus, TopicStats
from harness.bus.bagfile import ChunkPolicy
from harness.bus.bagread import ros1_recording
from harness.bus.live import LiveConfig, LiveView
from harness.bus.recover import RecoveredBag, recover_bag
from harness.camera_topics import recorded_cameras, unrecorded_topics
from harness.diff import DiffResult, Tolerance
from harness.diff import diff_runs as _diff_runs
from harness.diskspace import (
    MB,
    DiskGuard,
    FreeSpace,
    check_free_space,
    disk_free,
    large_bag_notice,
)
from harness.engine import Simulation
from harness.errors import BagError, InvalidRunError, RunStopped, ScenarioError, SrrError
from harness.graph import stage_to_json, stage_to_mermaid
from harness.memory import release_free_memory
from harness.metrics.types import HealthResult
from harness.output import ROS2_OUTPUT, OutputKind, check_output_topics, decide_output
from harness.regression import (
    baseline_path,
    comparable_config,
    compare,
    config_differences,
    decide,
    load_baseline,
    save_baseline,
    with_defaults,
)
from harness.regression.reference import reference_path
from harness.replay import Playback, Replay
from harness.report.graphs import RunGraphs, read_graphs, write_graphs
from harness.report.html import write_report
from harness.report.junit import junit_cases, write_junit
from harness.scenario import (
    Scenario,
    SutSpec,
    load_scenario,
    parse_override,
    rate_warnings,
    scenario_to_mapping,
)
from harness.scoring import Scores, check_scoring, scenario_frames, score_frames
from harness.sim.world_file import map_json
from harness.summary import read_summary
from harness.sut.base import SutContext, load_suts
from harness.wiring import check_wiring

__all__ = [
    "LiveConfig",
    "RecoverResult",
    "RepeatResult",
    "RunResult",
    "baselines_dir",
    "bless",
    "build_graphs",
    "default_run_dir",
    "diff_runs",
    "graph_text",
    "load",
    "recover",
    "replay",
    "report",
    "run_planned_suite",
    "run_repeat",
    "run_scenario",
    "start_streams",
    "suite",
    "validate",
    "versions",
    "write_diff",
]

Progress = Callable[[int, int], None]
Notice = Callable[[str], None]
Started = Callable[[Path], None]  # told the run directory once it is created and owned


@dataclass(frozen=True)
class RunResult:
    run_dir: Path
    verdict: str
    exit_code: int
    summary: dict[str, Any]


@dataclass(frozen=True)
class RepeatResult:
    runs: tuple[RunResult, ...]
    identical: bool
    differing_topics: tuple[str, ...]
    exit_code: int
    out_dir: Path


def versions() -> dict[str, str]:
    out = {"srr": __version__, "python": platform.python_version()}
    for dist in ("mujoco", "numpy", "rosbags", "mcap", "pandas"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out


def load(path: str | Path, *, seed: int | None = None, duration: float | None = None,
         srr_gt: bool | None = None, overrides: Sequence[str] = ()) -> Scenario:
    """Load a scenario with CLI-style overrides (``--set``, ``--seed``, ``--duration``)."""
    pairs = [parse_override(o) for o in overrides]
    if seed is not None:
        pairs.append(("seed", seed))
    if duration is not None:
        pairs.append(("duration", duration))
    if srr_gt is not None:
        pairs.append(("srr_gt", srr_gt))
    return load_scenario(path, pairs)


def build_graphs(scenario: Scenario, source: str = "<scenario>") -> Simulation:
    return Simulation(scenario, source=source)


def graph_text(scenario: Scenario, fmt: str = "mermaid", source: str = "<scenario>") -> str:
    """The scenario's action graphs as Mermaid or JSON (``srr graph``)."""
    sim = Simulation(scenario, source=source)
    return stage_to_mermaid(sim.stage) if fmt == "mermaid" else stage_to_json(sim.stage)


def default_run_dir(scenario: Scenario, root: Path = Path("reports"), suffix: str = "") -> Path:
    """``reports/<scenario>/<run id>``; the run id is the local start time plus the seed
    (a name only: no wall-clock value goes into the recorded data), then ``suffix``."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = root / scenario.name / f"{stamp}-s{scenario.seed}{suffix}"
    candidate, n = base, 1
    while candidate.exists():
        n += 1
        candidate = base.with_name(f"{base.name}-{n}")
    return candidate


def combined_digest(topics: dict[str, Any]) -> str:
    h = hashlib.sha256()
    for name in sorted(topics):
        h.update(f"{name}\0{topics[name]['sha256']}\n".encode())
    return h.hexdigest()


def _topic_table(stats: dict[str, TopicStats], published: dict[str, int],
                 duration_s: float) -> dict[str, Any]:
    table = {}
    for name, st in stats.items():
        rate = st.count / duration_s if duration_s > 0 else 0.0
        table[name] = {
            "type": st.msgtype,
            "count": st.count,
            "published": published.get(name, 0),
            "rate_hz": round(rate, 3),
            "bytes": st.bytes,
            "sha256": st.sha256,
            "durability": st.durability,
        }
    return table


@dataclass(frozen=True)
class _Loop:
    """What the shared recording path needs from a loop: its bus, systems under test, tick
    counter and ``run``/``close``, plus what the summary says about it."""

    bus: Bus
    suts: Sequence[tuple[str, Any, SutContext]]
    step: Callable[[], None]  # one tick
    close: Callable[[], None]
    ticks: Callable[[], int]
    srr_gt: bool
    extra: dict[str, Any]
    output: OutputKind = ROS2_OUTPUT  # what the recorder writes (harness.output)
    graphs: RunGraphs | None = None  # written into the run directory (graphs.json)


def _prepare(run_dir: Path) -> None:
    runlock.refuse_if_live(run_dir)
    if run_dir.exists() and any(run_dir.iterdir()):
        raise SrrError(f"--out {run_dir}: directory exists and is not empty")


def run_scenario(scenario: Scenario, *, source: str = "<scenario>", out: Path | None = None,
                 progress: Progress | None = None, baselines: Path | None = None,
                 update_baseline: bool = False, update_reason: str = "updated with "
                 "--update-baseline", free_space: FreeSpace = disk_free,
                 live: LiveConfig | None = None, notice: Notice | None = None,
                 started: Started | None = None) -> RunResult:
    """Build, run and record ``scenario``; write the run directory and return its verdict.

    ``free_space`` measures the free bytes on a path's filesystem (``shutil.disk_usage`` by
    default): the run refuses to start (:class:`~harness.errors.DiskSpaceError`) when it is
    below the estimated bag size plus ``recording.min_free_mb``, and stops at a tick boundary,
    INVALID, when it falls below ``recording.min_free_mb`` during the run.

    ``live`` serves the run over the Foxglove WebSocket protocol while it goes
    (:mod:`harness.bus.live`): the server starts once the scene is built and wired (a port
    in use is refused then, before anything is written) and stops when the run ends, however
    it ends. It changes nothing that is recorded. ``notice`` receives its one-line messages
    for the user; ``started`` the run directory, once it is created and owned."""
    run_dir = Path(out) if out is not None else default_run_dir(scenario)
    baselines = baselines_dir(source, baselines, scenario)  # a bad folder stops it here
    if scenario.baselines is not None:  # the run's scenario.yaml names it wherever it is read
        scenario = dataclasses.replace(scenario, baselines=str(baselines))
    _prepare(run_dir)
    size_note = large_bag_notice(scenario, check_free_space(scenario, run_dir, free_space))
    if size_note is not None and notice is not None:
        notice(size_note)
    check_scoring(scenario, srr_gt=scenario.srr_gt, source=source)
    sim = Simulation(with_ros2_bridge(scenario, run_dir), source=source)
    try:
        graphs = _graphs_of(sim)  # as built, before any tick
        output = decide_output(scenario, sim.stage, sim.custom_graphs, source)
        if live is not None and output.ros == 1:
            raise SrrError(f"--foxglove: the live view serves ROS 2 messages, and this run "
                           f"records ROS 1 ({output.because})")
        plan = sim.plan()
        warnings = [*rate_warnings(scenario, source), *check_wiring(plan, scenario, source),
                    *check_output_topics(output, plan.topics, scenario, source)]
        # After the plan, so the server advertises every topic the run will publish at once.
        view = (LiveView.start(live, topics={t.topic: t.msgtype for t in plan.topics
                                             if t.kind == "pub"}, notice=notice)
                if live is not None else None)
    except BaseException:
        sim.close()
        raise
    try:
        start_streams(sim, scenario, source, notice)
    except BaseException:
        sim.close()
        if view is not None:
            view.close()
        raise
    extra: dict[str, Any] = {"graphs": sim.graph_paths, "warnings": list(warnings),
                             "scene_files": dict(sim.world.scene_files),
                             "command": reproduce_command(source, scenario, run_dir)}
    if sim.world.world_file is not None:  # the file's static geometry, for the report's map
        extra["world_map"] = map_json(sim.world.world_file)
    loop = _Loop(sim.bus, sim.suts, sim.step_tick, sim.close, lambda: sim.tick_index,
                 sim.srr_gt, extra, output, graphs)
    try:
        return _record(scenario, loop, source=source, run_dir=run_dir,
                       n_ticks=scenario.n_ticks, progress=progress, baselines=baselines,
                       update_baseline=update_baseline, update_reason=update_reason,
                       free_space=free_space, view=view, started=started)
    finally:
        if view is not None:
            view.close()


def start_streams(sim: Simulation, scenario: Scenario, source: str = "<scenario>",
                  notice: Notice | None = None) -> list[str]:
    """Serve the scenario's RTSP streams (``rtsp.enabled``): bind every camera's port now, so
    a port in use stops the run before anything is written, then wait for clients
    (``rtsp.wait_s``). Returns the stream URLs. The servers stop with the simulation."""
    from harness.builders.rtsp_cameras import stream_cameras
    from harness.errors import StreamError
    from harness.graph.nodes.video import rtsp_hub
    from harness.video.rtsp import StreamConfig

    cams = stream_cameras(scenario)
    if not cams:
        return []
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
    if spec.wait_s is not None:
        say(f"rtsp: waiting up to {spec.wait_s:g} s for a client on every stream")
        missing = hub.wait_for_clients(spec.wait_s)
        if missing:
            say(f"rtsp: no client on {', '.join(missing)}; starting anyway")
    return urls


ROS2_BRIDGE = "ros2_bridge"


def with_ros2_bridge(scenario: Scenario, run_dir: Path | None) -> Scenario:
    """``scenario`` with the ROS 2 bridge as its last system under test when
    ``ros2.enabled`` (:mod:`harness.ros2.bridge`); as it is otherwise. Without ``run_dir``
    the bridge only checks (``srr validate``)."""
    if not scenario.ros2.enabled:
        return scenario
    params: dict[str, Any] = ({"run_dir": str(run_dir)} if run_dir is not None
                              else {"check_only": True})
    bridge = SutSpec(name=ROS2_BRIDGE, plugin="harness.ros2.bridge:Ros2Bridge", params=params)
    return dataclasses.replace(
        scenario, systems_under_test=(*scenario.systems_under_test, bridge))


def _sut_endpoints(suts: Sequence[tuple[str, Any, SutContext]]) -> dict[str, Any]:
    """Name → plug-in and the topics it publishes and subscribes (what a replay withholds)."""
    out: dict[str, Any] = {}
    for name, sut, ctx in suts:
        out[name] = {
            "plugin": f"{type(sut).__module__}:{type(sut).__qualname__}",
            "publishes": sorted({e.topic for e in ctx.endpoints if e.kind == "pub"}),
            "subscribes": sorted({e.topic for e in ctx.endpoints if e.kind == "sub"}),
        }
    return out


def _record(scenario: Scenario, loop: _Loop, *, run_dir: Path, started: Started | None = None,
            **kw: Any) -> RunResult:
    """:func:`_write_run` while this process owns ``run_dir`` (:mod:`harness.runlock`): it is
    created and locked first (a live owner is refused), and released, its lock file
    removed, however the run ends (``kill -9`` releases the lock too)."""
    with contextlib.ExitStack() as owned:
        try:
            owned.enter_context(runlock.owning(run_dir, "written", fresh=True))
            if started is not None:
                started(run_dir)
        except BaseException:
            loop.close()  # which _write_run does once it runs
            raise
        return _write_run(scenario, loop, run_dir=run_dir, **kw)


def _write_run(scenario: Scenario, loop: _Loop, *, source: str, run_dir: Path, n_ticks: int,
               progress: Progress | None, baselines: Path | None, update_baseline: bool = False,
               update_reason: str = "", free_space: FreeSpace = disk_free,
               view: LiveView | None = None) -> RunResult:
    """Record ``loop`` into ``run_dir``, score it and write the run directory (shared by
    :func:`run_scenario` and :func:`replay`). Until ``summary.json`` is written the directory
    holds ``incomplete.json`` (:mod:`harness.runmarker`), so a killed run never looks done.
    ``view`` (a started live view) gets every message the recorder serializes and, after each
    tick, the simulation time; it may hold the first tick for a client and pace the loop."""
    command = str(loop.extra.get("command", ""))
    runmarker.mark(run_dir, "recording", scenario_file=source, command=command)
    (run_dir / "scenario.yaml").write_text(
        yamlio.dump(scenario_to_mapping(scenario), sort_keys=False), encoding="utf-8")
    if loop.graphs is not None:
        write_graphs(run_dir, loop.graphs)
    rec = scenario.recording
    recorder = loop.output.recorder(run_dir / "bag", ChunkPolicy(
        max_bytes=round(rec.chunk_mb * MB), max_span_ns=round(rec.chunk_s * 1e9),
        fsync=rec.fsync, compression=rec.compression),
        unrecorded=unrecorded_topics(scenario))
    guard = DiskGuard(run_dir, round(rec.min_free_mb * MB), free_space,
                      every_ticks=scenario.physics.tick_hz)
    interrupted = False
    stopped: str | None = None
    gate = "disk_space"
    try:
        recorder.open(loop.bus.qos)
        loop.bus.add_tap(recorder)
        for _, sut, _ in loop.suts:  # the ROS 2 bridge publishes the recorder's bytes
            attach = getattr(sut, "attach_recorder", None)
            if callable(attach):
                attach(recorder)
        if view is not None:
            recorder.add_serialized_tap(view.log)
            view.advertise({t: i.msgtype for t, i in loop.bus.topics().items()}, loop.bus.qos)
            view.wait_for_client()
        hz = scenario.physics.tick_hz
        for _ in range(n_ticks):
            loop.step()
            if view is not None:
                view.tick()
            if progress is not None:
                progress(loop.ticks(), n_ticks)
            if loop.ticks() % hz == 0:  # flat resident memory however long the run
                release_free_memory()
            low = guard.poll(loop.ticks(), recorder.bytes_serialized)
            if low is not None:
                stopped = (f"{low}: the run was stopped after "
                           f"{loop.ticks() / scenario.physics.tick_hz:g} s of simulated time")
                break
    except KeyboardInterrupt:
        interrupted = True
    except RunStopped as err:  # at a tick boundary: what was recorded stays, INVALID
        gate, stopped = err.gate, (f"{err}; the run was stopped after "
                                   f"{loop.ticks() / scenario.physics.tick_hz:g} s of "
                                   "simulated time")
    except BaseException:
        with contextlib.suppress(Exception):  # the original error is the one to report
            recorder.close()
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    finally:
        loop.close()
    runmarker.mark(run_dir, "finalizing", scenario_file=source, command=command)
    try:  # until summary.json exists the directory is half-written: an error removes it
        stats = recorder.close()
        release_free_memory()  # the loop's buffers, before scoring reads the bag
        published = {t: n for t, n in loop.bus.published_counts().items()
                     if t not in recorder.unrecorded}
        sim_s = loop.ticks() / scenario.physics.tick_hz
        topics = _topic_table(stats, published, sim_s)
        frames = scenario_frames(scenario, run_dir / "bag")
        scores = score_frames(scenario, frames, srr_gt=loop.srr_gt, published=published,
                              recorded={t: st.count for t, st in stats.items()},
                              duration_s=sim_s, source=source)
    except BaseException:
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    if stopped is not None:
        scores = dataclasses.replace(
            scores, health=(*scores.health, HealthResult(gate, False, stopped)))
    summary: dict[str, Any] = {
        "scenario": scenario.name,
        "scenario_file": source,
        "seed": scenario.seed,
        "srr_gt": loop.srr_gt,
        "duration_s": scenario.duration,
        "simulated_s": sim_s,
        "ticks": loop.ticks(),
        "tick_hz": scenario.physics.tick_hz,
        "interrupted": interrupted,
        "stopped": stopped,
        "warnings": [],
        "health": [dataclasses.asdict(h) for h in scores.health],
        "metrics": [dataclasses.asdict(m) for m in scores.metrics],
        "graphs": [],
        "systems_under_test": [name for name, _, _ in loop.suts],
        "sut_endpoints": _sut_endpoints(loop.suts),
        "output": loop.output.summary(),
        "topics": topics,
        "digest": combined_digest(topics),
        "versions": versions(),
        **loop.extra,
    }
    if recorder.unrecorded:  # published in the run, recorded compressed (or not at all)
        summary["unrecorded"] = {t: {"type": ty, "published": n}
                                 for t, (ty, n) in recorder.skipped().items()}
    # what plug-ins noticed while running (the ROS 2 bridge: topics it could not bridge)
    summary["warnings"] = [*summary["warnings"], *(
        w for _, sut, _ in loop.suts for w in getattr(sut, "warnings", list)())]
    bdir = baselines_dir(source, baselines, scenario)
    summary["baselines_dir"] = str(bdir)  # where bless writes this run's baseline
    if update_baseline and not interrupted:
        if not all(h.ok for h in scores.health):
            raise InvalidRunError(f"{run_dir}: health gates tripped; an invalid run cannot "
                                  "become the baseline")
        save_baseline(baseline_path(baseline_name(scenario), bdir), summary,
                      reason=update_reason, source_run=str(run_dir),
                      config=scene_config(scenario, summary.get("scene_files")),
                      bag=run_dir / "bag")
    _judge(summary, scenario, scores, bdir)
    if interrupted:
        summary["verdict"], summary["exit_code"] = "INTERRUPTED", 130
        summary["reasons"] = ["interrupted before the end of the scenario"]
    write_junit(run_dir / "junit.xml", scenario.name, junit_cases(summary))
    write_json_atomic(run_dir / "summary.json", summary)  # the run is complete from here on
    runmarker.clear(run_dir)
    try:  # last: a report that fails to render never costs the run its summary
        write_report(run_dir, summary=summary, scenario=scenario, frames=frames,
                     rebuild_graphs=_rebuild_graphs)
    except SrrError:
        raise
    except Exception as err:
        raise SrrError(f"{run_dir / 'report.html'}: the report could not be rendered "
                       f"({type(err).__name__}: {err}); summary.json is complete") from err
    return RunResult(run_dir, summary["verdict"], summary["exit_code"], summary)


def replay(run_dir: str | Path, *, suts: Sequence[str] = (), overrides: Sequence[str] = (),
           out: Path | None = None, progress: Progress | None = None,
           baselines: Path | None = None, started: Started | None = None) -> RunResult:
    """Open-loop replay of a recorded run (``srr replay``): its bag played back, in
    publication order, into its systems under test — or into replacements (``suts``:
    ``NAME=module:Class``) and changed parameters (``overrides``: ``--set`` on the systems
    under test and the scoring). What the systems under test published is produced again;
    everything else is the recording's bytes. The new run directory is scored and judged
    like a run of the recorded scenario (:mod:`harness.replay`)."""
    src = Path(run_dir)
    runlock.refuse_if_live(src)
    summary = read_summary(src)
    recorded = load_scenario(src / "scenario.yaml")
    pairs = [parse_override(o) for o in overrides]
    for text in suts:
        name, sep, plugin = text.partition("=")
        if not sep or not name.strip() or not plugin.strip():
            raise ScenarioError("--sut", text, "expected NAME=module:Class")
        if not any(s.name == name.strip() for s in recorded.systems_under_test):
            names = ", ".join(s.name for s in recorded.systems_under_test) or "none"
            raise ScenarioError("--sut", name, f"no system under test named {name.strip()!r} "
                                f"in {src / 'scenario.yaml'} (names: {names})")
        pairs.append((f"systems_under_test.{name.strip()}.plugin", plugin.strip()))
    scenario = load_scenario(src / "scenario.yaml", pairs)
    _check_replay_scene(recorded, scenario)
    source = str(summary.get("scenario_file") or src / "scenario.yaml")
    check_scoring(scenario, srr_gt=bool(summary.get("srr_gt")), source=source)
    judged = summary.get("baselines_dir")  # judged against the recorded run's baselines
    baselines = baselines_dir(source, baselines if baselines is not None
                              else Path(judged) if judged else None, scenario)
    playback = Playback(src / "bag")
    withheld = _recorded_outputs(summary, recorded, source)
    rep = Replay(scenario, playback, withheld, source)
    try:
        rep.start()
        withheld |= {e.topic for _, _, ctx in rep.suts for e in ctx.endpoints
                     if e.kind == "pub"}
        warnings = _replay_wiring(rep, playback, withheld)
    except BaseException:
        rep.close()
        raise
    out_dir = Path(out) if out is not None else default_run_dir(scenario, suffix="-replay")
    _prepare(out_dir)
    check_free_space(scenario, out_dir, disk_free)
    command = " ".join(["srr replay", str(src), *(f"--sut {t}" for t in suts),
                        *(f"--set {o}" for o in overrides), f"--out {out_dir}"])
    extra = {"warnings": warnings, "command": command,
             "scene_files": dict(summary.get("scene_files") or {}), "replay_of": {
        "run_dir": str(src.resolve()), "digest": summary.get("digest"), "mode": "open-loop",
        "replaced": {t.partition("=")[0].strip(): t.partition("=")[2].strip() for t in suts},
        "overrides": list(overrides), "withheld": sorted(withheld)}}
    if "world_map" in summary:  # the recorded scene, as it was
        extra["world_map"] = summary["world_map"]
    try:  # the recorded scene's graphs; without them the report rebuilds them
        graphs = read_graphs(src)
    except (OSError, ValueError):
        graphs = None
    loop = _Loop(rep.bus, rep.suts, rep.step_tick, rep.close, lambda: rep.tick_index,
                 bool(summary.get("srr_gt")), extra, playback.output, graphs)
    return _record(scenario, loop, source=source, run_dir=out_dir,
                   n_ticks=int(summary.get("ticks") or scenario.n_ticks), progress=progress,
                   baselines=baselines, started=started)


def _check_replay_scene(recorded: Scenario, scenario: Scenario) -> None:
    """A replay may change the systems under test and the scoring, not the recorded scene."""
    def scene(sc: Scenario) -> dict[str, Any]:
        cfg = comparable_config(scenario_to_mapping(sc))
        cfg.pop("scoring", None)
        return cfg

    if recorded.output != scenario.output:
        raise ScenarioError("--set", "output", "a replay records what the recording is "
                            "(ROS 1 or ROS 2, bag or MCAP); it cannot change the output")
    diffs = config_differences(scene(recorded), scene(scenario))
    if diffs:
        field = diffs[0].split(":", 1)[0]
        raise ScenarioError("--set", field, "changes the recorded scene, which an open-loop "
                            "replay plays back as it was; a replay can change the systems "
                            "under test and the scoring")


def _recorded_outputs(summary: dict[str, Any], recorded: Scenario, source: str) -> set[str]:
    """Topics the recorded run's systems under test published: from ``summary.json``, or, for
    runs recorded before it kept them, by setting the recorded plug-ins up on a scratch bus."""
    eps = summary.get("sut_endpoints")
    if isinstance(eps, dict):
        return {t for v in eps.values() if isinstance(v, dict)
                for t in v.get("publishes", []) if isinstance(t, str)}
    bus = Bus(lambda: 0)
    suts = load_suts(recorded, bus, source)
    for _, sut, ctx in suts:
        sut.setup(ctx)
    return {e.topic for _, _, ctx in suts for e in ctx.endpoints if e.kind == "pub"}


def _replay_wiring(rep: Replay, playback: Playback, withheld: set[str]) -> list[str]:
    """Types of what the systems under test read must match the recording; inputs that are
    neither recorded nor published by another system under test are warnings."""
    produced = {e.topic: e.msgtype for _, _, ctx in rep.suts for e in ctx.endpoints
                if e.kind == "pub"}
    warnings = []
    for name, _, ctx in rep.suts:
        for e in ctx.endpoints:
            rec = playback.topics.get(e.topic)
            if rec is not None and rec.msgtype != e.msgtype:
                raise ScenarioError(ctx.field.split(": ", 1)[0], ctx.field.split(": ", 1)[-1],
                                    f"{name} uses {e.topic} as {e.msgtype}, but the recording "
                                    f"carries {rec.msgtype}")
            fed = ((rec is not None and e.topic not in withheld) or e.topic in produced
                   or e.topic in rep.decoded)
            if e.kind == "sub" and not fed:
                warnings.append(f"{ctx.field}: {name} subscribes to {e.topic}, which neither "
                                "the recording nor another system under test provides")
    return warnings


def report(run_dir: str | Path) -> Path:
    """Re-render a run directory's ``report.html`` (``srr report``). Unlike the lenient
    renderer, which notes what it could not read, this refuses a run directory whose
    summary, scenario or bag does not read back (SrrError, exit 2) and writes nothing then."""
    run = Path(run_dir)
    runlock.refuse_if_live(run)
    summary = read_summary(run)
    scenario = load_scenario(run / "scenario.yaml")
    if not (run / "bag" / "metadata.yaml").is_file() and ros1_recording(run / "bag") is None:
        raise BagError(f"{run / 'bag'}: metadata.yaml: missing (not a rosbag2 directory)")
    frames = scenario_frames(scenario, run / "bag")
    return write_report(run, summary=summary, scenario=scenario, frames=frames,
                        rebuild_graphs=_rebuild_graphs)


def _graphs_of(sim: Simulation) -> RunGraphs:
    return RunGraphs(stage_to_json(sim.stage), stage_to_mermaid(sim.stage))


def _rebuild_graphs(scenario: Scenario, summary: Mapping[str, Any], run_dir: Path) -> RunGraphs:
    """The action graphs of a run directory from before runs wrote ``graphs.json``: the
    scene built again from its scenario (the report itself never builds one)."""
    srr_gt = summary.get("srr_gt")
    # Model and world files are named relative to the scenario file the run was started
    # from (the run's own scenario.yaml keeps those paths as written), as for a replay.
    source = str(summary.get("scenario_file") or run_dir / "scenario.yaml")
    sim = Simulation(scenario, srr_gt=srr_gt if isinstance(srr_gt, bool) else None,
                     source=source)
    try:
        return _graphs_of(sim)
    finally:
        with contextlib.suppress(Exception):  # nothing ran: nothing worth reporting
            sim.close()


def validate(scenario: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """Every check that can be made without running (``srr validate``): the scenario itself
    (done by loading it), the scoring block, building the world and the graphs, loading and
    setting up the systems under test, and the wiring (topics and TF). Raises the first error;
    returns the warnings."""
    check_scoring(scenario, srr_gt=scenario.srr_gt, source=source)
    baselines_dir(source, None, scenario)  # a baselines: path that is not a folder
    busy = check_video(scenario, source)
    sim = Simulation(with_ros2_bridge(scenario, None), source=source)
    try:
        output = decide_output(scenario, sim.stage, sim.custom_graphs, source)
        plan = sim.plan()
        size_note = large_bag_notice(scenario)
        return (*rate_warnings(scenario, source), *check_wiring(plan, scenario, source),
                *check_output_topics(output, plan.topics, scenario, source), *busy,
                *([f"{source}: {size_note}"] if size_note else []))
    finally:
        sim.close()


def check_video(scenario: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """What ``srr validate`` can know of the video settings before a run: every h264 encoder
    the scenario asks for opens here (NVENC needs an NVIDIA GPU with an encoder), and, with
    ``rtsp.enabled``, GStreamer's RTSP server loads. Raises the first error; returns warnings
    for stream ports another program holds now (a run would stop on them)."""
    import socket

    from harness.builders.rtsp_cameras import stream_cameras
    from harness.errors import StreamError, VideoError
    from harness.video import gst
    from harness.video.codec import check_encoder, settings_of

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
    warnings = []
    for i, cam in cams:
        with socket.socket(socket.AF_INET6 if ":" in scenario.rtsp.host
                           else socket.AF_INET) as probe:
            try:
                probe.bind((scenario.rtsp.host, cam.port or 0))
            except OSError as err:
                warnings.append(f"{scenario.file_for(f'cameras[{i}]', source)}: "
                                f"cameras[{i}].port: {scenario.rtsp.host}:{cam.port} cannot "
                                f"be bound now ({err.strerror or err}); a run would stop there")
    return tuple(warnings)


def baseline_name(scenario: Scenario) -> str:
    return scenario.baseline or scenario.name


#: What makes a folder a project root: the search for ``baselines/`` stops there.
PROJECT_MARKERS = (".git", "pyproject.toml")


def baselines_dir(source: str, explicit: Path | None = None,
                  scenario: Scenario | None = None) -> Path:
    """The absolute baselines folder of the scenario in file ``source``, the same from any
    working directory (run, suite, replay and bless all use it):

    1. ``explicit`` (``--baselines``), relative to the working directory;
    2. the scenario's ``baselines:`` field, relative to the file that sets it;
    3. the nearest ``baselines/`` folder in the scenario file's folder or a parent, looking
       no higher than the project root (a folder with ``.git`` or ``pyproject.toml``) or
       the filesystem root;
    4. else ``baselines/`` beside the scenario file (blessing creates it).

    A scenario that comes from no file (``<scenario>``) uses ``./baselines``."""
    if explicit is not None:
        folder = Path(explicit).resolve()
        if folder.exists() and not folder.is_dir():
            raise SrrError(f"--baselines: {folder} is not a folder")
        return folder
    from_file = bool(source) and not source.startswith("<")
    if scenario is not None and scenario.baselines is not None:
        origin = scenario.file_for("baselines", source)
        base = Path(origin).resolve().parent if not origin.startswith("<") else Path.cwd()
        folder = (base / scenario.baselines).resolve()
        if folder.exists() and not folder.is_dir():
            raise ScenarioError(origin, "baselines", f"{folder} is not a folder")
        return folder
    if not from_file:
        return Path("baselines").resolve()
    folder = Path(source).resolve().parent
    here = folder
    while True:
        if (here / "baselines").is_dir():
            return here / "baselines"
        if any((here / m).exists() for m in PROJECT_MARKERS) or here == here.parent:
            return folder / "baselines"
        here = here.parent


def reproduce_command(source: str, scenario: Scenario, run_dir: Path) -> str:
    return (f"srr run {source} --seed {scenario.seed} --duration {scenario.duration:g} "
            f"--out {run_dir}")


def scene_config(scenario: Scenario, scene_files: Mapping[str, str] | None) -> dict[str, Any]:
    """The comparable configuration of a run: the scenario's comparable part plus, when the
    scene has model files, their digests by field (``robots[0].model`` → SHA-256), so an
    edited URDF or mesh makes another configuration even under the same path."""
    config = comparable_config(scenario_to_mapping(scenario))
    if scene_files:
        config["scene_files"] = dict(sorted(scene_files.items()))
    return config


def _judge(summary: dict[str, Any], scenario: Scenario, scores: Scores, bdir: Path) -> None:
    """Compare with the baseline and fill ``verdict``, ``exit_code``, ``reasons``,
    ``baseline`` and ``comparison`` in the summary."""
    path = baseline_path(baseline_name(scenario), bdir)
    base = load_baseline(path) if scores.metrics else None
    cmp = compare(scores.metrics, base, scenario.scoring.tolerances) if base else None
    note = (f"no baseline at {path}: bless one with `srr baseline bless RUN_DIR --reason "
            "TEXT` or `srr run ... --update-baseline`")
    if "@" in baseline_name(scenario):  # a sweep point's own baseline
        note = (f"no baseline at {path}: bless every sweep point with `srr suite SUITE "
                "--update-baselines --reason TEXT`")
    files = summary.get("scene_files") if base is not None and base.config is not None \
        and "scene_files" in base.config else None  # a baseline from before srr hashed them
    mismatch = [] if base is None or base.config is None else config_differences(
        with_defaults(base.config), scene_config(scenario, files))
    if cmp is not None and mismatch:  # a baseline of another configuration judges nothing
        cmp = cmp.not_compared()
    verdict = decide(scores.health, scores.metrics, cmp, note, mismatch,
                     record_only=scenario.scoring.record_only)
    summary["verdict"], summary["exit_code"] = verdict.name, verdict.exit_code
    summary["reasons"] = list(verdict.reasons)
    summary["baseline"] = None if base is None else {
        "path": str(path), "blessed_by": base.blessed_by, "reason": base.reason,
        "blessed_at": base.blessed_at, "seed": base.seed, "digest": base.digest,
        "digest_matches": base.digest == summary["digest"],
        "config_checked": base.config is not None, "config_differences": mismatch,
        "reference": str(reference_path(path)) if base.reference
        and reference_path(path).is_file() else None,
    }
    summary["comparison"] = [] if cmp is None else [dataclasses.asdict(e) for e in cmp.entries]


def bless(run_dir: Path, reason: str, *, baselines: Path | None = None) -> Path:
    """Make a finished run the baseline of its scenario (``srr baseline bless``), in
    ``baselines`` if given, else in the folder the run was judged against (its summary's
    ``baselines_dir``; for runs from before it was recorded, :func:`baselines_dir` of its
    scenario file). An INVALID or interrupted run is refused (SrrError, exit 2)."""
    runlock.refuse_if_live(run_dir)
    summary = read_summary(run_dir)
    if summary.get("verdict") == "INVALID" or summary.get("interrupted"):
        why = " ".join("; ".join(str(r) for r in summary.get("reasons") or []).split())
        raise SrrError(f"{Path(run_dir).resolve()}: not blessed: the run is "
                       f"{summary.get('verdict', 'invalid')} ({why or 'no reason recorded'}); "
                       "only a valid, complete run can become the baseline")
    scenario = load_scenario(Path(run_dir) / "scenario.yaml")
    recorded = summary.get("baselines_dir")  # the folder the run was judged against
    path = baseline_path(baseline_name(scenario), baselines_dir(
        summary.get("scenario_file", ""), baselines if baselines is not None
        else Path(recorded) if recorded else None, scenario))
    save_baseline(path, summary, reason=reason, source_run=str(run_dir),
                  config=scene_config(scenario, summary.get("scene_files")),
                  bag=Path(run_dir) / "bag")
    return path


def run_repeat(scenario: Scenario, n: int, *, source: str = "<scenario>",
               out: Path | None = None, progress: Progress | None = None,
               baselines: Path | None = None, started: Started | None = None) -> RepeatResult:
    """Run ``n`` times (``run_1`` … ``run_n`` under one directory) and compare digests."""
    if n < 1:
        raise SrrError(f"--repeat: must be >= 1, got {n}")
    out_dir = Path(out) if out is not None else default_run_dir(scenario)
    runs = tuple(run_scenario(scenario, source=source, out=out_dir / f"run_{i + 1}",
                              progress=progress, baselines=baselines, started=started)
                 for i in range(n))
    first = runs[0].summary["topics"]
    differing = sorted({t for r in runs[1:] for t in set(first) | set(r.summary["topics"])
                        if first.get(t, {}).get("sha256")
                        != r.summary["topics"].get(t, {}).get("sha256")})
    identical = not differing
    report = {
        "runs": [str(r.run_dir) for r in runs],
        "identical": identical,
        "differing_topics": differing,
        "digests": [r.summary["digest"] for r in runs],
    }
    write_json_atomic(out_dir / "determinism.json", report)
    worst = max(r.exit_code for r in runs)
    return RepeatResult(runs, identical, tuple(differing),
                        worst if identical else max(worst, 1), out_dir)


@dataclass(frozen=True)
class RecoverResult:
    """What :func:`recover` did. ``bag.status`` says what happened to the bag (``valid``,
    ``metadata`` or ``rebuilt``); ``run_dir`` is None for a bare bag directory; ``summary``
    is the summary written for a run that had not finished (None when nothing was written);
    ``phase`` is how far the killed run had got (from its ``incomplete.json``)."""

    bag: RecoveredBag
    run_dir: Path | None
    summary: dict[str, Any] | None
    phase: str | None

    @property
    def changed(self) -> bool:
        return self.bag.status != "valid" or self.summary is not None


def _run_dir_of(path: Path) -> Path | None:
    """The run directory ``path`` is, or whose ``bag/`` it is (one with a scenario.yaml)."""
    for cand in (path, path.parent):
        if (cand / "bag").is_dir() and (cand / "scenario.yaml").is_file():
            return cand
    return None


def recover(path: str | Path) -> RecoverResult:
    """``srr recover``: make a run directory (or a bag directory) left by a killed run valid.

    The bag's MCAP file is rebuilt from its complete chunks when it was cut short
    (:func:`harness.bus.recover.recover_bag`; the original is kept as ``*.mcap.damaged``). A
    run directory that has no summary, or still holds ``incomplete.json``, or whose bag had to
    be rebuilt, gets a ``summary.json`` (and ``junit.xml``) marked ``recovered: true`` with
    verdict INVALID: per-topic counts and digests of what was kept, no scores (the run did not
    finish, so nothing is compared with the baseline). A finished run with a valid bag is left
    as it is. Raises :class:`~harness.errors.BagError` (nothing written) when the bag cannot
    be recovered, and :class:`~harness.errors.RunInUseError` (nothing touched) when the run
    is still being written: its lock is held (:mod:`harness.runlock`); a lock left by a dead
    process is free. The run directory is owned while it is recovered."""
    p = Path(path)
    base = p.parent if p.is_file() else p
    for cand in (base, base.parent):  # a run directory, or its bag/
        runlock.refuse_if_live(cand)
    run_dir = _run_dir_of(base)
    if run_dir is None:
        return _recover(p, None)
    with runlock.owning(run_dir, "recovered", fresh=False):
        return _recover(p, run_dir)


def _recover(p: Path, run_dir: Path | None) -> RecoverResult:
    marker = runmarker.read(run_dir) if run_dir is not None else None
    scenario = load_scenario(run_dir / "scenario.yaml") if run_dir is not None else None
    bag = recover_bag(p)
    if run_dir is None or scenario is None:
        return RecoverResult(bag, None, None, None)
    phase = None if marker is None else str(marker.get("phase", "unknown"))
    has_summary = (run_dir / "summary.json").is_file()
    if bag.status == "valid" and has_summary:
        runmarker.clear(run_dir)  # killed after the summary was written: the run is complete
        return RecoverResult(bag, run_dir, None, phase)
    summary = _recovered_summary(run_dir, scenario, bag, marker or {}, phase)
    write_junit(run_dir / "junit.xml", scenario.name, junit_cases(summary))
    write_json_atomic(run_dir / "summary.json", summary)
    runmarker.clear(run_dir)
    return RecoverResult(bag, run_dir, summary, phase)


def _recovered_summary(run_dir: Path, scenario: Scenario, bag: RecoveredBag,
                       marker: dict[str, Any], phase: str | None) -> dict[str, Any]:
    hz = scenario.physics.tick_hz
    last = max((t.last_ns for t in bag.topics.values() if t.last_ns is not None), default=None)
    # Stamps are tick * 1e9 // hz, so the last kept tick is ceil(last * hz / 1e9).
    ticks = 0 if last is None else -(-last * hz // 1_000_000_000) + 1
    sim_s = ticks / hz
    topics = _topic_table(bag.topics, {}, sim_s)
    for t in topics.values():
        t["published"] = None  # unknown: the run did not finish
    kept = sum(t.count for t in bag.topics.values())
    dropped = (f"; the {bag.dropped_bytes} bytes after them, an incomplete chunk, were "
               "dropped" if bag.dropped_bytes else "")
    what = {"rebuilt": f"the bag was rebuilt from its {bag.chunks} complete chunks "
                       f"({kept} messages, {sim_s:g} s of simulated time{dropped}; the "
                       f"original is kept as {bag.damaged.name if bag.damaged else '?'})",
            "metadata": f"the bag's MCAP file was complete ({kept} messages); its "
                        "metadata.yaml was rewritten",
            "valid": f"the bag was complete ({kept} messages)"}[bag.status]
    when = {"recording": "during the tick loop", "finalizing": "while finalizing (after the "
            "tick loop)"}.get(phase or "", "before it wrote its summary")
    detail = (f"the run was killed {when}; recovered with srr recover: {what}; scores were "
              "not computed")
    health = [HealthResult("recording_complete", False, detail)]
    return {
        "scenario": scenario.name,
        "scenario_file": marker.get("scenario_file", ""),
        "seed": scenario.seed,
        "srr_gt": scenario.srr_gt,
        "duration_s": scenario.duration,
        "simulated_s": sim_s,
        "ticks": ticks,
        "tick_hz": scenario.physics.tick_hz,
        "interrupted": True,
        "recovered": True,
        "recovery": {"bag": bag.status, "phase": phase, "chunks_kept": bag.chunks,
                     "messages_kept": kept, "dropped_bytes": bag.dropped_bytes,
                     "damaged_file": None if bag.damaged is None else bag.damaged.name},
        "stopped": None,
        "warnings": [],
        "health": [dataclasses.asdict(h) for h in health],
        "metrics": [],
        "graphs": [],
        "systems_under_test": [s.name for s in scenario.systems_under_test if s.enabled],
        "topics": topics,
        "digest": combined_digest(topics),
        "versions": versions(),
        "command": marker.get("command") or reproduce_command(
            marker.get("scenario_file", str(run_dir / "scenario.yaml")), scenario, run_dir),
        "verdict": "INVALID",
        "exit_code": 3,
        "reasons": [f"health recording_complete: {detail}"],
        "baseline": None,
        "comparison": [],
    }
def diff_runs(a: str | Path, b: str | Path, *,
              tolerances: Sequence[Tolerance | str] = ()) -> DiffResult:
    """Compare two run directories (``srr diff A B``): per topic counts, digests, the first
    divergence and per-field differences against ``tolerances``
    (``TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]`` strings or :class:`Tolerance`), and both runs'
    metrics side by side. ``result.exit_code`` is 0 when the recorded data are equal within
    tolerance, 1 when not; bad input raises :class:`SrrError` (exit 2), and so does a run
    still being written (:mod:`harness.runlock`)."""
    for run in (a, b):
        runlock.refuse_if_live(run)
    return _diff_runs(a, b, tolerances=tolerances)


def suite(paths: Sequence[str | Path], *, executor: str = "local", jobs: int | None = None,
          address: str | None = None, repeat: int | None = None, out: Path | None = None,
          timeout_s: float | None = None, history: Path | None = None,
          baselines: Path | None = None, gpu_share: float = 0.5,
          bless_reason: str | None = None, listen: Any = None, fork: bool = False) -> Any:
    """``srr suite``: check every scenario, sweep point and suite file in ``paths`` (bad input
    raises :class:`SrrError` before anything runs), run them on ``executor`` (``local``: ``jobs``
    worker processes, default one per CPU; ``ray``: tasks on the cluster at ``address``, else on
    a local cluster started for the suite) and write ``out``'s ``summary.json``, ``junit.xml``
    and ``index.html``. Returns a :class:`harness.suite.runner.SuiteResult`; ``listen`` gets
    :class:`harness.suite.events.Event` s as runs start and finish. ``fork``: local workers
    are forked from this process when it is safe (:func:`harness.suite.local.fork_safe`; what
    ``srr suite`` does), saving each run the interpreter's start-up and imports."""
    from harness.suite.runner import plan_suite

    plan = plan_suite(paths, repeat=repeat, timeout_s=timeout_s)
    return run_planned_suite(plan, executor=executor, jobs=jobs, address=address, out=out,
                             history=history, baselines=baselines, gpu_share=gpu_share,
                             bless_reason=bless_reason, listen=listen, fork=fork)


def run_planned_suite(plan: Any, *, executor: str = "local", jobs: int | None = None,
                      address: str | None = None, out: Path | None = None,
                      history: Path | None = None, baselines: Path | None = None,
                      gpu_share: float = 0.5, bless_reason: str | None = None,
                      listen: Any = None, fork: bool = False) -> Any:
    """:func:`suite` for a plan already checked (:func:`harness.suite.runner.plan_suite`)."""
    import os

    from harness.suite.local import LocalExecutor
    from harness.suite.ray_executor import RayExecutor
    from harness.suite.runner import run_suite

    if jobs is not None and jobs < 1:
        raise SrrError(f"--jobs: must be >= 1, got {jobs}")
    if executor not in ("local", "ray"):
        raise SrrError(f"--executor: expected local or ray, got {executor!r}")
    if address is not None and executor != "ray":
        raise SrrError("--address: only with --executor ray")
    ex: Any = (LocalExecutor(jobs or os.cpu_count() or 1, baselines=baselines, fork=fork)
               if executor == "local" else
               RayExecutor(address=address, jobs=jobs, baselines=baselines, gpu_share=gpu_share))
    return run_suite(plan, ex, out=out, history=history, listen=listen,
                     bless_reason=bless_reason, baselines=baselines)


def write_diff(result: DiffResult, path: str | Path) -> Path:
    """Write the one-page HTML view of ``result`` (``srr diff --html FILE``): both runs'
    trajectories on one map, their time series overlaid, metric deltas, the topic table and
    camera keyframes side by side at the first divergence and the worst moments."""
    from harness.diff.html import write_diff as _write

    return _write(result, path)
