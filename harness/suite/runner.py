"""A whole suite: check everything, run it on an executor, judge the groups, write the
outputs (``summary.json``, ``junit.xml``, ``index.html``)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from harness import runlock
from harness.errors import SrrError
from harness.outdir import check_out_folder
from harness.regression import baseline_path
from harness.regression.config import config_differences
from harness.run.baselines import NotBlessedError, baseline_name, baselines_dir, bless_if_changed
from harness.run.loading import ScenarioLoads
from harness.run.simulate import check_point, validate
from harness.scenario import scenario_to_mapping
from harness.suite.events import Executor, Listener
from harness.suite.outputs import FORMAT, write_outputs
from harness.suite.plan import RunSpec, plan_runs
from harness.suite.results import GROUP_ORDER, GroupResult, group_runs, suite_exit_code
from harness.suite.resume import Resumed, clear_for_rerun, resume_runs
from harness.suite.spec import Entry, SuiteSpec, load_suite
from harness.suite.sweep import expand
from harness.suite.timeline import run_timings, suite_timeline

__all__ = ["SuitePlan", "SuiteResult", "default_suite_dir", "plan_suite", "resume_suite",
           "run_suite"]


@dataclass(frozen=True)
class SuitePlan:
    spec: SuiteSpec
    runs: tuple[RunSpec, ...]
    warnings: tuple[str, ...]
    checked_s: float = 0.0  # wall seconds spent planning and checking
    #: the scenarios planning loaded, for what the suite looks up in them later (baselines)
    loads: ScenarioLoads = field(default_factory=ScenarioLoads, compare=False, repr=False)


@dataclass(frozen=True)
class SuiteResult:
    out_dir: Path
    verdict: str
    exit_code: int
    summary: dict[str, Any]
    groups: tuple[GroupResult, ...]
    blessed: tuple[Path, ...] = ()
    unchanged: tuple[Path, ...] = ()  # baselines --update-baselines found up to date
    not_blessed: tuple[str, ...] = ()  # --update-baselines: why a group's run was not blessed


def default_suite_dir(root: Path = Path("reports")) -> Path:
    """``reports/suite/<local start time>`` (a name only; nothing recorded depends on it)."""
    base = root / "suite" / time.strftime("%Y%m%d-%H%M%S")
    candidate, n = base, 1
    while candidate.exists():
        n += 1
        candidate = base.with_name(f"{base.name}-{n}")
    return candidate


def plan_suite(paths: Sequence[str | Path], *, repeat: int | None = None,
               timeout_s: float | None = None,
               on_render: Callable[[], None] | None = None) -> SuitePlan:
    """Everything ``srr validate`` checks, for every entry (its first sweep point: the world,
    graphs, systems under test and wiring are built once), and every point's scenario loaded,
    before anything runs. ``on_render``: called once, as soon as a run that renders is
    planned (:func:`~harness.suite.plan.plan_runs`)."""
    t0 = time.monotonic()
    loads = ScenarioLoads()  # each (file, overrides) loaded once, from here to the baselines
    spec = load_suite(paths, repeat=repeat, timeout_s=timeout_s, loads=loads)
    # every point loads: a bad sweep path names where it was declared
    runs = plan_runs(spec, on_render=on_render, loads=loads)
    warnings: list[str] = []
    for entry in spec.entries:
        first, *others = expand(entry.sweep)
        try:
            sc = loads(entry.scenario_file, entry.overrides + first.overrides())
            said = validate(sc, entry.scenario_file)
        except SrrError as err:
            raise _of_entry(err, entry, first.label if entry.sweep else None) from None
        warnings += [_said_of_entry(w, entry, first.label if entry.sweep else None)
                     for w in said]
        for point in others:  # what the points differ in (check_point); a warning the first
            # point did not give is said with the point's label
            try:
                sc = loads(entry.scenario_file, entry.overrides + point.overrides())
                more = check_point(sc, entry.scenario_file, scene=any(
                    path.split(".", 1)[0] in _SCENE_KEYS for path, _ in point.params))
            except SrrError as err:
                raise _of_entry(err, entry, point.label) from None
            warnings += [_said_of_entry(w, entry, point.label) for w in more if w not in said]
    warnings += _shared_baseline_warnings(spec, runs, loads)
    return SuitePlan(spec, runs, tuple(warnings), time.monotonic() - t0, loads)


#: Top-level scenario keys whose sweep changes the scene each point builds (robots' models
#: and spawn poses, fixed cameras, the world): those points' worlds are built before the first run.
_SCENE_KEYS = ("robots", "world", "cameras")


def _said_of_entry(warning: str, entry: Entry, label: str | None) -> str:
    """A warning about an entry's scenario (at sweep point ``label``), said of the entry: one
    about a value its ``set:`` or sweep gave names the suite file's entry, as
    :func:`_of_entry` names an error; the others say the entry's name first."""
    at = f" [{label}]" if label else ""
    if warning.startswith("--set: "):
        return f"{entry.declared_in}{at}: {warning.removeprefix('--set: ')}"
    return f"{entry.name}{at}: {warning}"


