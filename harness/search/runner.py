"""A whole search: check the input, open (or resume) the study, run batches of trials on an
executor until the budget is spent (or, with ``stop_at_first``, a violation is found), and
write the outputs into ``OUT`` (default ``reports/search/<name>``)::

    study.db            the optuna study (SQLite): what a resumed search continues
    runs/t00007/        each trial's run directory (report.html, summary.json, bag/)
    logs/t00007.log     each trial's worker output
    counterexamples/    the worst violating trials as scenario files, parameters baked in
    search.json         every trial, the best so far, importances, counterexamples
    junit.xml           one case for the objective, one per counterexample
    index.html          the search page

Exit code: 1 when some trial violated the objective, 0 when none did and at least one trial
was valid, 3 when no trial was (all crashed or INVALID), 130 when interrupted.
"""

from __future__ import annotations

import contextlib
import math
import shutil
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from harness.atomic import write_json_atomic
from harness.errors import ScenarioError, SrrError
from harness.interrupt import INTERRUPTED_EXIT
from harness.outdir import check_out_folder
from harness.report.junit import Case, write_junit
from harness.report.search_page import write_search_page
from harness.run.baselines import baselines_dir
from harness.run.facts import scenario_text
from harness.run.simulate import scenario_warnings, validate
from harness.scenario import Scenario, load_scenario, parse_override
from harness.search.objective import Objective, check_scored, missing_metric
from harness.search.space import Dimension
from harness.search.study import ATTR, ask_batch, finished_trials, importances, open_study, status
from harness.suite.events import Executor, Listener
from harness.suite.plan import RunSpec, safe_file_name
from harness.suite.results import RunOutcome
from harness.suite.sweep import Point, Scalar, varied_path

__all__ = ["FORMAT", "SearchConfig", "SearchResult", "TrialRecord", "default_search_dir",
           "plan_search", "run_search"]

FORMAT = "srr-search/1"


@dataclass(frozen=True)
class SearchConfig:
    scenario_file: str
    space: tuple[Dimension, ...]
    objective: Objective
    overrides: tuple[str, ...] = ()
    sampler: str = "tpe"
    seed: int = 0
    budget: int = 20
    stop_at_first: bool = False
    timeout_s: float | None = None
    name: str | None = None
    counterexamples: int = 3
    prune: bool = False  # delete the bag/ of every trial that does not violate the objective


@dataclass(frozen=True)
class SearchPlan:
    """A checked search: its config, the nominal scenario, its warnings."""

    config: SearchConfig
    scenario: Scenario
    name: str
    warnings: tuple[str, ...]
    renders: bool
    cost: float


@dataclass(frozen=True)
class TrialRecord:
    """One trial as the search saw it. ``status``: ``violated``, ``holds``, ``invalid`` (the
    run crashed, timed out or is INVALID), ``no-value`` (the run has the metric, without a
    value) or ``killed`` (the search was stopped while it ran)."""

    number: int
    params: dict[str, Scalar]
    status: str
    value: float | None = None
    margin: float | None = None
    verdict: str | None = None
    run_dir: str | None = None
    report: str | None = None
    log: str | None = None
    reason: str | None = None

    @property
    def id(self) -> str:
        return f"t{self.number:05d}"

    def to_json(self) -> dict[str, Any]:
        return {"number": self.number, "id": self.id, "params": self.params,
                "status": self.status, "value": self.value, "margin": self.margin,
                "verdict": self.verdict, "run_dir": self.run_dir, "report": self.report,
                "log": self.log, "reason": self.reason}


@dataclass(frozen=True)
class SearchResult:
    out_dir: Path
    exit_code: int
    verdict: str
    trials: tuple[TrialRecord, ...]
    counterexamples: tuple[Path, ...]
    summary: dict[str, Any]
    ran: int = 0  # trials run by this call (the rest were resumed from the study)
    warnings: tuple[str, ...] = field(default=())
    addition: SuiteAddition | None = None  # what --add-to-suite did


def default_search_dir(name: str, root: Path = Path("reports")) -> Path:
    """``reports/search/<name>``: a fixed place, so re-running the command resumes."""
    return root / "search" / safe_file_name(name)


def _load(cfg: SearchConfig, extra: Sequence[str], where: str) -> Scenario:
    pairs = [parse_override(o) for o in (*cfg.overrides, *extra)]
    try:
        return load_scenario(cfg.scenario_file, pairs)
    except ScenarioError as err:
        if err.file != "--set" and not extra:
            raise
        what = f"{err.field}: {err.message}" if err.file == "--set" else str(err)
        raise SrrError(f"{where}: {what}") from None


