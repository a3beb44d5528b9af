"""Open-loop replay of a recorded run (``srr replay``): its bag played back into its systems
under test, or replacements, and the new run recorded, scored and judged like a run of the
recorded scenario (:mod:`harness.replay` plays it; :mod:`harness.run.record` records it).

With ``ros2.enabled`` (``srr replay --ros2``, or a recording of ``srr run --ros2``) the ROS 2
bridge of a run (:func:`~harness.run.simulate.ros2_bridge`) joins the replay: the recorded
bytes go out on the run's own ROS 2 graph tick by tick, the external processes of
``ros2.external`` (``--ros2-external NAME=CMD`` swaps one's command) are started, and each
tick waits, in lockstep, for the outputs they are due to publish, which are recorded in
place of the recorded ones."""

from __future__ import annotations

import json
import shlex
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from harness import runlock
from harness.bus import Bus
from harness.diskspace import check_free_space, disk_free
from harness.errors import ScenarioError, SrrError
from harness.live.config import LiveConfig
from harness.live.view import LiveView
from harness.recording.verify import verify_recording
from harness.regression import comparable_config, config_differences
from harness.replay import Playback, Replay
from harness.report.graphs import read_graphs
from harness.run.baselines import baselines_dir
from harness.run.facts import default_run_dir
from harness.run.judge import check_baseline
from harness.run.participants import LiveViewParticipant
from harness.run.record import Loop, Progress, RunResult, Started, prepare, record, unprepare
from harness.run.simulate import Notice, ros2_bridge
from harness.run.summary import RunSummary
from harness.scenario import Scenario, load_scenario, parse_override, scenario_to_mapping
from harness.scoring import check_scoring
from harness.sut.base import load_suts
from harness.sut.participant import Participant

__all__ = ["replay"]


def replay(run_dir: str | Path, *, suts: Sequence[str] = (), overrides: Sequence[str] = (),
           out: Path | None = None, progress: Progress | None = None,
           baselines: Path | None = None, started: Started | None = None,
           ros2: bool = False, externals: Sequence[str] = (), live: LiveConfig | None = None,
           notice: Notice | None = None) -> RunResult:
    """Open-loop replay of a recorded run (``srr replay``): its bag played back, in
    publication order, into its systems under test — or into replacements (``suts``:
    ``NAME=module:Class``) and changed parameters (``overrides``: ``--set`` on the systems
    under test, the scoring and the ``ros2`` block). What the systems under test published
    is produced again; everything else is the recording's bytes. The new run directory is
    scored and judged like a run of the recorded scenario (:mod:`harness.replay`).

    ``ros2`` (= ``--set ros2.enabled=true``): the replay goes out on a live ROS 2 graph and
    the external nodes of ``ros2.external`` produce ``ros2.outputs`` in lockstep;
    ``externals`` (``NAME=CMD``, a shell-quoted command line) swaps the command of the
    external process ``NAME``. ``live`` serves the replay over the Foxglove WebSocket
    protocol (``--foxglove``; its ``rate`` paces it)."""
    src = Path(run_dir)
    runlock.refuse_if_live(src)
    summary = RunSummary.read(src)
    if summary.recovered or summary.interrupted or summary.stopped:
        # a replay plays the recording to its end and scores what it ran as a whole run
        why = ("recovered after its run was killed" if summary.recovered else
               "interrupted" if summary.interrupted else "stopped early")
        raise SrrError(f"{src}: its recording was cut short ({why}, {summary.simulated_s:g} "
                       f"of {summary.duration_s:g} s): a replay would score a shorter run as "
                       "a whole one; replay a run that finished")
    # the recording played back is the one the summary describes, every chunk's CRC checked:
    # the verification `srr diff`, `srr report` and `srr baseline bless` do
    verify_recording(src, summary.to_json())
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
    ros2_changes = (["ros2.enabled=true"] if ros2 and not recorded.ros2.enabled else []) + [
        _external_override(load_scenario(src / "scenario.yaml", pairs), text, src)
        for text in externals]
    pairs += [parse_override(o) for o in ros2_changes]
    source = str(summary.scenario_file or src / "scenario.yaml")
    try:
        scenario = load_scenario(src / "scenario.yaml", pairs)
    except SrrError as err:
        raise _named_by_flag(err, recorded, source, suts) from None
    _check_replay_scene(recorded, scenario)
    check_scoring(scenario, srr_gt=summary.srr_gt, source=source)
    judged = summary.baselines_dir  # judged against the recorded run's baselines
    baselines = baselines_dir(source, baselines if baselines is not None
                              else Path(judged) if judged else None, scenario)
    check_baseline(scenario, baselines)
    playback = Playback(src / "bag")
    if playback.output.ros == 1 and live is not None:  # (ros2.enabled: the scenario says)
        raise SrrError(f"{src}: --foxglove: the live view serves ROS 2 messages, and "
                       f"{playback.output.because}")
    if playback.output.ros == 1 and scenario.ros2.enabled:
        raise SrrError(f"{src}: --ros2: the live ROS 2 bridge plays ROS 2 messages, and "
                       f"{playback.output.because}")
    out_dir = Path(out) if out is not None else default_run_dir(scenario, suffix="-replay")
    made = prepare(out_dir)  # before the external processes write their logs into it
    withheld = _recorded_outputs(summary.sut_endpoints, recorded, source)
    try:
        rep = Replay(scenario, playback, withheld, source,
                     joined=ros2_bridge(scenario, out_dir, source))
    except SrrError as err:
        raise _named_by_flag(err, scenario, source, suts) from None
    participants: list[Participant] = []
    try:
        rep.start()
        withheld |= {e.topic for _, _, ctx in rep.suts for e in ctx.endpoints
                     if e.kind == "pub"}
        warnings = _replay_wiring(rep, playback, withheld)
        check_free_space(scenario, out_dir, disk_free)
        if live is not None:  # every topic the replay will publish, advertised up front
            topics = {t: r.msgtype for t, r in playback.topics.items() if t not in withheld}
            topics |= {e.topic: e.msgtype for _, _, ctx in rep.suts for e in ctx.endpoints
                       if e.kind == "pub"}
            participants.append(LiveViewParticipant(
                LiveView.start(live, topics=topics, notice=notice), rep.bus))
    except BaseException as err:
        rep.close()
        for p in participants:
            p.shutdown()
        unprepare(out_dir, made, err)
        raise
    command = " ".join(["srr replay", str(src), *(f"--sut {t}" for t in suts),
                        *(f"--set {o}" for o in overrides), *(["--ros2"] if ros2 else []),
                        *(f"--ros2-external {shlex.quote(t)}" for t in externals),
                        f"--out {out_dir}"])
    replay_of = {
        "run_dir": str(src.resolve()), "digest": summary.digest,
        "mode": "ros2-lockstep" if scenario.ros2.enabled else "open-loop",
        "replaced": {t.partition("=")[0].strip(): t.partition("=")[2].strip() for t in suts},
        "overrides": [*overrides, *ros2_changes], "withheld": sorted(withheld)}
    try:  # the recorded scene's graphs; without them the report rebuilds them
        graphs = read_graphs(src)
    except (OSError, ValueError):
        graphs = None
    loop = Loop(rep.bus, rep.suts, rep.step_tick, rep.close, lambda: rep.tick_index,
                summary.srr_gt, command=command, warnings=tuple(warnings),
                scene_files=dict(summary.scene_files or {}), replay_of=replay_of,
                world_map=summary.world_map,  # the recorded scene, as it was
                output=playback.output, graphs=graphs)
    return record(scenario, loop, source=source, run_dir=out_dir,
                   n_ticks=int(summary.ticks or scenario.n_ticks), progress=progress,
                   baselines=baselines, started=started, participants=participants, made=made)


