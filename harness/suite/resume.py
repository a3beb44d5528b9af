"""Resuming a suite in the output folder of an earlier, unfinished pass of it (``srr suite
--resume``): which runs ended there and are kept as they are, and which run (again).

A run is kept when its folder holds a finished run of the same scenario: a ``summary.json``
that is not INTERRUPTED, written by this version of srr, from the resolved scenario the plan
gives it now (``scenario.yaml``), compared with the baseline as it is now (blessed at the same
instant), and not one stopped at its timeout (its ``wall_clock_timeout`` gate failed, or the
earlier pass's ``summary.json`` says so) or lost to a crash (the earlier pass's says so).
Every other run of the plan runs: those the earlier pass never started, and those whose
folder it left unfinished or stale — that folder is removed first. Nothing is removed while a
process still writes a run of the folder.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness import __version__, yamlio
from harness.errors import SrrError
from harness.regression.config import scenario_differences
from harness.regression.store import BaselineError, load_baseline
from harness.run.loading import ScenarioLoads
from harness.runlock import refuse_if_live
from harness.scenario import scenario_to_mapping
from harness.suite.events import log_path
from harness.suite.plan import RunSpec
from harness.suite.results import RunOutcome, outcome_of
from harness.suite.unfinished import TIMEOUT_GATE
from harness.summary import SUMMARY_NAME

__all__ = ["Resumed", "clear_for_rerun", "resume_runs"]

#: What a run directory keeps its resolved scenario in (:mod:`harness.run.facts`).
_SCENARIO = "scenario.yaml"


@dataclass(frozen=True)
class Resumed:
    """The plan split for a resumed suite: ``kept`` (runs that ended, as the suite judges
    them), ``again`` (to run, in plan order) and ``notes`` (why a run that had a folder runs
    again: one line each)."""

    kept: tuple[RunOutcome, ...]
    again: tuple[RunSpec, ...]
    notes: tuple[str, ...]


def clear_for_rerun(runs: Sequence[RunSpec], out_dir: Path) -> None:
    """Remove what an earlier pass left of ``runs`` in ``out_dir`` (their run folders and
    logs), so that each runs again into an empty folder."""
    for spec in runs:
        run_dir = out_dir / spec.run_dir
        if run_dir.is_dir():
            refuse_if_live(run_dir)
            shutil.rmtree(run_dir)
        log_path(out_dir, spec).unlink(missing_ok=True)


def resume_runs(runs: tuple[RunSpec, ...], out_dir: Path, *, name: str,
                loads: ScenarioLoads) -> Resumed:
    """Split ``runs`` (a plan's, of the suite ``name``) for resuming in ``out_dir``: a missing
    or empty folder runs everything; one that holds no suite output, or another suite's, is
    refused (:class:`SrrError`), as is one where a run is still being written."""
    if not out_dir.is_dir() or not any(out_dir.iterdir()):
        return Resumed((), runs, ())
    earlier = _earlier_summary(out_dir, name)
    before = {r["id"]: r for r in earlier.get("runs", [])}
    kept: list[RunOutcome] = []
    again: list[RunSpec] = []
    notes: list[str] = []
    for spec in runs:
        refuse_if_live(out_dir / spec.run_dir)  # a live suite (or run) still writes here
        why, outcome = _judge(spec, out_dir, before.get(spec.id), loads)
        if outcome is not None:
            kept.append(outcome)
            continue
        again.append(spec)
        if why is not None:
            notes.append(f"{spec.id}: {why}; it runs again")
    return Resumed(tuple(kept), tuple(again), tuple(notes))


def _earlier_summary(out_dir: Path, name: str) -> dict[str, Any]:
    """The earlier pass's ``summary.json`` (``{}`` when it was killed before writing one),
    after checking that the folder holds a suite's output, and this suite's."""
    if not (out_dir / SUMMARY_NAME).is_file():
        if (out_dir / "runs").is_dir() or (out_dir / "logs").is_dir():
            return {}
        raise SrrError(f"--out {out_dir}: folder is not empty and holds no suite output to "
                       f"resume (no {SUMMARY_NAME}, runs/ or logs/)")
    # the checked reader `srr diff` uses (format, name, each run's id ...); imported here, on
    # a resume only: it brings the run diff and the report's formatting
    from harness.suite.diff import read_suite

    data = read_suite(out_dir)
    if data["name"] != name:
        raise SrrError(f"--out {out_dir}: holds the suite {data.get('name')!r}, not {name!r}; "
                       "nothing resumed")
    return data


def _judge(spec: RunSpec, out_dir: Path, before: dict[str, Any] | None,
           loads: ScenarioLoads) -> tuple[str | None, RunOutcome | None]:
    """``(why it runs again, None)``, or ``(None, its outcome)`` when it is kept; ``why`` is
    None for a run that has no folder (never started)."""
    run_dir = out_dir / spec.run_dir
    if not run_dir.is_dir():
        return None, None
    try:
        summary = json.loads((run_dir / SUMMARY_NAME).read_text(encoding="utf-8"))
    except FileNotFoundError:
        return "it did not finish (no summary.json)", None
    except (OSError, ValueError) as err:
        return f"its summary.json is unreadable ({err})", None
    if not isinstance(summary, dict):
        return "its summary.json is not a run's", None
    if summary.get("verdict") == "INTERRUPTED" or summary.get("interrupted"):
        return "it was interrupted", None
    timed_out = any(isinstance(g, dict) and g.get("name") == TIMEOUT_GATE and not g.get("ok")
                    for g in summary.get("health") or ())
    if timed_out or (before is not None and before.get("timed_out")):
        return "it was stopped at its timeout", None
    if before is not None and before.get("crash"):
        return f"its worker crashed ({before['crash']})", None
    recorded_by = (summary.get("versions") or {}).get("srr")
    if recorded_by != __version__:
        return f"it was recorded by srr {recorded_by}, this is {__version__}", None
    changed = _scenario_changes(spec, run_dir, loads)
    if changed:
        return f"its scenario changed since it ran ({changed})", None
    rebaselined = _baseline_changes(summary)
    if rebaselined:
        return rebaselined, None
    log = log_path(out_dir, spec)
    outcome = outcome_of(
        spec, out_dir, exit_code=int(summary.get("exit_code", 3)), error=None,
        wall_s=float(before.get("wall_s", 0.0)) if before else 0.0,
        log=log if log.is_file() else None,
        peak_rss_mb=before.get("peak_rss_mb") if before else None)
    note = before.get("peak_rss_note") if before else None
    return None, dataclasses.replace(outcome, peak_rss_note=str(note) if note else None)


def _scenario_changes(spec: RunSpec, run_dir: Path, loads: ScenarioLoads) -> str:
    """The first differences between the scenario the run used and the one it would use now
    ("" when none)."""
    try:
        then = yamlio.load((run_dir / _SCENARIO).read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        return f"{_SCENARIO} unreadable: {err}"
    now = scenario_to_mapping(loads(spec.scenario_file, spec.overrides))
    if not isinstance(then, dict):
        return f"{_SCENARIO} is not a scenario"
    diffs = scenario_differences(then, now, limit=2)
    return "; ".join(diffs)


def _baseline_changes(summary: dict[str, Any]) -> str:
    """Why the run's comparison with its baseline no longer holds ("" when it does): the
    baseline file it was compared with is gone or was blessed again since."""
    baseline = summary.get("baseline")
    if not isinstance(baseline, dict) or not baseline.get("path"):
        return ""
    path = Path(str(baseline["path"]))
    try:
        now = load_baseline(path)
    except BaselineError as err:
        return f"its baseline is unreadable ({err})"
    if now is None:
        return f"its baseline {path} is gone"
    if now.blessed_at != baseline.get("blessed_at"):
        return f"its baseline {path} was blessed again since it ran"
    return ""