def _corners(dim: Dimension) -> list[Scalar]:
    if dim.kind == "categorical":
        return list(dim.choices)
    if dim.kind == "int":
        return [int(dim.low), int(dim.high)]
    return [dim.low, dim.high]


def _search_warnings(nominal: Sequence[str], own: Sequence[str],
                     at_corners: Sequence[tuple[str, Sequence[str]]]) -> tuple[str, ...]:
    """The warnings of a search: the nominal scenario's (``validate``), less those read off
    the scenario alone (``own``) that some end of a searched range does not give (they are
    about a value the search replaces: a ``start_delay`` it varies), plus those an end of a
    range gives that the nominal scenario does not, said with that end."""
    ends = [said for _, said in at_corners]
    kept = [w for w in nominal if w not in own or all(w in said for said in ends)]
    more = [f"{where}: {w.removeprefix('--set: ')}" for where, said in at_corners
            for w in said if w not in nominal]
    return tuple(dict.fromkeys([*kept, *more]))


def plan_search(cfg: SearchConfig) -> SearchPlan:
    """Everything checked before a run: the scenario (with ``--set``), every dimension at
    its ends (or each choice), the objective's scoring block, budget and counts."""
    if cfg.budget < 1:
        raise SrrError(f"--budget: must be >= 1, got {cfg.budget}")
    if cfg.counterexamples < 0:
        raise SrrError(f"--counterexamples: must be >= 0, got {cfg.counterexamples}")
    if cfg.timeout_s is not None and not cfg.timeout_s > 0:
        raise SrrError(f"--timeout: must be > 0, got {cfg.timeout_s}")
    if not Path(cfg.scenario_file).is_file():
        raise SrrError(f"{cfg.scenario_file}: no such scenario file")
    for text in cfg.overrides:
        try:
            path, _ = parse_override(text)
        except ScenarioError as err:
            raise SrrError(f"--set {text}: {err.message}") from None
        hit = varied_path(path, (d.path for d in cfg.space))
        if hit is not None:
            raise SrrError(f"--set {text}: {hit} is searched (--space {hit}): each trial's "
                           "value would replace this one; leave one of the two out")
    sc = _load(cfg, (), "--set")
    at_corners: list[tuple[str, tuple[str, ...]]] = []
    for dim in cfg.space:
        for v in _corners(dim):
            corner = _load(cfg, Point(((dim.path, v),)).overrides(), f"--space {dim.path}")
            if dim.path.startswith("systems_under_test"):  # plug-in parameters: in set-up
                try:
                    validate(corner, cfg.scenario_file)
                except SrrError as err:  # the value is the flag's: said of --space
                    raise SrrError(f"--space {dim.path}={v}: "
                                   f"{str(err).removeprefix('--set: ')}") from None
            at_corners.append((f"--space {dim.path}={v}",
                               scenario_warnings(corner, cfg.scenario_file)))
    check_scored(cfg.objective, sc.scoring, cfg.scenario_file)
    warnings = _search_warnings(validate(sc, cfg.scenario_file),
                                scenario_warnings(sc, cfg.scenario_file), at_corners)
    cameras = sc.camera_count
    name = cfg.name or sc.name
    if not name or safe_file_name(name) != name:
        raise SrrError(f"--name {name!r}: expected letters, digits, '_', '-' and '.'")
    return SearchPlan(cfg, sc, name, warnings, cameras > 0, sc.duration * (1 + cameras))


def _config_key(plan: SearchPlan) -> dict[str, Any]:
    c = plan.config
    return {"scenario_file": str(Path(c.scenario_file).resolve()), "set": list(c.overrides),
            "space": [d.to_json() for d in c.space], "objective": c.objective.to_json(),
            "sampler": c.sampler, "seed": c.seed}


def _plain(v: Any) -> Scalar:
    item = getattr(v, "item", None)
    out = item() if callable(item) else v
    assert isinstance(out, bool | int | float | str)
    return out


def _spec(plan: SearchPlan, number: int, params: dict[str, Scalar]) -> RunSpec:
    point = Point(tuple((d.path, params[d.path]) for d in plan.config.space))
    rid = f"t{number:05d}"
    return RunSpec(id=rid, group=rid, entry=plan.name, scenario=plan.scenario.name,
                   scenario_file=plan.config.scenario_file,
                   overrides=plan.config.overrides + point.overrides(), params=point.params,
                   sweep=True, repeat=1, repeats=1, timeout_s=plan.config.timeout_s,
                   run_dir=f"runs/{rid}", renders=plan.renders, cost=plan.cost)


