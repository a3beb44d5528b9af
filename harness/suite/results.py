"""How runs ended, and what a group of repeats says: verdicts, statistics, flakiness.

A run's outcome comes from its run directory's ``summary.json`` plus what the executor saw
(exit status, signal, timeout). A run whose worker crashed (a signal such as SIGSEGV, an
out-of-memory kill), timed out, or could not start is INVALID with that reason; its run
directory is settled (:mod:`harness.suite.unfinished`): whatever it left is recovered (``srr
recover``) and kept for the reviewer, and one that left nothing gets a directory with an
INVALID summary saying what happened. A group — one scenario or sweep point, all its repeats —
is INVALID when any repeat is, FLAKY when its repeats' digests or verdicts differ (the first
divergence comes from ``srr diff``), else the repeats' verdict.
"""

from __future__ import annotations

import dataclasses
import signal
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from harness.errors import SrrError
from harness.interrupt import INTERRUPTED_EXIT
from harness.regression.verdict import EXIT_CODES, OK_VERDICTS
from harness.suite.plan import RunSpec
from harness.suite.stats import describe
from harness.suite.unfinished import Settled, mark_timed_out, settle
from harness.summary import SUMMARY_NAME, read_summary

__all__ = ["GROUP_ORDER", "GroupResult", "RunOutcome", "crash_reason", "group_runs",
           "outcome_of", "suite_exit_code", "worst"]

#: Worst first. FLAKY and INVALID are group verdicts a single run can make.
GROUP_ORDER = ("INVALID", "FLAKY", "MISMATCH", "REGRESSED", "FAIL", "INTERRUPTED", "UNSCORED",
               "RECORDED", "PASS")
_STATUS_ORDER = ("missing", "regressed", "new", "changed", "improved", "ok")
_BAND_ORDER = ("FAIL", "NEAR", "PASS")


def worst(verdicts: Sequence[str]) -> str:
    ranked = [v if v in GROUP_ORDER else "INVALID" for v in verdicts]
    return min(ranked, key=GROUP_ORDER.index) if ranked else "INVALID"


@dataclass(frozen=True)
class RunOutcome:
    """One run as the suite saw it. ``run_dir``, ``report`` and ``log`` are POSIX paths
    relative to the suite's output folder (None when absent)."""

    spec: RunSpec
    verdict: str
    exit_code: int
    reasons: tuple[str, ...]
    wall_s: float
    run_dir: str | None
    report: str | None
    log: str | None
    digest: str | None
    timed_out: bool = False
    crash: str | None = None
    topics: Mapping[str, str] = field(default_factory=dict)  # topic → sha256
    metrics: tuple[Mapping[str, Any], ...] = ()  # summary["metrics"] (trusted runs only)
    comparison: tuple[Mapping[str, Any], ...] = ()
    peak_rss_mb: float | None = None  # the worker process's peak resident memory
    #: Why ``peak_rss_mb`` is None for a run that ran (a host could not reset its peak)
    peak_rss_note: str | None = None
    #: When it was submitted and reaped, and the worker's :data:`harness.suite.worker.PHASES`
    #: (``time.monotonic`` instants of this machine; :mod:`harness.suite.timeline`)
    clock: Mapping[str, float] | None = None
    #: The run's bytes against its baseline's (trusted runs with a baseline only): the
    #: summary's ``digest_matches``, ``topics_differing`` and ``versions_differing``
    against_baseline: Mapping[str, Any] | None = None
    #: False for a run the suite never started (it was interrupted first)
    started: bool = True

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.spec.id, "group": self.spec.group, "repeat": self.spec.repeat,
            "scenario": self.spec.scenario, "params": dict(self.spec.params),
            "verdict": self.verdict, "exit_code": self.exit_code,
            "reasons": list(self.reasons), "wall_s": round(self.wall_s, 3),
            "peak_rss_mb": self.peak_rss_mb,
            "run_dir": self.run_dir, "report": self.report, "log": self.log,
            "digest": self.digest, "timed_out": self.timed_out, "crash": self.crash,
            "metrics": {m["name"]: m.get("value") for m in self.metrics},
            "recording_matches_baseline": None if self.against_baseline is None
            else bool(self.against_baseline.get("digest_matches")),
            **({"peak_rss_note": self.peak_rss_note} if self.peak_rss_note else {}),
        }


