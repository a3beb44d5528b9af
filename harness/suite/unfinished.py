"""A run that did not finish, as the suite leaves it: every run of a suite ends with its run
directory and a ``summary.json`` in it, however it ended.

The suite's own process settles each run after its worker has ended (exited, crashed, been
killed at its timeout or on Ctrl-C, or — on Ray — been cancelled before it even started):

* a run directory that still holds ``incomplete.json`` is recovered (``srr recover``: the bag
  from its complete chunks, a summary marked recovered, its report);
* a run that left no summary — stopped or dead before its first tick, before its first chunk
  was written (``srr recover`` refuses a bag that holds no message), or with nothing that
  could be recovered — gets its directory written here: the resolved ``scenario.yaml``, a
  ``summary.json`` with verdict INVALID (INTERRUPTED when the worker was stopped by Ctrl-C or
  SIGTERM), no topics and no scores, whose reason says what happened, and ``junit.xml``.
"""

from __future__ import annotations

import contextlib
import dataclasses
from dataclasses import dataclass
from pathlib import Path

from harness import runmarker
from harness.errors import SrrError
from harness.interrupt import INTERRUPTED_EXIT
from harness.metrics.types import HealthResult
from harness.recording.errors import NothingRecorded
from harness.report.junit import junit_cases, write_junit
from harness.run.facts import combined_digest, reproduce_command, versions, write_scenario
from harness.run.loading import load
from harness.run.summary import RunSummary
from harness.suite.plan import RunSpec
from harness.summary import SUMMARY_NAME

__all__ = ["TIMEOUT_GATE", "Settled", "mark_timed_out", "settle"]

#: The health gate a run the suite stopped at its timeout fails (its own summary said only
#: that it was interrupted: the suite's SIGTERM reached it as a Ctrl-C would).
TIMEOUT_GATE = "wall_clock_timeout"

#: The health gate a settled run fails, as a recovered one does.
GATE = "recording_complete"


@dataclass(frozen=True)
class Settled:
    """What :func:`settle` did: ``note`` says it for the run's reasons (None: nothing to say);
    ``written`` is True when the summary was written here (nothing was recorded)."""

    note: str | None
    written: bool = False


def _salvage(run_path: Path) -> str | None:
    """Recover what a killed run left (bag from its complete chunks, a summary marked
    recovered) and render its report; a note on what happened, None when nothing was left.
    Raises :class:`SrrError` when there was something that could not be recovered."""
    if runmarker.read(run_path) is None or not (run_path / "bag").is_dir():
        return None  # not even the recorder was made: nothing to recover
    # imported here: the bag readers and the report, needed only for a run that was killed
    from harness.run.recover import recover
    from harness.run.rerender import report

    res = recover(run_path)
    with contextlib.suppress(SrrError):
        report(run_path)
    kept = sum(t.count for t in res.bag.topics.values())
    return f"{kept} recorded messages were recovered from its complete chunks"


def settle(run_path: Path, spec: RunSpec, problem: str, *, interrupted: bool = False
           ) -> Settled:
    """Leave ``run_path`` (run ``spec``'s directory; its worker has ended, for ``problem``) with
    a ``summary.json``: what the run left, recovered; else one written here, INVALID (or
    INTERRUPTED when the worker was ``interrupted``: Ctrl-C or SIGTERM), saying ``problem``
    and how far the run got."""
    try:
        note = _salvage(run_path)
        if (run_path / SUMMARY_NAME).is_file():
            return Settled(note)
        what = "it ended before its first tick: nothing was recorded"
    except NothingRecorded as err:
        what = (f"it ended before its first chunk was written: nothing was recorded "
                f"({Path(err.mcap).name}: {err.size} bytes)")
    except SrrError as err:
        what = f"what it recorded could not be recovered ({err})"
    try:
        _write(run_path, spec, f"{problem}; {what}", interrupted=interrupted)
    except (SrrError, OSError) as err:
        return Settled(f"{what}; its run directory could not be written ({err})")
    verdict = "INTERRUPTED" if interrupted else "INVALID"
    return Settled(f"{what}; the suite wrote its run directory with an {verdict} summary",
                   written=True)


def _write(run_path: Path, spec: RunSpec, detail: str, *, interrupted: bool) -> None:
    """The resolved scenario, an INVALID (``interrupted``: INTERRUPTED) ``summary.json`` (no
    topics, no scores) whose one failed health gate says ``detail``, and its ``junit.xml``;
    the in-progress marker, if any, removed."""
    scenario = load(spec.scenario_file, overrides=list(spec.overrides))
    run_path.mkdir(parents=True, exist_ok=True)
    write_scenario(run_path, scenario)
    summary = RunSummary(
        scenario=scenario.name, scenario_file=spec.scenario_file, seed=scenario.seed,
        srr_gt=scenario.srr_gt, duration_s=scenario.duration, simulated_s=0.0, ticks=0,
        tick_hz=scenario.physics.tick_hz, interrupted=True,
        health=(HealthResult(GATE, False, detail),), metrics=(),
        systems_under_test=tuple(s.name for s in scenario.systems_under_test if s.enabled),
        topics={}, digest=combined_digest({}), versions=versions(),
        command=reproduce_command(spec.scenario_file, scenario, run_path),
        verdict="INTERRUPTED" if interrupted else "INVALID",
        exit_code=INTERRUPTED_EXIT if interrupted else 3,
        reasons=(f"health {GATE}: {detail}",))
    write_junit(run_path / "junit.xml", scenario.name, junit_cases(summary.to_json()))
    summary.write(run_path)
    runmarker.clear(run_path)


def mark_timed_out(run_path: Path, detail: str) -> None:
    """A run the suite stopped at its timeout finalized itself as INTERRUPTED (the SIGTERM
    reached it as Ctrl-C would): its ``summary.json`` and ``junit.xml`` are made to say what
    the suite says, INVALID (exit 3), the health gate :data:`TIMEOUT_GATE` failed with
    ``detail`` first among its reasons, and its report rendered again so the page agrees."""
    summary = RunSummary.read(run_path)
    summary = dataclasses.replace(
        summary, verdict="INVALID", exit_code=3,
        health=(*summary.health, HealthResult(TIMEOUT_GATE, False, detail)),
        reasons=(f"health {TIMEOUT_GATE}: {detail}", *summary.reasons))
    write_junit(run_path / "junit.xml", summary.scenario, junit_cases(summary.to_json()))
    summary.write(run_path)
    from harness.run.rerender import report

    with contextlib.suppress(SrrError):  # the summary is what counts; the page follows it
        report(run_path, video=(run_path / "video").is_dir())