def _record(plan: SearchPlan, number: int, params: dict[str, Scalar],
            o: RunOutcome) -> TrialRecord:
    base = TrialRecord(number, params, "invalid", verdict=o.verdict, run_dir=o.run_dir,
                       report=o.report, log=o.log)
    if o.verdict in ("INVALID", "INTERRUPTED") or not o.metrics:
        why = "; ".join(o.reasons) or f"the run is {o.verdict}"
        return replace(base, status="killed" if o.verdict == "INTERRUPTED" else "invalid",
                       reason=why)
    metrics = {str(m["name"]): m.get("value") for m in o.metrics}
    problem = missing_metric(plan.config.objective, metrics)
    if problem is not None:
        return replace(base, reason=problem)
    value = metrics[plan.config.objective.metric]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(
            value):
        return replace(base, status="no-value",
                       reason=f"{plan.config.objective.metric} has no value in this run")
    obj = plan.config.objective
    return replace(base, status="violated" if obj.violated(value) else "holds",
                   value=float(value), margin=obj.margin(float(value)))


def _from_trial(t: Any) -> TrialRecord:
    a = t.user_attrs.get(ATTR) or {}
    params = {k: _plain(v) for k, v in t.params.items()}
    return TrialRecord(t.number, params, str(a.get("status", "invalid")),
                       value=a.get("value"), margin=a.get("margin"), verdict=a.get("verdict"),
                       run_dir=a.get("run_dir"), report=a.get("report"), log=a.get("log"),
                       reason=a.get("reason"))


def _tell(study: Any, trial: Any, rec: TrialRecord) -> None:
    from optuna.trial import TrialState

    trial.set_user_attr(ATTR, {k: v for k, v in rec.to_json().items()
                               if k not in ("number", "id", "params")})
    if rec.status in ("violated", "holds"):
        study.tell(trial, rec.value)
    else:
        study.tell(trial, state=TrialState.FAIL)


@contextlib.contextmanager
def _session(executor: Executor) -> Iterator[None]:
    session = getattr(executor, "session", None)
    if session is None:
        yield
    else:
        with session():
            yield


def _best_so_far(records: Sequence[TrialRecord], obj: Objective) -> list[float | None]:
    best: float | None = None
    out: list[float | None] = []
    for r in records:
        if r.value is not None and (best is None or obj.margin(r.value) < obj.margin(best)):
            best = r.value
        out.append(best)
    return out


def _write_counterexamples(plan: SearchPlan, out_dir: Path,
                           worst: Sequence[TrialRecord]) -> list[dict[str, Any]]:
    folder = out_dir / "counterexamples"
    folder.mkdir(exist_ok=True)
    keep: set[str] = set()
    out: list[dict[str, Any]] = []
    obj = plan.config.objective
    for r in worst:
        name = f"{plan.name}_{r.id}"
        point = Point(tuple((d.path, r.params[d.path]) for d in plan.config.space))
        sc = _load(plan.config, point.overrides(), f"trial {r.id}")
        if sc.baselines is not None:  # relative to the file that set it: made absolute
            sc = replace(sc, baselines=str(baselines_dir(plan.config.scenario_file, None, sc)))
        sc = replace(sc, name=name, baseline=None, sweep={}, description=(
            f"Found by srr search {plan.name} (trial {r.id}): {obj.metric} = {r.value:g} "
            f"violates {obj.describe()}. Parameters: {point.label}. {sc.description}"
        ).strip())
        path = folder / f"{name}.yaml"
        path.write_text(scenario_text(sc), encoding="utf-8")
        keep.add(path.name)
        note = None
        try:
            load_scenario(path)
        except SrrError as err:  # relative model paths: run it from the scenario's folder
            note = f"does not load from {folder}: {err}"
        out.append({"trial": r.number, "id": r.id, "name": name,
                    "file": path.relative_to(out_dir).as_posix(), "params": r.params,
                    "value": r.value, "margin": r.margin, "report": r.report,
                    "run_dir": r.run_dir, "note": note})
    for stale in folder.glob("*.yaml"):
        if stale.name not in keep:
            stale.unlink()
    return out