def crash_reason(returncode: int) -> str:
    """``killed by signal SIGSEGV`` for a negative return code (the process got a signal)."""
    try:
        name = signal.Signals(-returncode).name
    except ValueError:
        name = f"{-returncode}"
    hint = {"SIGKILL": " (the out-of-memory killer, or kill -9)",
            "SIGSEGV": " (a segmentation fault)", "SIGABRT": " (an abort)"}.get(name, "")
    return f"killed by signal {name}{hint}"


def _rel(path: Path, root: Path) -> str:
    return path.relative_to(root).as_posix()


def outcome_of(spec: RunSpec, out_root: Path, *, exit_code: int, error: str | None,
               wall_s: float, timed_out: bool = False, crash: str | None = None,
               log: Path | None = None, peak_rss_mb: float | None = None) -> RunOutcome:
    """Read what run ``spec`` left under ``out_root`` and judge how it ended."""
    run_path = out_root / spec.run_dir
    problem = None
    if timed_out:
        problem = (f"timed out after {spec.timeout_s:g} s of wall-clock time and was stopped"
                   if spec.timeout_s is not None else "timed out")
    elif crash is not None:
        problem = f"the worker crashed: {crash}"
    # a worker that exits 130 on its own (not at its timeout) was stopped by Ctrl-C or SIGTERM
    interrupted = exit_code == INTERRUPTED_EXIT and not timed_out and crash is None
    if problem is None and not (run_path / SUMMARY_NAME).is_file():
        if interrupted:
            problem = error or "interrupted (Ctrl-C or SIGTERM) before it wrote summary.json"
        elif error:
            problem = f"it could not run: {error}"
        else:
            problem = f"the worker exited with status {exit_code} without writing summary.json"
    settled = (settle(run_path, spec, problem or f"the worker exited with status {exit_code}",
                      interrupted=interrupted)
               if problem is not None or exit_code not in (0, 1, 3) else Settled(None))
    summary: dict[str, Any] | None = None
    if (run_path / SUMMARY_NAME).is_file() and not settled.written:
        try:
            summary = read_summary(run_path)
            if timed_out and problem is not None and summary.get("verdict") == "INTERRUPTED":
                mark_timed_out(run_path, problem)  # its summary says what the suite says
                summary = read_summary(run_path)
        except SrrError as err:
            problem = problem or f"its summary.json is unreadable ({err})"
    salvaged = settled.note
    report = run_path / "report.html"
    base = RunOutcome(
        spec=spec, verdict="INVALID", exit_code=3, reasons=(), wall_s=wall_s,
        timed_out=timed_out, crash=crash, peak_rss_mb=peak_rss_mb,
        run_dir=_rel(run_path, out_root) if run_path.is_dir() else None,
        report=_rel(report, out_root) if report.is_file() else None,
        log=_rel(log, out_root) if log is not None and log.is_file() else None,
        digest=None if summary is None else summary.get("digest"),
        topics={} if summary is None else {
            t: str(v.get("sha256")) for t, v in summary.get("topics", {}).items()})
    if problem is not None:
        if interrupted:
            base = dataclasses.replace(base, verdict="INTERRUPTED", exit_code=INTERRUPTED_EXIT)
        return dataclasses.replace(base, reasons=(problem, *([salvaged] if salvaged else [])))
    assert summary is not None
    verdict = str(summary.get("verdict", "INVALID"))
    trusted = verdict not in ("INVALID", "INTERRUPTED")
    return dataclasses.replace(
        base, verdict=verdict, exit_code=int(summary.get("exit_code", 3)),
        reasons=tuple(str(r) for r in summary.get("reasons", [])),
        metrics=tuple(summary.get("metrics", [])) if trusted else (),
        comparison=tuple(summary.get("comparison") or []) if trusted else (),
        against_baseline=_against_baseline(summary) if trusted else None)


