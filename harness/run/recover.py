"""``srr recover``: turn what a killed run left back into a valid run directory (its bag
rebuilt from complete chunks, a summary marked recovered, INVALID)."""

from __future__ import annotations

import dataclasses
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness import runlock, runmarker
from harness.atomic import write_json_atomic
from harness.errors import SrrError
from harness.metrics.types import HealthResult
from harness.recording.errors import BagError, NothingRecorded
from harness.recording.recover import RecoveredBag, recover_bag
from harness.recording.verify import check_read_back
from harness.report.junit import junit_cases, write_junit
from harness.run.facts import combined_digest, reproduce_command, topic_table, versions
from harness.run.summary import RunSummary
from harness.scenario import Scenario, load_scenario
from harness.summary import SUMMARY_NAME, read_summary

__all__ = ["RecoverResult", "recover"]


@dataclass(frozen=True)
class RecoverResult:
    """What :func:`recover` did. ``bag.status`` says what happened to the bag (``valid``,
    ``metadata`` or ``rebuilt``); ``run_dir`` is None for a bare bag directory; ``summary``
    is the summary written for a run that had not finished, or whose summary no longer holds
    for its bag (None when nothing was written: a finished run keeps its own, ``kept``);
    ``phase`` is how far the killed run had got (from its ``incomplete.json``); ``cause``
    says, in a few words, why the summary was written; ``replaced`` maps the files the new
    summary replaced (``summary.json``, ``report.html``) to where they are kept."""

    bag: RecoveredBag
    run_dir: Path | None
    summary: dict[str, Any] | None
    phase: str | None
    kept: bool = False
    cause: str | None = None
    replaced: dict[str, Path] = dataclasses.field(default_factory=dict)

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
    (:func:`harness.recording.recover.recover_bag`; the original is kept as ``*.mcap.damaged``),
    and its ``metadata.yaml`` rewritten when it is missing or wrong. A finished run (its
    ``summary.json`` valid) keeps its summary as long as its bag holds every message the
    summary counts (per-topic counts and digests), whether the bag was whole or rebuilt; a whole
    bag that does not hold them is refused (the summary belongs to another recording). A run
    directory that has no summary, or still holds ``incomplete.json``, or whose summary does not
    read, or whose finished bag had to be rebuilt and lost messages, gets a ``summary.json``
    (and ``junit.xml``) marked ``recovered: true`` with verdict INVALID: per-topic counts and
    digests of what was kept, no scores (nothing is compared with the baseline). A summary it
    replaces is kept as ``summary.json.replaced``, and the ``report.html`` that showed it as
    ``report.html.replaced`` (``srr report`` renders the recovered run's). Raises
    :class:`~harness.recording.errors.BagError` (nothing written) when the bag cannot be
    recovered, and :class:`~harness.errors.RunInUseError` (nothing touched) when the run is
    still being written: its lock is held (:mod:`harness.runlock`); a lock left by a dead
    process is free. The run directory is owned while it is recovered."""
    p = Path(path)
    base = p.parent if p.is_file() else p
    for cand in (base, base.parent):  # a run directory, or its bag/
        runlock.refuse_if_live(cand)
    run_dir = _run_dir_of(base)
    if run_dir is None:
        result = _recover(p, None)
        orphan = next((c for c in (base, base.parent) if (c / "bag").is_dir()
                       and (c / runmarker.MARKER).is_file()), None)
        if orphan is not None:  # a killed run's directory that lost its scenario.yaml
            done = {"valid": "whole", "metadata": "whole (its metadata.yaml rewritten)",
                    "rebuilt": "rebuilt from its complete chunks"}[result.bag.status]
            raise SrrError(f"{orphan}: the bag is {done} ({result.bag.mcap}), but "
                           "the run directory has no scenario.yaml, so its summary cannot be "
                           f"written: the run stays unfinished ({runmarker.MARKER} kept); put "
                           "the run's scenario.yaml back and run srr recover again")
        return result
    with runlock.owning(run_dir, "recovered", fresh=False):
        return _recover(p, run_dir)


def _finished_summary(run_dir: Path) -> tuple[dict[str, Any] | None, str | None]:
    """``(summary, None)`` for a run directory whose ``summary.json`` reads, ``(None, why)``
    for one that does not, ``(None, None)`` for one without a summary."""
    if not (run_dir / SUMMARY_NAME).is_file():
        return None, None
    try:
        return read_summary(run_dir), None
    except SrrError as err:
        return None, str(err)


def _digests(summary: dict[str, Any] | None) -> dict[str, Any] | None:
    """A summary's per-topic counts and digests, None when it has none to check a bag against
    (a summary of an srr before digests, or of a run that recorded nothing)."""
    topics = None if summary is None else summary.get("topics")
    if not topics or not all(isinstance(t, dict) and t.get("sha256") for t in topics.values()):
        return None
    return dict(topics)


def _holds(bag: RecoveredBag, recorded: dict[str, Any] | None) -> bool:
    """Whether the (rebuilt) bag holds every message ``recorded`` counts, no more, no less."""
    if recorded is None:
        return False
    try:
        check_read_back(bag.mcap, recorded, {n: (t.count, t.sha256)
                                             for n, t in bag.topics.items() if t.count})
    except BagError:
        return False
    return True


def _aside(path: Path) -> Path:
    """Where ``path`` is kept when it is replaced: ``<name>.replaced`` (or ``.replaced.2``,
    ...: an earlier one is never overwritten)."""
    dest, n = path.with_name(path.name + ".replaced"), 1
    while dest.exists():
        n += 1
        dest = path.with_name(f"{path.name}.replaced.{n}")
    return dest


def _recover(p: Path, run_dir: Path | None) -> RecoverResult:
    marker = runmarker.read(run_dir) if run_dir is not None else None
    scenario = load_scenario(run_dir / "scenario.yaml") if run_dir is not None else None
    finished, unreadable = (None, None) if run_dir is None else _finished_summary(run_dir)
    recorded = _digests(finished)
    try:
        bag = recover_bag(p, recorded=recorded)
    except NothingRecorded as err:
        if run_dir is None or (run_dir / SUMMARY_NAME).is_file():
            raise
        raise NothingRecorded(err.mcap, err.size, (
            f"{run_dir}: nothing was recorded: the run was killed before its first chunk was "
            f"written ({Path(err.mcap).name}: {err.size} bytes, no complete chunk); nothing to "
            "recover, the run directory can be deleted")) from err
    if run_dir is None or scenario is None:
        return RecoverResult(bag, None, None, None)
    phase = None if marker is None else str(marker.get("phase", "unknown"))
    has_summary = (run_dir / SUMMARY_NAME).is_file()
    if finished is not None and (bag.status != "rebuilt" or _holds(bag, recorded)):
        # finished (or killed in the instant between its summary and the marker's removal),
        # and its bag holds what the summary says: the summary stands
        runmarker.clear(run_dir)
        return RecoverResult(bag, run_dir, None, phase, kept=True)
    if bag.status == "valid" and has_summary:
        runmarker.clear(run_dir)  # a whole bag beside a summary that does not read: left as is
        return RecoverResult(bag, run_dir, None, phase)
    if marker is not None:
        cause, short = {"recording": ("the run was killed during the tick loop",
                                      "killed while recording"),
                        "finalizing": ("the run was killed while finalizing (after the tick "
                                       "loop)", "killed while finalizing")}.get(
            phase or "", ("the run was killed before it wrote its summary",
                          f"killed while {runmarker.killed_while(marker)}"))
    elif finished is not None:
        cause = ("the run had finished, but its bag was cut short or damaged afterwards: it "
                 "no longer holds every message its summary counted")
        short = "its bag was damaged after the run finished"
    elif unreadable is not None:
        cause, short = f"its summary did not read ({unreadable})", "its summary did not read"
    else:
        cause = "the run was killed before it wrote its summary"
        short = "killed while running"
    replaced = {name: _aside(run_dir / name) for name in (SUMMARY_NAME, "report.html")
                if (run_dir / name).is_file()}
    if replaced:
        cause += "; " + " and ".join(f"the {n} it had is kept as {dest.name}"
                                      for n, dest in replaced.items())
    summary = _recovered_summary(run_dir, scenario, bag, marker or {}, phase,
                                 cause).to_json()
    if SUMMARY_NAME in replaced:  # a copy first: the directory always holds a summary
        shutil.copy2(run_dir / SUMMARY_NAME, replaced[SUMMARY_NAME])
    write_junit(run_dir / "junit.xml", scenario.name, junit_cases(summary))
    write_json_atomic(run_dir / SUMMARY_NAME, summary)
    if "report.html" in replaced:  # it shows the replaced summary
        os.replace(run_dir / "report.html", replaced["report.html"])
    runmarker.clear(run_dir)
    return RecoverResult(bag, run_dir, summary, phase, cause=short, replaced=replaced)


def _recovered_summary(run_dir: Path, scenario: Scenario, bag: RecoveredBag,
                       marker: dict[str, Any], phase: str | None, cause: str) -> RunSummary:
    hz = scenario.physics.tick_hz
    last = max((t.last_ns for t in bag.topics.values() if t.last_ns is not None), default=None)
    # Stamps are tick * 1e9 // hz, so the last kept tick is ceil(last * hz / 1e9).
    ticks = 0 if last is None else -(-last * hz // 1_000_000_000) + 1
    sim_s = ticks / hz
    topics = {n: dataclasses.replace(t, published=None)  # unknown: the run did not finish
              for n, t in topic_table(bag.topics, {}, sim_s).items()}
    kept = sum(t.count for t in bag.topics.values())
    dropped = (f"; the {bag.dropped_bytes} bytes after them, an incomplete chunk, were "
               "dropped" if bag.dropped_bytes else "")
    what = {"rebuilt": f"the bag was rebuilt from its {bag.chunks} complete chunks "
                       f"({kept} messages, {sim_s:g} s of simulated time{dropped}; the "
                       f"original is kept as {bag.damaged.name if bag.damaged else '?'})",
            "metadata": f"the bag's MCAP file was complete ({kept} messages); its "
                        "metadata.yaml was rewritten",
            "valid": f"the bag was complete ({kept} messages)"}[bag.status]
    detail = f"{cause}; recovered with srr recover: {what}; scores were not computed"
    return RunSummary(
        scenario=scenario.name, scenario_file=marker.get("scenario_file", ""),
        seed=scenario.seed, srr_gt=scenario.srr_gt, duration_s=scenario.duration,
        simulated_s=sim_s, ticks=ticks, tick_hz=scenario.physics.tick_hz, interrupted=True,
        recovered=True,
        recovery={"bag": bag.status, "phase": phase, "chunks_kept": bag.chunks,
                  "messages_kept": kept, "dropped_bytes": bag.dropped_bytes,
                  "damaged_file": None if bag.damaged is None else bag.damaged.name},
        health=(HealthResult("recording_complete", False, detail),), metrics=(),
        systems_under_test=tuple(s.name for s in scenario.systems_under_test if s.enabled),
        topics=topics, digest=combined_digest(topics), versions=versions(),
        command=marker.get("command") or reproduce_command(
            marker.get("scenario_file", str(run_dir / "scenario.yaml")), scenario, run_dir),
        verdict="INVALID", exit_code=3,
        reasons=(f"health recording_complete: {detail}",))