def _outputs(plan: SearchPlan, out_dir: Path, study: Any, records: Sequence[TrialRecord],
             meta: dict[str, Any]) -> tuple[dict[str, Any], int, str]:
    cfg = plan.config
    obj = cfg.objective
    violated = sorted((r for r in records if r.status == "violated"),
                      key=lambda r: (r.margin if r.margin is not None else 0.0, r.number))
    valid = [r for r in records if r.status in ("violated", "holds")]
    invalid = [r for r in records if r.status == "invalid"]
    no_value = [r for r in records if r.status == "no-value"]
    if meta.get("interrupted"):
        code, verdict = INTERRUPTED_EXIT, "INTERRUPTED"
    elif violated:
        code, verdict = 1, "VIOLATED"
    elif valid:
        code, verdict = 0, "HOLDS"
    else:
        code, verdict = 3, "INVALID"
    distinct: list[TrialRecord] = []  # worst first, one per set of parameters
    for r in violated:
        if all(r.params != d.params for d in distinct):
            distinct.append(r)
    cex = _write_counterexamples(plan, out_dir, distinct[:cfg.counterexamples])
    best = min(valid, key=lambda r: (obj.margin(r.value or 0.0), r.number), default=None)
    summary: dict[str, Any] = {
        "format": FORMAT, "name": plan.name, "scenario": plan.scenario.name,
        "scenario_file": cfg.scenario_file, "set": list(cfg.overrides),
        "space": [d.to_json() for d in cfg.space], "objective": obj.to_json(),
        "sampler": cfg.sampler, "seed": cfg.seed, "budget": cfg.budget,
        "stop_at_first": cfg.stop_at_first, **meta,
        "verdict": verdict, "exit_code": code,
        "counts": {"trials": len(records), "violated": len(violated), "valid": len(valid),
                   "invalid": len(invalid), "no_value": len(no_value),
                   "killed": sum(r.status == "killed" for r in records)},
        "best": None if best is None else {"trial": best.number, "value": best.value},
        "first_violation": min((r.number for r in violated), default=None),
        "best_so_far": _best_so_far(records, obj),
        "importances": importances(study, cfg.seed),
        "trials": [r.to_json() for r in records],
        "counterexamples": cex, "warnings": list(plan.warnings),
    }
    write_json_atomic(out_dir / "search.json", summary)
    cases = [Case(f"search.{obj.metric}", not violated,
                  (f"{len(violated)} of {len(records)} trials violate {obj.describe()}; worst "
                   f"{violated[0].id}: {violated[0].value:g}") if violated else
                  ((f"interrupted with {len(valid)} of {cfg.budget} trials done: "
                    if meta.get("interrupted") else "") +
                   f"no trial of {len(records)} violates {obj.describe()} ({len(valid)} valid, "
                   f"{len(invalid)} invalid, {len(no_value)} without a value)"),
                  # an interrupted search that found nothing has not shown the objective holds
                  skipped=bool(meta.get("interrupted")) and not violated)]
    cases += [Case(f"counterexample.{c['id']}", False,
                   f"{obj.metric} = {c['value']:g} at "
                   + ", ".join(f"{k}={v}" for k, v in c["params"].items())) for c in cex]
    if not valid and not meta.get("interrupted"):
        cases.append(Case("search.valid_trials", False, "no trial produced a value"))
    write_junit(out_dir / "junit.xml", f"search.{plan.name}", cases)
    write_search_page(out_dir, summary)
    return summary, code, verdict