def _of_entry(err: SrrError, entry: Entry, label: str | None) -> SrrError:
    """``err`` about an entry's scenario (at sweep point ``label``), said of the entry: a
    value its ``set:`` or sweep gave, which the loader names as ``--set``'s, is the suite
    file's entry's (``suite.yaml: scenarios[0] [x=1]: robots[0].spawn.position: ...``)."""
    text = str(err)
    given = text.startswith("--set: ")
    if not given and label is None:
        return err  # the scenario file's own problem, named by it
    at = entry.declared_in + (f" [{label}]" if label else "")
    return SrrError(f"{at}: {text.removeprefix('--set: ')}")


def _sweeps(groups: Sequence[GroupResult]) -> list[dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for g in groups:
        s = g.runs[0].spec
        if s.sweep:
            sw = out.setdefault(s.entry, {"name": s.entry, "scenario": s.scenario,
                                          "params": [p for p, _ in s.params], "groups": []})
            sw["groups"].append(g.id)
    return list(out.values())


@dataclass(frozen=True)
class _SharedBaseline:
    """Two groups whose first repeats are judged against (and blessed into) one baseline
    file under different configurations (two entries of one scenario with other ``set:``
    values): one of them is MISMATCH on every run."""

    where: str  # the later group's entry (and sweep point)
    group: str
    other: str  # the earlier group, and its entry
    other_where: str
    path: Path
    changed: tuple[str, ...]  # how the configurations differ (up to three)


def _shared_baselines(suite: SuiteSpec, runs: Sequence[RunSpec], baselines: Path | None,
                      loads: ScenarioLoads) -> list[_SharedBaseline]:
    """Every group of ``runs`` that shares its baseline file with an earlier group under
    another configuration."""
    declared = {e.name: e.declared_in for e in suite.entries}
    seen: dict[Path, tuple[RunSpec, dict[str, Any]]] = {}
    out = []
    for spec in runs:
        if spec.repeat != 1:
            continue
        sc = loads(spec.scenario_file, spec.overrides)
        path = baseline_path(baseline_name(sc), baselines_dir(spec.scenario_file, baselines,
                                                              sc))
        mapping = scenario_to_mapping(sc)
        if path not in seen:
            seen[path] = (spec, mapping)
            continue
        other, theirs = seen[path]
        changed = config_differences(theirs, mapping, limit=3)
        if changed:
            where = declared[spec.entry] + (f" [{spec.group.split('[', 1)[1]}"
                                            if spec.sweep else "")
            out.append(_SharedBaseline(where, spec.group, other.group,
                                       declared[other.entry], path, tuple(changed)))
    return out


def _refuse_shared_baselines(plan: SuitePlan, baselines: Path | None) -> None:
    """``--update-baselines``: refuse (before anything runs) two groups that would be blessed
    into one baseline file under different configurations: the second would overwrite the
    first, and the first be MISMATCH against it from then on."""
    for s in _shared_baselines(plan.spec, plan.runs, baselines, plan.loads)[:1]:
        raise SrrError(
            f"{s.where}: --update-baselines would bless {s.group} into {s.path}, the "
            f"baseline it shares with {s.other} ({s.other_where}) under another "
            f"configuration ({'; '.join(s.changed)}): one would overwrite the other, which "
            "would then be MISMATCH; give one entry its own baseline "
            "(set: {baseline: NAME})")


def _shared_baseline_warnings(suite: SuiteSpec, runs: Sequence[RunSpec],
                              loads: ScenarioLoads) -> list[str]:
    """A warning for each group judged against a baseline file (in its scenario's own
    baselines folder) that it shares with another group under another configuration: one of
    the two is MISMATCH on every run."""
    return [f"{s.where}: {s.group} is judged against {s.path}, the baseline it shares with "
            f"{s.other} ({s.other_where}) under another configuration "
            f"({'; '.join(s.changed)}): one of the two is MISMATCH on every run; give one "
            "entry its own baseline (set: {baseline: NAME})"
            for s in _shared_baselines(suite, runs, None, loads)]


def resume_suite(plan: SuitePlan, out: Path) -> Resumed:
    """What resuming ``plan`` in ``out`` keeps and runs (:mod:`harness.suite.resume`); bad
    input (a folder of another suite, of something else; a run still being written) raises
    :class:`SrrError` before anything is touched."""
    check_out_folder(Path(out))
    runlock.refuse_if_live(Path(out))  # the suite that writes it is still running
    return resume_runs(plan.runs, Path(out), name=plan.spec.name, loads=plan.loads)


def run_suite(plan: SuitePlan, executor: Executor, *, out: Path | None = None,
              history: Path | None = None, listen: Listener | None = None,
              bless_reason: str | None = None, baselines: Path | None = None,
              allow_failing: bool = False, resume: Resumed | None = None) -> SuiteResult:
    """Run ``plan`` on ``executor`` into ``out`` (default :func:`default_suite_dir`).

    ``resume`` (:func:`resume_suite`, for ``out``): run only its ``again`` runs, each in a
    folder cleared first, and judge them with the runs it keeps, as one suite.

    ``history``: a folder of earlier suite outputs whose metrics the page shows as trends.
    ``bless_reason``: make the first repeat of every group that is neither INVALID, FLAKY nor
    interrupted its baseline (``--update-baselines``), e.g. to bless each sweep point; a
    baseline that would change only in who blessed it when and why is left as it is
    (:attr:`SuiteResult.unchanged`), so a re-bless rewrites only what changed. A run that
    fails an absolute criterion is not blessed (unless ``allow_failing``): the rule of
    ``srr baseline bless`` (:func:`~harness.run.baselines.blessing_refusal`); why is kept in
    :attr:`SuiteResult.not_blessed` and in ``baselines_blessed.not_blessed``."""

    if history is not None and not Path(history).is_dir():
        raise SrrError(f"--history {history}: no such folder")
    if bless_reason is not None:
        _refuse_shared_baselines(plan, baselines)
    out_dir = Path(out) if out is not None else default_suite_dir()
    check_out_folder(out_dir)
    if resume is None and out_dir.exists() and any(out_dir.iterdir()):
        raise SrrError(f"--out {out_dir}: folder exists and is not empty (--resume runs "
                       "what an earlier pass of the suite there left undone)")
    out_dir.mkdir(parents=True, exist_ok=True)
    # held until the outputs are written: `srr suite --resume` refuses a live suite's folder
    with runlock.owning(out_dir, "written", fresh=True):
        return _run_into(plan, executor, out_dir, history=history, listen=listen,
                         bless_reason=bless_reason, baselines=baselines,
                         allow_failing=allow_failing, resume=resume)


def _run_into(plan: SuitePlan, executor: Executor, out_dir: Path, *, history: Path | None,
              listen: Listener | None, bless_reason: str | None, baselines: Path | None,
              allow_failing: bool, resume: Resumed | None) -> SuiteResult:
    """:func:`run_suite` once its output folder is made and owned."""
    from harness.suite.history import load_history

    todo, kept = (plan.runs, ()) if resume is None else (resume.again, resume.kept)
    if resume is not None:
        clear_for_rerun(todo, out_dir)
    started = datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")
    t0 = time.monotonic()
    # the costliest runs start first (longest processing time first), so the last worker
    # is not left alone with a long run; results are kept in plan order
    order = sorted(todo, key=lambda s: -s.cost)
    done, interrupted = executor.run(order, out_dir, listen or (lambda e: None))
    by_id = {o.spec.id: o for o in (*kept, *done)}
    outcomes = [by_id[s.id] for s in plan.runs]
    wall = time.monotonic() - t0
    timings = [run_timings(o.clock, t0) for o in outcomes]
    t_judge = time.monotonic()
    groups = group_runs(outcomes, out_dir)
    ranked = sorted(groups, key=lambda g: GROUP_ORDER.index(g.verdict))
    code = suite_exit_code(groups, interrupted)
    verdict = "INTERRUPTED" if interrupted else (ranked[0].verdict if ranked else "INVALID")
    counts = {v: n for v in GROUP_ORDER if (n := sum(g.verdict == v for g in groups))}
    summary: dict[str, Any] = {
        "format": FORMAT, "name": plan.spec.name, "started_at": started,
        "wall_s": round(wall, 3), "executor": executor.name, "jobs": executor.jobs,
        "address": getattr(executor, "address", None), "verdict": verdict, "exit_code": code,
        "interrupted": interrupted, "counts": counts, "warnings": list(plan.warnings),
        "groups": [g.to_json() for g in ranked],
        "runs": [{**o.to_json(), "timings": t} for o, t in zip(outcomes, timings, strict=True)],
        "sweeps": _sweeps(groups), "history": None,
        **({} if resume is None else {"resumed": {
            "kept": [o.spec.id for o in resume.kept], "ran": [s.id for s in resume.again],
            "notes": list(resume.notes)}}),
        "timeline": suite_timeline(timings, jobs=executor.jobs, checked_s=plan.checked_s,
                                   wall_s=wall),
    }
    if history is not None:
        summary["history"] = load_history([Path(history)], summary)
    summary["timeline"]["judged_s"] = round(time.monotonic() - t_judge, 3)
    blessed: list[Path] = []
    unchanged: list[Path] = []
    refused: list[str] = []
    if bless_reason is not None and not interrupted:
        for g in groups:
            if g.verdict not in ("INVALID", "FLAKY", "INTERRUPTED") and g.runs[0].run_dir:
                # the folder as this process finds it: a run on a Ray cluster judged against
                # the copy of the project shipped to its node, whose path it recorded
                spec = g.runs[0].spec
                here = baselines if baselines is not None else baselines_dir(
                    spec.scenario_file, None, plan.loads(spec.scenario_file, spec.overrides))
                try:
                    path, written = bless_if_changed(out_dir / g.runs[0].run_dir,
                                                     bless_reason, baselines=here,
                                                     allow_failing=allow_failing)
                except NotBlessedError as err:
                    refused.append(str(err))
                    continue
                (blessed if written else unchanged).append(path)
        # what the groups' reasons ("no baseline at ...") said before: the baselines now
        summary["baselines_blessed"] = {"reason": bless_reason,
                                        "written": [str(p) for p in blessed],
                                        "unchanged": [str(p) for p in unchanged]}
        if refused:  # written only when there is something to say
            summary["baselines_blessed"]["not_blessed"] = refused
    summary = write_outputs(out_dir, summary, ranked)
    return SuiteResult(out_dir, verdict, code, summary, tuple(ranked), tuple(blessed),
                       tuple(unchanged), tuple(refused))

