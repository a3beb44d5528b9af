"""The Python API: everything the CLI does is a call here. A facade: the run pipeline lives in
:mod:`harness.run` (its steps named there), the suite in :mod:`harness.suite`.

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
    video/          its camera videos and clips (WebM), played in report.html
    incomplete.json only while the run has not finished (harness.runmarker): a killed run
                    keeps it, and ``recover`` turns such a directory back into a valid one
    run.lock        only while a process writes the directory (harness.runlock): its lock
                    says the run is live, and every command that reads a run refuses it then
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from harness import runlock
from harness._lazy import lazy_exports
from harness.errors import SrrError
from harness.live.config import LiveConfig

if TYPE_CHECKING:
    from harness.diff import DiffResult, Tolerance
    from harness.engine import Simulation
    from harness.export.rerun import RerunExport
    from harness.run.baselines import (
        PROJECT_MARKERS,
        baseline_name,
        baselines_dir,
        bless,
        scene_config,
    )
    from harness.run.facts import combined_digest, default_run_dir, reproduce_command, versions
    from harness.run.loading import load
    from harness.run.record import Progress, RunResult, Started, import_after_the_loop
    from harness.run.recover import RecoverResult, recover
    from harness.run.replay import replay
    from harness.run.rerender import report
    from harness.run.simulate import (
        ROS2_BRIDGE,
        Notice,
        RepeatResult,
        check_video,
        ros2_bridge,
        run_repeat,
        run_scenario,
        start_streams,
        validate,
    )
    from harness.scenario import Scenario
    from harness.search.runner import SearchResult
    from harness.suite.diff import SuiteDiff
    from harness.suite.events import Listener
    from harness.suite.resume import Resumed
    from harness.suite.runner import SuitePlan, SuiteResult, plan_suite

__all__ = [
    "PROJECT_MARKERS",
    "ROS2_BRIDGE",
    "SCHEMA_KINDS",
    "LiveConfig",
    "Notice",
    "Progress",
    "RecoverResult",
    "RepeatResult",
    "RerunExport",
    "Resumed",
    "RunResult",
    "Started",
    "SuitePlan",
    "SuiteResult",
    "baseline_name",
    "baselines_dir",
    "bless",
    "build_graphs",
    "check_video",
    "combined_digest",
    "default_run_dir",
    "diff_runs",
    "diff_suites",
    "export_rerun",
    "graph_text",
    "import_after_the_loop",
    "json_schema",
    "load",
    "plan_suite",
    "recover",
    "replay",
    "report",
    "reproduce_command",
    "resume_suite",
    "ros2_bridge",
    "run_planned_suite",
    "run_repeat",
    "run_scenario",
    "scene_config",
    "search",
    "start_streams",
    "suite",
    "validate",
    "versions",
    "write_diff",
    "write_suite_diff",
    "write_summary_md",
]

# Every name is imported on first use (harness._lazy): a command imports only what it calls, so
# that commands that read a run back (diff, report, recover, export) do not import the scene
# builders, graphs and MuJoCo, and `srr run` and `srr suite` start their runs without the bag
# readers, pandas and the report.
_WHERE = {
    **dict.fromkeys(("PROJECT_MARKERS", "baseline_name", "baselines_dir", "bless",
                     "scene_config"), "harness.run.baselines"),
    **dict.fromkeys(("combined_digest", "default_run_dir", "reproduce_command", "versions"),
                    "harness.run.facts"),
    "load": "harness.run.loading",
    **dict.fromkeys(("Progress", "RunResult", "Started", "import_after_the_loop"),
                    "harness.run.record"),
    **dict.fromkeys(("ROS2_BRIDGE", "Notice", "RepeatResult", "check_video", "ros2_bridge",
                     "run_repeat", "run_scenario", "start_streams", "validate"),
                    "harness.run.simulate"),
    **dict.fromkeys(("SuitePlan", "SuiteResult", "plan_suite"), "harness.suite.runner"),
    "RecoverResult": "harness.run.recover",
    "Resumed": "harness.suite.resume",
    "RerunExport": "harness.export.rerun",
    "recover": "harness.run.recover",
    "replay": "harness.run.replay",
    "report": "harness.run.rerender",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())


def build_graphs(scenario: Scenario, source: str = "<scenario>") -> Simulation:
    from harness.engine import Simulation

    return Simulation(scenario, source=source)


def graph_text(scenario: Scenario, fmt: str = "mermaid", source: str = "<scenario>") -> str:
    """The scenario's action graphs as Mermaid or JSON (``srr graph``)."""
    from harness.graph import stage_to_json, stage_to_mermaid

    sim = build_graphs(scenario, source)
    return stage_to_mermaid(sim.stage) if fmt == "mermaid" else stage_to_json(sim.stage)


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
    # imported here: only `srr diff` reads two runs back (pandas, the bag readers)
    from harness.diff import diff_runs as _diff_runs

    return _diff_runs(a, b, tolerances=tolerances)