def run_search(plan: SearchPlan, executor: Executor, *, out: Path | None = None,
               listen: Listener | None = None,
               on_trial: Callable[[TrialRecord], None] | None = None) -> SearchResult:
    """Run (or resume) the search ``plan`` on ``executor`` into ``out``."""
    cfg = plan.config
    out_dir = Path(out) if out is not None else default_search_dir(plan.name)
    db = out_dir / "study.db"
    check_out_folder(out_dir)
    # an empty study.db is no search either: a new study there would number its trials from
    # 0 again, into the run directories left beside it
    holds_study = db.is_file() and db.stat().st_size > 0
    if out_dir.exists() and not holds_study and any(p.name != db.name
                                                    for p in out_dir.iterdir()):
        raise SrrError(f"--out {out_dir}: folder exists, is not empty and holds no search "
                       f"({db.name}{' is empty' if db.is_file() else ''}) to resume")
    made = not out_dir.exists() or not any(out_dir.iterdir())  # by this search
    out_dir.mkdir(parents=True, exist_ok=True)
    study = open_study(db, cfg.objective, _config_key(plan))
    t0 = time.monotonic()
    started = datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")
    ran = 0
    interrupted = False
    stop: str | None = None

    def records() -> list[TrialRecord]:
        return [_from_trial(t) for t in study.get_trials(deepcopy=False) if status(t)]

    with _session(executor):
        while not (interrupted or stop):
            done = finished_trials(study)
            found = any(status(t) == "violated" for t in done)
            if len(done) >= cfg.budget or (cfg.stop_at_first and found):
                break
            n = min(max(1, executor.jobs), cfg.budget - len(done))
            trials: list[Any] = []
            try:
                trials = ask_batch(study, cfg.space, cfg.sampler, cfg.seed, n)
                params = [{k: _plain(v) for k, v in t.params.items()} for t in trials]
                specs = [_spec(plan, t.number, p) for t, p in zip(trials, params, strict=True)]
                outcomes, interrupted = executor.run(specs, out_dir,
                                                     listen or (lambda e: None))
            except KeyboardInterrupt:  # between runs (asking, planning): none of them ran
                for t in trials:
                    _tell(study, t, TrialRecord(t.number, {}, "killed",
                                                reason="the search was interrupted"))
                interrupted = True
                break
            for t, p, o in zip(trials, params, outcomes, strict=True):
                rec = _record(plan, t.number, p, o)
                if interrupted and rec.status == "invalid":  # stopped by the interrupt
                    rec = replace(rec, status="killed", reason="stopped: the search was "
                                  f"interrupted ({rec.reason})")
                _tell(study, t, rec)
                if cfg.prune and rec.status != "violated" and rec.run_dir:
                    shutil.rmtree(out_dir / rec.run_dir / "bag", ignore_errors=True)
                ran += 1
                if on_trial is not None:
                    on_trial(rec)
                if stop is None and rec.reason and rec.reason.startswith("--objective"):
                    stop = rec.reason
    meta = {"started_at": started, "wall_s": round(time.monotonic() - t0, 3),
            "executor": getattr(executor, "name", "?"), "jobs": executor.jobs,
            "interrupted": interrupted, "ran_now": ran}
    if stop is not None:  # a bad --objective, seen in the first run's metrics
        if made:  # exit 2 leaves nothing, and the corrected command can use the same --out
            del study
            shutil.rmtree(out_dir, ignore_errors=True)
        raise SrrError(stop)
    recs = records()
    summary, code, verdict = _outputs(plan, out_dir, study, recs, meta)
    cex = tuple(out_dir / c["file"] for c in summary["counterexamples"])
    return SearchResult(out_dir, code, verdict, tuple(recs), cex, summary, ran,
                        plan.warnings)


@dataclass(frozen=True)
class SuiteAddition:
    suite: Path
    added: tuple[str, ...]  # entry names appended
    present: tuple[str, ...]  # already in the suite
    blessed: tuple[Path, ...]  # baselines written
    not_reproduced: tuple[str, ...]  # re-run without violating the objective (not added)


def add_to_suite(result: SearchResult, plan: SearchPlan, executor: Executor, suite: Path, *,
                 bless_reason: str | None = None,
                 baselines: Path | None = None) -> SuiteAddition:
    """Put ``result``'s counterexamples into ``suite`` (see
    :mod:`harness.search.counterexamples`). With ``bless_reason`` each is run first as a
    suite that blesses it; one whose re-run does not violate the objective again (or is not
    valid) is reported and left out."""
    from harness.search.counterexamples import append_to_suite, place_beside
    from harness.suite.runner import plan_suite, run_suite

    cex = list(result.summary["counterexamples"])
    placed = [(str(c["name"]), place_beside(plan.config.scenario_file,
                                            result.out_dir / c["file"], str(c["name"])))
              for c in cex]
    blessed: tuple[Path, ...] = ()
    bad: list[str] = []
    if bless_reason is not None and placed:
        k = 1
        while (result.out_dir / f"bless-{k}").exists():
            k += 1
        res = run_suite(plan_suite([str(p) for _, p in placed]), executor,
                        out=result.out_dir / f"bless-{k}", bless_reason=bless_reason,
                        baselines=baselines,
                        # a counterexample fails on purpose: its baseline records that
                        allow_failing=True)
        obj = plan.config.objective
        for g in res.groups:
            run = g.runs[0]
            value = {str(m["name"]): m.get("value") for m in run.metrics}.get(obj.metric)
            ok = (g.verdict not in ("INVALID", "FLAKY", "INTERRUPTED")
                  and isinstance(value, int | float) and obj.violated(float(value)))
            if not ok:
                bad.append(run.spec.entry)
        blessed = tuple(p for p in res.blessed
                        if not any(p.name.startswith(f"{b}.") for b in bad))
        placed = [(n, p) for n, p in placed if n not in bad]
    done = append_to_suite(suite, placed)
    for c in result.summary["counterexamples"]:
        if c["name"] not in bad:
            c["suite"] = str(suite)
    write_json_atomic(result.out_dir / "search.json", result.summary)
    write_search_page(result.out_dir, result.summary)
    return SuiteAddition(suite, tuple(a.name for a in done if a.added),
                         tuple(a.name for a in done if not a.added), blessed, tuple(bad))