def _against_baseline(summary: Mapping[str, Any]) -> dict[str, Any] | None:
    b = summary.get("baseline")
    if not isinstance(b, Mapping):
        return None
    return {"digest_matches": bool(b.get("digest_matches")),
            "topics_differing": list(b.get("topics_differing") or ()),
            "versions_differing": dict(b.get("versions_differing") or {})}


@dataclass(frozen=True)
class GroupResult:
    """All repeats of one scenario or sweep point."""

    id: str
    runs: tuple[RunOutcome, ...]
    verdict: str
    reasons: tuple[str, ...]
    flaky: bool
    flaky_detail: Mapping[str, Any] | None
    stats: Mapping[str, Mapping[str, Any]]

    @property
    def exit_code(self) -> int:
        if self.verdict == "INTERRUPTED":
            return INTERRUPTED_EXIT
        return EXIT_CODES.get(self.verdict, 1)

    def to_json(self) -> dict[str, Any]:
        first = self.runs[0].spec
        return {
            "id": self.id, "name": first.entry, "scenario": first.scenario,
            "scenario_file": first.scenario_file, "params": dict(first.params),
            "sweep": first.entry if first.sweep else None, "repeats": len(self.runs),
            "verdict": self.verdict, "exit_code": self.exit_code, "reasons": list(self.reasons),
            "flaky": self.flaky, "flaky_detail": self.flaky_detail,
            "stats": {k: dict(v) for k, v in self.stats.items()},
            "runs": [r.spec.id for r in self.runs],
            "against_baseline": self.against_baseline,
        }

    @property
    def against_baseline(self) -> Mapping[str, Any] | None:
        """The first repeat's bytes against the baseline's (a group that is not flaky
        recorded the same bytes in every repeat): ``digest_matches``, ``topics_differing``,
        ``versions_differing``; None without a baseline or a trusted run."""
        return self.runs[0].against_baseline if self.runs else None

    @property
    def recorded_other_bytes(self) -> bool:
        """Whether the group (not flaky) recorded other bytes than its baseline's while its
        metrics were judged on their own: what the console, the Markdown summary and the page
        point out."""
        b = self.against_baseline
        return (not self.flaky and self.verdict != "MISMATCH"  # (its metrics: not judged)
                and b is not None and not b.get("digest_matches"))


def _stats(runs: Sequence[RunOutcome]) -> dict[str, dict[str, Any]]:
    names: dict[str, Mapping[str, Any]] = {}
    for r in runs:
        for m in r.metrics:
            names.setdefault(str(m["name"]), m)
    out: dict[str, dict[str, Any]] = {}
    for name, first in names.items():
        values = [m["value"] for r in runs for m in r.metrics
                  if m["name"] == name and isinstance(m.get("value"), (int, float))]
        entries = [e for r in runs for e in r.comparison if e.get("name") == name]
        bands = [str(m["verdict"]) for r in runs for m in r.metrics
                 if m["name"] == name and m.get("verdict") in _BAND_ORDER]
        statuses = [str(e.get("status")) for e in entries if e.get("status") in _STATUS_ORDER]
        d = describe(values)
        out[name] = {
            "unit": first.get("unit", ""), "direction": first.get("direction", "none"),
            "group": first.get("group", ""), "n": 0 if d is None else d.n,
            "mean": None if d is None else d.mean, "std": None if d is None else d.std,
            "min": None if d is None else d.min, "max": None if d is None else d.max,
            "ci95": None if d is None or d.ci95 is None else list(d.ci95),
            "baseline": entries[0].get("baseline") if entries else None,
            "tolerance": entries[0].get("tolerance") if entries else None,
            "status": min(statuses, key=_STATUS_ORDER.index) if statuses else None,
            "band": min(bands, key=_BAND_ORDER.index) if bands else None,
        }
    return dict(sorted(out.items()))