def diff_suites(a: str | Path, b: str | Path, *,
                tolerances: Sequence[Tolerance | str] = ()) -> SuiteDiff:
    """Compare two suite output folders (``srr diff SUITE_A SUITE_B``): runs matched by their
    id in the suite, runs only in one, verdict changes, and for each pair a run diff
    (:func:`diff_runs`) that reads only the topics whose digests differ. Raises
    :class:`SrrError` for bad input (exit 2)."""
    from harness.suite.diff import diff_suites as _diff_suites

    return _diff_suites(a, b, tolerances=tolerances)


def write_suite_diff(result: SuiteDiff, path: str | Path, *, video: bool = True) -> Path:
    """Write the page of a suite comparison (``srr diff SUITE_A SUITE_B --html FILE``), and
    the run diff's page of every pair that differs into ``FILE.pairs/``."""
    from harness.suite.diff_page import write_suite_diff as _write

    return _write(result, path, video=video)


def suite(paths: Sequence[str | Path], *, executor: str = "local", jobs: int | None = None,
          address: str | None = None, repeat: int | None = None, out: Path | None = None,
          timeout_s: float | None = None, history: Path | None = None,
          baselines: Path | None = None, gpu_share: float = 0.5,
          bless_reason: str | None = None, listen: Listener | None = None,
          fork: bool = False, allow_failing: bool = False, resume: bool = False) -> SuiteResult:
    """``srr suite``: check every scenario, sweep point and suite file in ``paths`` (bad input
    raises :class:`SrrError` before anything runs), run them on ``executor`` (``local``: ``jobs``
    worker processes, default one per CPU; ``ray``: tasks on the cluster at ``address``, else on
    a local cluster started for the suite) and write ``out``'s ``summary.json``, ``junit.xml``
    and ``index.html``. Returns a :class:`harness.suite.runner.SuiteResult`; ``listen`` gets
    :class:`harness.suite.events.Event` s as runs start and finish. ``fork``: local workers
    are forked from this process when it is safe (:func:`harness.suite.local.fork_safe`; what
    ``srr suite`` does), saving each run the interpreter's start-up and imports.
    ``bless_reason`` (``--update-baselines``) blesses each valid group's first run, but not one
    that fails an absolute criterion unless ``allow_failing``. ``resume`` (``--resume``, needs
    ``out``): run only what an earlier pass of the suite in ``out`` left undone
    (:func:`resume_suite`)."""
    from harness.suite.runner import plan_suite

    if resume and out is None:
        raise SrrError("--resume: name the folder of the suite to resume with --out")
    plan = plan_suite(paths, repeat=repeat, timeout_s=timeout_s)
    resumed = resume_suite(plan, out) if resume and out is not None else None
    return run_planned_suite(plan, executor=executor, jobs=jobs, address=address, out=out,
                             history=history, baselines=baselines, gpu_share=gpu_share,
                             bless_reason=bless_reason, listen=listen, fork=fork,
                             allow_failing=allow_failing, resume=resumed)


