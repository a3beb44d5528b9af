"""``srr recover``: turn what a killed run left back into a valid run directory (its bag
rebuilt from complete chunks, a summary marked recovered, INVALID)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness import runlock, runmarker
from harness.atomic import write_json_atomic
from harness.metrics.types import HealthResult
from harness.recording.recover import RecoveredBag, recover_bag
from harness.report.junit import junit_cases, write_junit
from harness.run.facts import combined_digest, reproduce_command, topic_table, versions
from harness.run.summary import RunSummary
from harness.scenario import Scenario, load_scenario
from harness.summary import SUMMARY_NAME

__all__ = ["RecoverResult", "recover"]


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
    (:func:`harness.recording.recover.recover_bag`; the original is kept as ``*.mcap.damaged``). A
    run directory that has no summary, or still holds ``incomplete.json``, or whose bag had to
    be rebuilt, gets a ``summary.json`` (and ``junit.xml``) marked ``recovered: true`` with
    verdict INVALID: per-topic counts and digests of what was kept, no scores (the run did not
    finish, so nothing is compared with the baseline). A finished run with a valid bag is left
    as it is. Raises :class:`~harness.recording.errors.BagError` (nothing written) when the
    bag cannot be recovered, and :class:`~harness.errors.RunInUseError` (nothing touched) when
    the run is still being written: its lock is held (:mod:`harness.runlock`); a lock left by a dead
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
    summary = _recovered_summary(run_dir, scenario, bag, marker or {}, phase).to_json()
    write_junit(run_dir / "junit.xml", scenario.name, junit_cases(summary))
    write_json_atomic(run_dir / SUMMARY_NAME, summary)
    runmarker.clear(run_dir)
    return RecoverResult(bag, run_dir, summary, phase)


def _recovered_summary(run_dir: Path, scenario: Scenario, bag: RecoveredBag,
                       marker: dict[str, Any], phase: str | None) -> RunSummary:
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
    when = {"recording": "during the tick loop", "finalizing": "while finalizing (after the "
            "tick loop)"}.get(phase or "", "before it wrote its summary")
    detail = (f"the run was killed {when}; recovered with srr recover: {what}; scores were "
              "not computed")
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