def _named_by_flag(err: SrrError, scenario: Scenario, source: str,
                   suts: Sequence[str]) -> SrrError:
    """``err`` about the plug-in a ``--sut NAME=module:Class`` gave, said of that flag (the
    loader names the scenario's entry, whose plug-in the flag replaced, or the ``--set`` the
    flag stands for), else ``err``."""
    names = [s.name for s in scenario.systems_under_test]
    for text in suts:
        name = text.partition("=")[0].strip()
        if name in names:
            field = f"systems_under_test[{names.index(name)}].plugin"
            if isinstance(err, ScenarioError) and (err.file, err.field) == ("--set", field):
                return SrrError(f"--sut {text}: {err.message}")
            for prefix in (f"{source}: {field}: ", f"--set: {field}: "):
                if str(err).startswith(prefix):
                    return SrrError(f"--sut {text}: {str(err)[len(prefix):]}")
    return err


def _external_override(scenario: Scenario, text: str, src: Path) -> str:
    """``--ros2-external NAME=CMD`` as the ``--set`` it stands for:
    ``ros2.external.NAME.cmd=[...]``, CMD split like a shell command line."""
    name, sep, cmd = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise ScenarioError("--ros2-external", text, "expected NAME='command and arguments'")
    names = [p.name or f"external_{i}" for i, p in enumerate(scenario.ros2.external)]
    if name not in names:
        raise ScenarioError("--ros2-external", name, f"no external process named {name!r} in "
                            f"the ros2 block of {src / 'scenario.yaml'} (names: "
                            f"{', '.join(names) or 'none'})")
    try:
        argv = shlex.split(cmd)
    except ValueError as err:
        raise ScenarioError("--ros2-external", name, f"cannot split the command: {err}") \
            from None
    if not argv:
        raise ScenarioError("--ros2-external", name, "the command is empty")
    if shutil.which(argv[0]) is None:
        raise ScenarioError("--ros2-external", name, f"{argv[0]!r} is not an executable file "
                            "or on PATH")
    return f"ros2.external.{names.index(name)}.cmd={json.dumps(argv)}"


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


def _recorded_outputs(eps: Mapping[str, Any] | None, recorded: Scenario,
                      source: str) -> set[str]:
    """Topics the recorded run's systems under test published: from its summary's
    ``sut_endpoints`` (``eps``), or, for runs recorded before it kept them, by setting the
    recorded plug-ins up on a scratch bus."""
    if isinstance(eps, Mapping):  # checked when the summary was read
        return {t for v in eps.values() for t in v.get("publishes", [])}
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
    first: dict[str, str] = {}  # topic → the system under test that publishes it first
    for name, _, ctx in rep.suts:
        for topic in dict.fromkeys(e.topic for e in ctx.endpoints if e.kind == "pub"):
            if topic in first:  # as a run's wiring check says it
                warnings.append(f"{ctx.field}: {name} publishes {topic}, which {first[topic]} "
                                "publishes too")
            first.setdefault(topic, name)
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
