"""Recording a run: own the run directory, record the tick loop into the bag, score, judge
and write the outputs. Shared by a run of a scenario (:mod:`harness.run.simulate`) and an
open-loop replay (:mod:`harness.run.replay`), which differ only in the :class:`Loop` they
record.

The steps of :func:`record`, each a function here:

1. :func:`prepare` — refuse a live or non-empty run directory (before anything is built);
2. :func:`record` — own the directory (:mod:`harness.runlock`) for the steps below;
3. :func:`_open_recorder` — the in-progress marker, ``scenario.yaml``, the recorder;
4. :func:`_tick_loop` — the participants attached to the recorder, then the ticks, under the
   disk-space guard; a stop at a tick boundary or Ctrl-C keeps what was recorded;
5. :func:`_score` — close the recorder, tabulate the topics and score the recording;
6. :func:`_summarize` — the run's summary (without its verdict);
7. :func:`_update_baseline` (``--update-baseline``) and :func:`harness.run.judge.judge`;
8. :func:`_write_outputs` — ``junit.xml``, ``summary.json`` (the run is complete from here),
   then ``report.html``.

Everything that takes part in the run is a :class:`~harness.sut.participant.RunParticipant`,
its hooks called here and by the engine, in this order: the systems under test (the
scenario's plug-ins, then the ROS 2 bridge) are set up, stepped and shut down by the loop
(:mod:`harness.engine`); the run's own participants (``participants``: the live view, the
RTSP streams, :mod:`harness.run.participants`) were started before :func:`record`. Once the
recorder is open, every one is ``attach``-ed (systems under test first, then the run's
participants, in order); after each tick every one gets ``after_tick``; the loop closes
(the systems under test's ``shutdown``) when the ticks end; ``warnings`` go into the summary;
the run's participants are ``shutdown`` last, in reverse order, once the run directory is
released, however the run ends.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import shutil
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from harness import runlock, runmarker
from harness.atomic import write_text_atomic
from harness.bus import Bus
from harness.camera_topics import unrecorded_topics
from harness.diskspace import MB, DiskGuard, FreeSpace, disk_free
from harness.errors import RunStopped, SrrError
from harness.interrupt import INTERRUPTED_EXIT, StopRequests
from harness.memory import release_free_memory
from harness.metrics.types import HealthResult
from harness.outdir import check_out_folder, first_missing, remove_empty
from harness.output import ROS2_OUTPUT, OutputKind
from harness.recording.bagfile import ChunkPolicy
from harness.regression import baseline_path, save_baseline
from harness.report.graphs import RunGraphs, write_graphs
from harness.report.junit import junit_cases, write_junit
from harness.run.baselines import baseline_name, baselines_dir, blessing_refusal, scene_config
from harness.run.facts import (
    combined_digest,
    scenario_path,
    sut_endpoints,
    topic_table,
    versions,
    write_scenario,
)
from harness.run.graphs import rebuild_graphs
from harness.run.judge import judge
from harness.run.summary import RunSummary, TopicRow
from harness.scenario import Scenario
from harness.scoring import Scores, scenario_frames, score_frames
from harness.sim.render import gl_renderer_name
from harness.sut.base import SutContext
from harness.sut.participant import Participant

if TYPE_CHECKING:
    from harness.frames import Frames

__all__ = ["AFTER_THE_LOOP", "Loop", "Progress", "RunResult", "Started", "import_after_the_loop",
           "prepare", "record", "unprepare"]

#: What a run imports only once it has been recorded, where it is used: scoring's frames and
#: metrics (pandas), the report (Jinja2, its plots), and SciPy's assignment solver, which
#: perception scoring imports at its first match (a single run without tracks never does). A
#: run starts its loop without them.
AFTER_THE_LOOP = ("harness.frames", "harness.metrics.control", "harness.metrics.health",
                  "harness.metrics.perception", "harness.metrics.safety", "harness.report.html",
                  "scipy.optimize")

#: A run stopped by a plug-in's error keeps its traceback here, in the run directory.
TRACEBACK_NAME = "traceback.txt"

Progress = Callable[[int, int], None]
Started = Callable[[Path], None]  # told the run directory once it is created and owned


@dataclass(frozen=True)
class RunResult:
    """A recorded run: its directory, verdict and exit code, and its summary, as
    ``summary.json`` holds it (``summary``) and typed (``run_summary``)."""

    run_dir: Path
    verdict: str
    exit_code: int
    summary: dict[str, Any]
    run_summary: RunSummary
    #: ``--update-baseline``: the baseline written from this run, or why it was not
    blessed: Path | None = None
    not_blessed: str | None = None


@dataclass(frozen=True)
class Loop:
    """What the shared recording path needs from a loop: its bus, systems under test, tick
    counter and ``step``/``close``, plus what the summary says about it."""

    bus: Bus
    suts: Sequence[tuple[str, Participant, SutContext]]
    step: Callable[[], None]  # one tick
    close: Callable[[], None]
    ticks: Callable[[], int]
    srr_gt: bool
    command: str  # what reproduces the run
    warnings: tuple[str, ...] = ()  # found before the run (wiring, rates, output topics)
    graph_paths: tuple[Any, ...] = ()  # the action graphs' files (summary "graphs")
    scene_files: Mapping[str, str] | None = None  # model files' digests by field
    world_map: Any = None  # a world file's static geometry, for the report's map
    replay_of: Mapping[str, Any] | None = None  # what a replay plays back
    graphs: RunGraphs | None = None  # written into the run directory (graphs.json)
    output: OutputKind = ROS2_OUTPUT  # what the recorder writes (harness.output)


def prepare(run_dir: Path) -> Path | None:
    """Refuse a run directory another process is writing, one that is not empty, or a path
    where no folder can be. Returns the folder a failed start must remove: the outermost one
    that making ``run_dir`` creates (``reports/<scenario>`` for the first run of a scenario),
    or None when ``run_dir`` is an empty folder already (the user's: a failed start empties
    it). Nothing is made here."""
    check_out_folder(run_dir)
    runlock.refuse_if_live(run_dir)
    if run_dir.exists() and any(run_dir.iterdir()):
        raise SrrError(f"--out {run_dir}: directory exists and is not empty")
    return first_missing(run_dir)


def unprepare(run_dir: Path, made: Path | None, err: BaseException) -> None:
    """A run that failed (``err``) before :func:`record` took its directory leaves nothing
    there (the external ROS 2 processes' logs, written as they start): the run directory
    goes, and so do the folders :func:`prepare` said making it would make while they are
    empty (a suite's other runs make theirs beside it), or the user's folder is emptied
    (``made`` None); unless ``err`` names a file in it (an external node that died before it
    was ready: its log says why)."""
    if str(run_dir) in str(err):
        return
    if made is not None:  # the run's folder, then the folders made for it while empty:
        # other runs (a suite's) may have made theirs beside it in the meantime
        shutil.rmtree(run_dir, ignore_errors=True)
        remove_empty(run_dir.parent, made)
    elif run_dir.is_dir():
        for child in run_dir.iterdir():
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child, ignore_errors=True)
            else:
                child.unlink(missing_ok=True)


def record(scenario: Scenario, loop: Loop, *, source: str, run_dir: Path, n_ticks: int,
           progress: Progress | None, baselines: Path | None, update_baseline: bool = False,
           update_reason: str = "", allow_failing: bool = False,
           free_space: FreeSpace = disk_free, participants: Sequence[Participant] = (),
           started: Started | None = None, video: bool = True,
           made: Path | None) -> RunResult:
    """:func:`write_run` while this process owns ``run_dir`` (:mod:`harness.runlock`): it is
    created and locked first (a live owner is refused), and released, its lock file
    removed, however the run ends (``kill -9`` releases the lock too). ``participants``
    (started) are shut down after that, in reverse order, however the run ends.
    ``made``: :func:`prepare`'s answer, the outermost folder making ``run_dir`` creates; a run
    that fails and removes ``run_dir`` removes the empty folders up to it too. None: the
    (empty) folder was the user's before the run (not one the external ROS 2 processes' logs
    made since), and a failed run leaves it."""
    with contextlib.ExitStack() as owned:
        if made is None:
            owned.callback(lambda: run_dir.mkdir(exist_ok=True))
        for p in participants:  # called last, in reverse order
            owned.callback(p.shutdown)
        try:
            owned.enter_context(runlock.owning(run_dir, "written", fresh=True))
            if started is not None:
                started(run_dir)
        except BaseException:
            loop.close()  # which write_run does once it runs
            raise
        try:
            return write_run(scenario, loop, source=source, run_dir=run_dir, n_ticks=n_ticks,
                             progress=progress, baselines=baselines,
                             update_baseline=update_baseline, update_reason=update_reason,
                             allow_failing=allow_failing, free_space=free_space,
                             participants=participants, video=video)
        except BaseException:
            if made is not None and not run_dir.exists():
                remove_empty(run_dir.parent, made)
            raise


@dataclass(frozen=True)
class _Ended:
    """How the tick loop ended: ``interrupted`` (Ctrl-C), or ``stopped`` at a tick boundary
    by the health gate ``gate`` (the disk-space guard, or a :class:`RunStopped`)."""

    interrupted: bool = False
    stopped: str | None = None
    gate: str = "disk_space"


def write_run(scenario: Scenario, loop: Loop, *, source: str, run_dir: Path, n_ticks: int,
              progress: Progress | None, baselines: Path | None, update_baseline: bool = False,
              update_reason: str = "", allow_failing: bool = False,
              free_space: FreeSpace = disk_free,
              participants: Sequence[Participant] = (), video: bool = True) -> RunResult:
    """Record ``loop`` into ``run_dir``, score it and write the run directory. Until
    ``summary.json`` is written the directory holds ``incomplete.json``
    (:mod:`harness.runmarker`), so a killed run never looks done. ``participants`` (the
    run's own, started: the live view gets every message the recorder serializes and, after
    each tick, the simulation time; it may hold the first tick for a client and pace the
    loop) are attached and told of each tick after the systems under test. ``video=False``:
    the report without camera videos (``srr run --no-video``)."""
    command = loop.command
    try:  # nothing recorded yet: an error (or Ctrl-C) here leaves no half-made directory
        recorder = _open_recorder(scenario, loop, run_dir, source=source, command=command)
    except BaseException:
        loop.close()
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    ended = _tick_loop(scenario, loop, recorder, run_dir, n_ticks=n_ticks, progress=progress,
                       free_space=free_space, participants=participants)
    with _half_written(run_dir):
        # The recorder's queue written out and the bag closed before the phase says the loop
        # is over: a run killed while finalizing has its whole recording on disk.
        stats = recorder.close()
    runmarker.mark(run_dir, "finalizing", scenario_file=scenario_path(source),
                   command=command)
    with _half_written(run_dir):
        scores, frames, topics, sim_s = _score(scenario, loop, recorder, stats, run_dir,
                                               source)
    if ended.stopped is not None:  # the gate that stopped the run first: the cause, then
        # what came of it (topics that fell short of their rates, ...)
        scores = dataclasses.replace(
            scores, health=(HealthResult(ended.gate, False, ended.stopped), *scores.health))
    bdir = baselines_dir(source, baselines, scenario)
    summary = _summarize(scenario, loop, recorder, source=source, scores=scores,
                         topics=topics, sim_s=sim_s, ended=ended, bdir=bdir,
                         participants=participants)
    blessing = update_baseline and not ended.interrupted
    j = judge(scenario, scores, bdir, digest=summary.digest, scene_files=summary.scene_files,
              topics=summary.topics, versions=summary.versions, blessing=blessing)
    summary = dataclasses.replace(summary, verdict=j.verdict, exit_code=j.exit_code,
                                  reasons=j.reasons, baseline=j.baseline,
                                  comparison=j.comparison)
    if ended.interrupted:
        summary = dataclasses.replace(summary, verdict="INTERRUPTED", exit_code=INTERRUPTED_EXIT,
                                      reasons=("interrupted before the end of the scenario",))
    data = _write_outputs(scenario, summary, run_dir, frames, video=video)
    blessed = not_blessed = None
    if blessing:  # judged against the baseline it replaces, written out, then blessed
        refusal = blessing_refusal(summary, allow_failing=allow_failing)
        if refusal is None:
            blessed = _update_baseline(scenario, summary, bdir, run_dir, update_reason)
        else:
            not_blessed = f"{run_dir}: not blessed: {refusal}"
    return RunResult(run_dir, summary.verdict, summary.exit_code, data, summary,
                     blessed=blessed, not_blessed=not_blessed)


@contextlib.contextmanager
def _half_written(run_dir: Path) -> Iterator[None]:
    """A step after the loop, before ``summary.json`` exists: an error removes the directory;
    Ctrl-C leaves it as a killed run's (what was recorded stays, for ``srr recover``) and
    says where."""
    try:
        yield
    except KeyboardInterrupt as err:
        raise KeyboardInterrupt(f"the recording is in {run_dir}; `srr recover {run_dir}` "
                                "makes it a finished run directory") from err
    except BaseException:
        shutil.rmtree(run_dir, ignore_errors=True)
        raise


def _open_recorder(scenario: Scenario, loop: Loop, run_dir: Path, *, source: str,
                   command: str) -> Any:
    """The in-progress marker, the resolved ``scenario.yaml`` and the action graphs, then the
    recorder (not yet opened) of the loop's output."""
    runmarker.mark(run_dir, "recording", scenario_file=scenario_path(source),
                   command=command)
    write_scenario(run_dir, scenario)
    if loop.graphs is not None:
        write_graphs(run_dir, loop.graphs)
    rec = scenario.recording
    return loop.output.recorder(run_dir / "bag", ChunkPolicy(
        max_bytes=round(rec.chunk_mb * MB), max_span_ns=round(rec.chunk_s * 1e9),
        fsync=rec.fsync, compression=rec.compression),
        unrecorded=unrecorded_topics(scenario))


def _tick_loop(scenario: Scenario, loop: Loop, recorder: Any, run_dir: Path, *, n_ticks: int,
               progress: Progress | None, free_space: FreeSpace,
               participants: Sequence[Participant]) -> _Ended:
    """Open the recorder on the bus and attach every participant to it (the systems under
    test, then ``participants``), then run the ticks, each followed by every participant's
    ``after_tick``.
    A low disk or a :class:`RunStopped` stops the loop at a tick boundary and Ctrl-C (or
    SIGTERM) ends it, whatever error it became where it landed, what was recorded kept; any
    other error removes the run directory. The loop is closed however it ends."""
    guard = DiskGuard(run_dir, round(scenario.recording.min_free_mb * MB), free_space,
                      every_ticks=scenario.physics.tick_hz)
    hz = scenario.physics.tick_hz
    stop = StopRequests(at_once=True)
    try:
        recorder.open(loop.bus.qos)
        loop.bus.add_tap(recorder)
        everyone = (*(sut for _, sut, _ in loop.suts), *participants)
        for p in everyone:  # the ROS 2 bridge publishes the recorder's bytes; the live view
            p.attach(recorder)  # serves them
        with stop.installed():
            for _ in range(n_ticks):
                loop.step()
                ticks = loop.ticks()
                now_ns = (ticks - 1) * 1_000_000_000 // hz  # the tick just run
                for p in everyone:
                    p.after_tick(now_ns)
                if progress is not None:
                    progress(ticks, n_ticks)
                if ticks % hz == 0:  # flat resident memory however long the run
                    release_free_memory()
                low = guard.poll(ticks, recorder.bytes_serialized)
                if low is not None:
                    return _Ended(stopped=f"{low}: the run was stopped after "
                                          f"{ticks / hz:g} s of simulated time")
                stop.check()  # a Ctrl-C that code in the tick caught and dropped
    except KeyboardInterrupt:
        return _interrupted(loop, recorder, run_dir)
    except RunStopped as err:  # at a tick boundary: what was recorded stays, INVALID
        if stop.requested:  # a Ctrl-C that a plug-in's error (SutRaised) carries
            return _interrupted(loop, recorder, run_dir)
        said = str(err)
        if err.details:  # a plug-in's traceback, beside the recording
            write_text_atomic(run_dir / TRACEBACK_NAME, err.details)
            said += f" (traceback: {run_dir / TRACEBACK_NAME})"
        return _Ended(gate=err.gate, stopped=f"{said}; the run was stopped after "
                                             f"{loop.ticks() / hz:g} s of simulated time")
    except BaseException:
        if stop.requested:  # a Ctrl-C that became another error where it landed
            return _interrupted(loop, recorder, run_dir)
        with contextlib.suppress(Exception):  # the original error is the one to report
            recorder.close()
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    finally:
        loop.close()
    return _Ended()


def _interrupted(loop: Loop, recorder: Any, run_dir: Path) -> _Ended:
    """Ctrl-C (or SIGTERM) in the tick loop: the run ends INTERRUPTED with what it recorded;
    before its first tick (a live view waiting for a client) nothing was: the directory goes
    and the interrupt goes on (``srr run: interrupted``)."""
    if loop.ticks() == 0:
        with contextlib.suppress(Exception):
            recorder.close()
        shutil.rmtree(run_dir, ignore_errors=True)
        raise KeyboardInterrupt(f"before the first tick: nothing was recorded and {run_dir} "
                                "was removed")
    return _Ended(interrupted=True)


def import_after_the_loop() -> None:
    """Import :data:`AFTER_THE_LOOP` now: a process about to fork workers for many runs (``srr
    suite``) shares them with every worker (copy-on-write), instead of each importing them at
    its first run's end."""
    for name in AFTER_THE_LOOP:
        importlib.import_module(name)


def _score(scenario: Scenario, loop: Loop, recorder: Any, stats: Any, run_dir: Path,
           source: str) -> tuple[Scores, Frames, dict[str, TopicRow], float]:
    """Score what the (closed) recorder recorded, ``stats`` its per-topic statistics: the
    scores, the frames read from the bag (for the report), the topic table and the simulated
    seconds."""
    release_free_memory()  # the loop's buffers, before scoring reads the bag
    published = {t: n for t, n in loop.bus.published_counts().items()
                 if t not in recorder.unrecorded}
    sim_s = loop.ticks() / scenario.physics.tick_hz
    topics = topic_table(stats, published, sim_s)
    frames = scenario_frames(scenario, run_dir / "bag")
    scores = score_frames(scenario, frames, srr_gt=loop.srr_gt, published=published,
                          recorded={t: st.count for t, st in stats.items()},
                          duration_s=sim_s, source=source)
    return scores, frames, topics, sim_s


def _summarize(scenario: Scenario, loop: Loop, recorder: Any, *, source: str, scores: Scores,
               topics: dict[str, TopicRow], sim_s: float, ended: _Ended,
               bdir: Path, participants: Sequence[Participant]) -> RunSummary:
    """The run's summary, not yet judged (INVALID until :func:`harness.run.judge.judge`)."""
    # what participants noticed while running (the ROS 2 bridge: topics it could not bridge)
    noticed = [w for p in (*(sut for _, sut, _ in loop.suts), *participants)
               for w in p.warnings()]
    return RunSummary(
        scenario=scenario.name, scenario_file=scenario_path(source), seed=scenario.seed,
        srr_gt=loop.srr_gt,
        duration_s=scenario.duration, simulated_s=sim_s, ticks=loop.ticks(),
        tick_hz=scenario.physics.tick_hz, interrupted=ended.interrupted,
        stopped=ended.stopped, warnings=(*loop.warnings, *noticed), health=scores.health,
        metrics=tuple(dataclasses.asdict(m) for m in scores.metrics), graphs=loop.graph_paths,
        systems_under_test=tuple(name for name, _, _ in loop.suts),
        sut_endpoints=sut_endpoints(loop.suts), output=loop.output.summary(),
        topics=topics, digest=combined_digest(topics),
        versions=versions(gl_renderer_name() if scenario.camera_count else None),
        scene_files=loop.scene_files, command=loop.command, replay_of=loop.replay_of,
        world_map=loop.world_map,
        # published in the run, recorded compressed (or not at all)
        unrecorded={t: {"type": ty, "published": n} for t, (ty, n)
                    in recorder.skipped().items()} if recorder.unrecorded else None,
        baselines_dir=str(bdir),  # where bless writes this run's baseline
        verdict="INVALID", exit_code=3)


def _update_baseline(scenario: Scenario, summary: RunSummary, bdir: Path, run_dir: Path,
                     reason: str) -> Path:
    """``--update-baseline``: this valid, finished run becomes its scenario's baseline; its
    path."""
    path = baseline_path(baseline_name(scenario), bdir)
    save_baseline(path, summary.to_json(), reason=reason, source_run=str(run_dir),
                  config=scene_config(scenario, summary.scene_files), bag=run_dir / "bag")
    return path


def _write_outputs(scenario: Scenario, summary: RunSummary, run_dir: Path,
                   frames: Frames, *, video: bool = True) -> dict[str, Any]:
    """``junit.xml``, then ``summary.json`` (the run is complete from here on: the marker
    goes), then ``report.html``, last: a report that fails to render never costs the run its
    summary. Returns the summary as written."""
    data = summary.to_json()
    write_junit(run_dir / "junit.xml", scenario.name, junit_cases(data))
    summary.write(run_dir)
    runmarker.clear(run_dir)
    # imported here: the report (Jinja2, its plots) is needed only once a run has been
    # recorded, so a run starts its loop without it
    from harness.report.html import write_report

    try:
        write_report(run_dir, summary=data, scenario=scenario, frames=frames,
                     rebuild_graphs=rebuild_graphs, video=video)
    except SrrError:
        raise
    except KeyboardInterrupt as err:  # the run is complete; only its report is missing
        raise KeyboardInterrupt(f"the run is complete in {run_dir} but has no report; "
                                f"`srr report {run_dir}` renders it") from err
    except Exception as err:
        raise SrrError(f"{run_dir / 'report.html'}: the report could not be rendered "
                       f"({type(err).__name__}: {err}); summary.json is complete") from err
    return data