def resume_suite(plan: SuitePlan, out: Path) -> Resumed:
    """What resuming ``plan`` in ``out`` keeps and runs again: the runs of an earlier pass
    there that ended, and the rest (never started, interrupted, timed out, crashed, or stale:
    another srr, scenario or baseline), each with why; a missing or empty ``out`` runs
    everything. Bad input (a folder of another suite or of something else, a run still being
    written) raises :class:`SrrError` before anything is touched."""
    from harness.suite.runner import resume_suite as _resume

    return _resume(plan, out)


def run_planned_suite(plan: SuitePlan, *, executor: str = "local", jobs: int | None = None,
                      address: str | None = None, out: Path | None = None,
                      history: Path | None = None, baselines: Path | None = None,
                      gpu_share: float = 0.5, bless_reason: str | None = None,
                      listen: Listener | None = None, fork: bool = False,
                      allow_failing: bool = False, resume: Resumed | None = None) -> SuiteResult:
    """:func:`suite` for a plan already checked (:func:`harness.suite.runner.plan_suite`);
    ``resume``: :func:`resume_suite`'s answer for ``out``."""
    from harness.suite.runner import run_suite

    ex = _executor(executor, jobs, address, baselines, gpu_share, fork)
    return run_suite(plan, ex, out=out, history=history, listen=listen,
                     bless_reason=bless_reason, baselines=baselines,
                     allow_failing=allow_failing, resume=resume)


def search(scenario_file: str | Path, *, space: Sequence[str], objective: str,
           violated_below: float | None = None, violated_above: float | None = None,
           overrides: Sequence[str] = (), sampler: str = "tpe", seed: int = 0,
           budget: int = 20, stop_at_first: bool = False, executor: str = "local",
           jobs: int | None = None, address: str | None = None, out: Path | None = None,
           timeout_s: float | None = None, name: str | None = None,
           counterexamples: int = 3, prune: bool = False, add_to_suite: Path | None = None,
           bless_reason: str | None = None, baselines: Path | None = None,
           listen: Listener | None = None, on_trial: Any = None,
           fork: bool = False) -> SearchResult:
    """``srr search``: look for parameters in ``space`` (``PATH=RANGE`` strings) at which
    the metric ``objective`` crosses its threshold; runs go to ``executor`` as in
    :func:`suite`; the study is kept in ``out/study.db`` and resumed when the same call is
    made again. ``prune``: delete the recording (``bag/``) of every trial that does not
    violate the objective (its summary and report stay). Returns a
    :class:`harness.search.runner.SearchResult` (with ``addition``, a
    :class:`harness.search.runner.SuiteAddition`, when ``add_to_suite``). Bad input
    raises :class:`SrrError` before anything runs."""
    from harness.search.counterexamples import check_suite
    from harness.search.objective import parse_objective
    from harness.search.runner import SearchConfig, plan_search, run_search
    from harness.search.runner import add_to_suite as _add
    from harness.search.space import parse_space
    from harness.search.study import SAMPLERS

    if sampler not in SAMPLERS:
        raise SrrError(f"--sampler {sampler}: expected one of {', '.join(SAMPLERS)}")
    if bless_reason is not None and add_to_suite is None:
        raise SrrError("--bless: only with --add-to-suite SUITE")
    if add_to_suite is not None:
        check_suite(Path(add_to_suite))
    cfg = SearchConfig(
        scenario_file=str(scenario_file), space=parse_space(space),
        objective=parse_objective(objective, below=violated_below, above=violated_above),
        overrides=tuple(overrides), sampler=sampler, seed=seed, budget=budget,
        stop_at_first=stop_at_first, timeout_s=timeout_s, name=name,
        counterexamples=counterexamples, prune=prune)
    plan = plan_search(cfg)
    ex = _executor(executor, jobs, address, baselines, 0.5, fork)
    result = run_search(plan, ex, out=out, listen=listen, on_trial=on_trial)
    addition = None
    if add_to_suite is not None and result.exit_code == 1:
        addition = _add(result, plan, ex, Path(add_to_suite), bless_reason=bless_reason,
                        baselines=baselines)
    import dataclasses

    return dataclasses.replace(result, addition=addition)