def _flaky(runs: Sequence[RunOutcome], out_root: Path) -> dict[str, Any] | None:
    """How the repeats disagree (digests or verdicts), None when they agree. Repeats that
    were interrupted (Ctrl-C), timed out or crashed are left out: where a run was stopped is
    a matter of wall-clock time, so what it recorded up to then says nothing of whether the
    simulation repeats (their group is INTERRUPTED or INVALID, with what happened)."""
    runs = [r for r in runs
            if r.verdict != "INTERRUPTED" and not r.timed_out and r.crash is None]
    finished = [r for r in runs if r.digest is not None and r.run_dir is not None]
    verdicts = [r.verdict for r in runs]
    odd = next((r for r in finished[1:] if r.digest != finished[0].digest), None)
    if odd is None and len(set(verdicts)) <= 1:
        return None
    detail: dict[str, Any] = {"verdicts": verdicts, "digests": [r.digest for r in runs],
                              "differing_topics": [], "first_divergence": None,
                              "compared": []}
    if odd is not None:
        a = finished[0]
        detail["compared"] = [a.spec.id, odd.spec.id]
        detail["differing_topics"] = sorted(
            t for t in set(a.topics) | set(odd.topics) if a.topics.get(t) != odd.topics.get(t))
        from harness.diff import diff_runs

        try:
            assert a.run_dir is not None and odd.run_dir is not None
            first = diff_runs(out_root / a.run_dir, out_root / odd.run_dir).first_divergence
            detail["first_divergence"] = None if first is None else first.describe()
        except SrrError as err:
            detail["first_divergence"] = f"(not found: {err})"
    return detail


def _group(gid: str, runs: Sequence[RunOutcome], out_root: Path) -> GroupResult:
    flaky = _flaky(runs, out_root)
    base = worst([r.verdict for r in runs])
    verdict = "FLAKY" if flaky is not None and base != "INVALID" else base
    reasons: list[str] = []
    if flaky is not None:
        what = (f"digests differ on {', '.join(flaky['differing_topics'])}"
                if flaky["differing_topics"] else "verdicts differ")
        verdicts = flaky["verdicts"]
        reasons.append(f"flaky over {len(verdicts)} repeats ({' / '.join(verdicts)}): "
                       f"{what}" + (f"; first divergence: {flaky['first_divergence']}"
                                    if flaky["first_divergence"] else ""))
    for r in runs:
        if r.verdict != "PASS":
            tag = f"#{r.spec.repeat}: " if len(runs) > 1 else ""
            reasons += [f"{tag}{x}" for x in r.reasons if f"{tag}{x}" not in reasons]
    return GroupResult(gid, tuple(runs), verdict, tuple(reasons), flaky is not None, flaky,
                       _stats(runs))


def group_runs(outcomes: Sequence[RunOutcome], out_root: Path) -> tuple[GroupResult, ...]:
    """Groups in plan order (repeats in order within each)."""
    by: dict[str, list[RunOutcome]] = {}
    for o in outcomes:
        by.setdefault(o.spec.group, []).append(o)
    return tuple(_group(gid, sorted(rs, key=lambda r: r.spec.repeat), out_root)
                 for gid, rs in by.items())


def suite_exit_code(groups: Sequence[GroupResult], interrupted: bool) -> int:
    """130 interrupted; 3 any INVALID; 1 any regression, failure, mismatch or flaky; 0 all
    PASS or RECORDED (an empty suite is not a pass)."""
    if interrupted:
        return INTERRUPTED_EXIT
    if not groups or any(g.verdict == "INVALID" for g in groups):
        return 3
    return 0 if all(g.verdict in OK_VERDICTS for g in groups) else 1