def _executor(executor: str, jobs: int | None, address: str | None, baselines: Path | None,
              gpu_share: float, fork: bool) -> Any:
    import os

    from harness.suite.local import LocalExecutor
    from harness.suite.ray_executor import RayExecutor

    if jobs is not None and jobs < 1:
        raise SrrError(f"--jobs: must be >= 1, got {jobs}")
    if executor not in ("local", "ray"):
        raise SrrError(f"--executor: expected local or ray, got {executor!r}")
    if address is not None and executor != "ray":
        raise SrrError("--address: only with --executor ray")
    return (LocalExecutor(jobs or os.cpu_count() or 1, baselines=baselines, fork=fork)
            if executor == "local" else
            RayExecutor(address=address, jobs=jobs, baselines=baselines, gpu_share=gpu_share))


def export_rerun(run_dir: str | Path, out: str | Path) -> RerunExport:
    """Write a finished run (its bag and ``summary.json``) as a Rerun recording ``out``
    (``srr export RUN_DIR --rerun FILE.rrd``; needs the rerun extra) on the ``sim_time``
    timeline; returns what was written (:class:`RerunExport`). Bad input, a live run or a
    missing rerun-sdk raise :class:`SrrError` (exit 2)."""
    from harness.export.rerun import export_rerun as _export

    return _export(run_dir, out)


def write_diff(result: DiffResult, path: str | Path, *, video: bool = True) -> Path:
    """Write the one-page HTML view of ``result`` (``srr diff --html FILE``): both runs'
    trajectories on one map, their time series overlaid, metric deltas, the topic table,
    camera keyframes side by side at the first divergence and the worst moments, and (unless
    ``video`` is False) both runs' camera videos side by side on one time cursor."""
    from harness.diff.html import write_diff as _write

    return _write(result, path, video=video)


def write_summary_md(result: SuiteResult | RunResult, path: str | Path, *,
                     link_base: str | None = None) -> Path:
    """Write the pull-request summary of a suite's or a run's result (``--summary-md FILE``):
    GitHub-flavoured Markdown from the same result that gives the exit code, capped at
    GitHub's comment size. Report links are the suite folder's (the run directory's)
    relative paths under ``link_base``, by default that folder relative to ``path``."""
    from harness.suite.runner import SuiteResult

    if isinstance(result, SuiteResult):
        from harness.suite.markdown import write_markdown as write_suite

        return write_suite(result, Path(path), link_base=link_base)
    from harness.run.markdown import write_markdown as write_run

    return write_run(result.run_summary, result.run_dir, Path(path), link_base=link_base)


#: The files ``srr schema`` describes.
SCHEMA_KINDS = ("scenario", "suite")


def json_schema(kind: str = "scenario") -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a scenario file (and the fragments it includes) or
    of a suite file, generated from the dataclasses the loaders validate them into."""
    from harness.scenario.jsonschema import scenario_schema
    from harness.schemagen import json_schema as schema_of
    from harness.suite.spec import SuiteFile

    if kind == "scenario":
        return scenario_schema()
    if kind == "suite":
        doc = schema_of(SuiteFile, title="srr suite file")
        doc["description"] = "An srr suite file (`srr suite FILE`)."
        return doc
    raise SrrError(f"srr schema: no schema for {kind!r} (expected one of "
                   f"{', '.join(SCHEMA_KINDS)})")
