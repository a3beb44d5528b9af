"""``srr diff SUITE_A SUITE_B``: two suite output folders compared run by run — what changed
between last night's suite and tonight's, or between the suite on main and on a branch.

Runs are matched by their id in the suite (``<entry>[<sweep point>]#<repeat>``, see
:mod:`harness.suite.plan`): the suite file's entry name, the sweep point's label and the
repeat. A pair is compared by :func:`harness.diff.diff_runs` with ``digests_first``: the
topics both runs' ``summary.json`` record alike are identical without a message read, so
only the bags of runs whose recordings differ are opened, and in them only the topics that
differ. What is reported: runs only in A, only in B, verdict changes (of runs and of groups),
and for each matched run whose recording or metrics differ, one line (topics differing, the
first divergence, metrics moved beyond tolerance with their values).

The result (:attr:`SuiteDiff.exit_code`) keeps ``srr diff``'s meaning: 0 when both suites
ran the same runs, with the same verdicts, and every pair's recordings are equal (identical,
or within the ``--tolerance`` options); 1 otherwise; 2 (an :class:`SrrError`) for bad input.
As for two runs, metrics are shown but do not decide: equal recordings score equally.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any, Literal

from harness.diff import DiffResult, MetricDelta, Tolerance, diff_runs, parse_tolerance
from harness.errors import SrrError
from harness.report.html import fmt_value
from harness.suite.outputs import FORMAT
from harness.summary import SUMMARY_NAME, is_suite_summary

__all__ = ["GroupChange", "RunPair", "SuiteDiff", "SuiteInfo", "UnmatchedRun", "diff_suites",
           "is_suite_dir", "read_suite", "runs_named"]

#: How a pair's recordings compare: the run diff's verdict, or why there is none.
Recording = Literal["identical", "within_tolerance", "differs", "only_in_a", "only_in_b",
                    "none"]
MAX_TOPICS = 3  # topics named in a pair's line
MAX_METRICS = 3  # metrics named in a pair's line


def runs_named(ids: tuple[str, ...], total: int) -> str:
    """The runs a change applies to, for a line: ``all N runs`` when it is every one of the
    ``total`` pairs, else the first four ids and how many more."""
    if len(ids) == total and total > 1:
        return f"all {total} runs"
    return ", ".join(ids[:4]) + (f", +{len(ids) - 4} more" if len(ids) > 4 else "")


@dataclass(frozen=True)
class SuiteInfo:
    """One suite output folder as its ``summary.json`` says."""

    path: Path
    name: str
    verdict: str
    started_at: str | None
    runs: int


@dataclass(frozen=True)
class UnmatchedRun:
    """A run of one suite that the other did not run. ``run_dir``: its folder (None when the
    suite kept none)."""

    id: str
    group: str
    verdict: str
    run_dir: Path | None
    report: Path | None


@dataclass(frozen=True)
class GroupChange:
    """A group (one entry or sweep point, all its repeats) of both suites whose verdict
    changed: FLAKY is a group's verdict, not a run's."""

    id: str
    verdict_a: str
    verdict_b: str


@dataclass(frozen=True)
class RunPair:
    """One run of both suites. ``diff``: the run diff (:func:`harness.diff.diff_runs`), None
    when one run or both recorded nothing (``recording`` says which: a run that crashed or
    timed out before its first tick)."""

    id: str
    group: str
    verdict_a: str
    verdict_b: str
    run_a: Path | None
    run_b: Path | None
    report_a: Path | None
    report_b: Path | None
    diff: DiffResult | None
    recording: Recording

    @property
    def verdict_changed(self) -> bool:
        return self.verdict_a != self.verdict_b

    @property
    def moved(self) -> tuple[MetricDelta, ...]:
        """The metrics that moved beyond their tolerance (status other than ``ok``)."""
        return () if self.diff is None else tuple(m for m in self.diff.metrics
                                                  if m.status != "ok")

    @property
    def equal(self) -> bool:
        """The same verdict, and recordings equal (or neither run recorded anything)."""
        return not self.verdict_changed and self.recording in ("identical",
                                                                "within_tolerance", "none")

    @property
    def changed(self) -> bool:
        """Anything to show: a verdict, recordings not identical, a metric that moved (not
        two runs that both recorded nothing, with the same verdict)."""
        return not self.equal or self.recording not in ("identical", "none") \
            or bool(self.moved)

    def describe(self) -> str:
        """The pair in one line (without its id): verdicts, recording, metrics."""
        parts = [self.verdict_a if not self.verdict_changed
                 else f"{self.verdict_a} → {self.verdict_b}"]
        d = self.diff
        if self.recording in ("only_in_a", "only_in_b"):
            parts.append(f"recorded only in {'A' if self.recording == 'only_in_a' else 'B'}")
        elif self.recording == "none":
            parts.append("neither run recorded anything")
        elif d is not None and self.recording != "identical":
            differing = [t for t in d.topics if t.status != "identical"]
            names = ", ".join(t.name for t in differing[:MAX_TOPICS])
            more = len(differing) - MAX_TOPICS
            text = (f"recording {'differs' if self.recording == 'differs' else 'within tolerance'}"
                    f" in {len(differing)} of {len(d.topics)} topics ({names}"
                    f"{f', +{more} more' if more > 0 else ''})")
            first = d.first_divergence
            if first is not None:
                text += (f", first at {first.t_ns / 1e9:.3f} s: {first.topic} "
                         f"#{first.index} {first.path}")
            parts.append(text)
        else:
            parts.append("recording identical")
        moved = self.moved
        if moved:
            shown = [f"{m.name} {fmt_value(m.value_a, m.unit)} → {fmt_value(m.value_b, m.unit)}"
                     f" ({m.status})" for m in moved[:MAX_METRICS]]
            more = len(moved) - MAX_METRICS
            parts.append("metrics moved: " + ", ".join(shown)
                         + (f", +{more} more" if more > 0 else ""))
        return "; ".join(parts)

    def to_dict(self) -> dict[str, Any]:
        d = self.diff
        first = None if d is None else d.first_divergence
        return {
            "id": self.id, "group": self.group, "verdict_a": self.verdict_a,
            "verdict_b": self.verdict_b, "verdict_changed": self.verdict_changed,
            "run_a": _str(self.run_a), "run_b": _str(self.run_b),
            "recording": self.recording, "equal": self.equal, "changed": self.changed,
            "summary": self.describe(),
            "topics": [] if d is None else [
                {"name": t.name, "status": t.status, "count_a": t.count_a,
                 "count_b": t.count_b, "messages_differ": t.messages_differ}
                for t in d.topics if t.status != "identical"],
            "first_divergence": None if first is None else first.describe(),
            "metrics_moved": [{"name": m.name, "unit": m.unit, "value_a": _num(m.value_a),
                               "value_b": _num(m.value_b), "delta": _num(m.delta),
                               "tolerance": _num(m.tolerance), "status": m.status}
                              for m in self.moved],
            "changes": [] if d is None else list(d.changes),
            "notes": [] if d is None else list(d.notes),
        }


@dataclass(frozen=True)
class SuiteDiff:
    """``srr diff SUITE_A SUITE_B``. ``pairs``: the runs of both, in A's order;
    ``changes``: what changed between the pairs' inputs (:attr:`DiffResult.changes`), each
    line once with the ids of the runs it is true of; ``notes``: the suites' own (another
    suite file) and the pairs' (each with the ids it is true of)."""

    a: SuiteInfo
    b: SuiteInfo
    pairs: tuple[RunPair, ...]
    only_in_a: tuple[UnmatchedRun, ...]
    only_in_b: tuple[UnmatchedRun, ...]
    groups: tuple[GroupChange, ...]
    changes: tuple[tuple[str, tuple[str, ...]], ...]
    tolerances: tuple[Tolerance, ...]
    notes: tuple[str, ...]

    @property
    def equal(self) -> bool:
        return (not self.only_in_a and not self.only_in_b and not self.groups
                and all(p.equal for p in self.pairs))

    @property
    def exit_code(self) -> int:
        return 0 if self.equal else 1

    @property
    def verdict(self) -> str:
        if not self.equal:
            return "DIFFERENT"
        if all(p.recording in ("identical", "none") for p in self.pairs):
            return "IDENTICAL"
        return "EQUAL_WITHIN_TOLERANCE"

    @property
    def changed(self) -> tuple[RunPair, ...]:
        """The pairs worth a line: verdict changed, recordings not identical or metrics
        moved."""
        return tuple(p for p in self.pairs if p.changed)

    @property
    def verdict_changes(self) -> tuple[RunPair, ...]:
        return tuple(p for p in self.pairs if p.verdict_changed)

    def counts(self) -> str:
        """``23 matched runs: recordings 21 identical, 2 different; 2 verdicts changed;
        1 only in A``."""
        by = {"identical": 0, "within tolerance": 0, "different": 0, "recorded by neither": 0}
        for p in self.pairs:
            by[{"identical": "identical", "within_tolerance": "within tolerance",
                "none": "recorded by neither"}.get(p.recording, "different")] += 1
        parts = [f"{n} {k}" for k, n in by.items() if n]
        n = len(self.pairs)
        out = [f"{n} matched run{'s' if n != 1 else ''}"
               + (f": recordings {', '.join(parts)}" if parts else "")]
        changed = len(self.verdict_changes)
        if changed:
            out.append(f"{changed} verdict{'s' if changed > 1 else ''} changed")
        out += [f"{len(runs)} only in {side}"
                for side, runs in (("A", self.only_in_a), ("B", self.only_in_b)) if runs]
        return "; ".join(out)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (``--json``): paths as strings."""
        def info(s: SuiteInfo) -> dict[str, Any]:
            return {"path": str(s.path), "name": s.name, "verdict": s.verdict,
                    "started_at": s.started_at, "runs": s.runs}

        def unmatched(r: UnmatchedRun) -> dict[str, Any]:
            return {"id": r.id, "group": r.group, "verdict": r.verdict,
                    "run_dir": _str(r.run_dir)}

        return {
            "a": info(self.a), "b": info(self.b), "verdict": self.verdict,
            "equal": self.equal, "exit_code": self.exit_code,
            "pairs": [p.to_dict() for p in self.pairs],
            "only_in_a": [unmatched(r) for r in self.only_in_a],
            "only_in_b": [unmatched(r) for r in self.only_in_b],
            "groups_changed": [{"id": g.id, "verdict_a": g.verdict_a,
                                "verdict_b": g.verdict_b} for g in self.groups],
            "changes": [{"change": c, "runs": list(ids)} for c, ids in self.changes],
            "tolerances": [t.spec for t in self.tolerances],
            "notes": list(self.notes),
        }


def _str(p: Path | None) -> str | None:
    return None if p is None else str(p)


def _num(v: float | None) -> float | str | None:
    return str(v) if isinstance(v, float) and not math.isfinite(v) else v


# --------------------------------------------------------------------------- reading


def is_suite_dir(path: str | Path) -> bool:
    """Whether ``path`` is a suite output folder (what ``srr suite --out`` writes): a folder
    with no ``bag/`` that holds ``runs/`` or a ``summary.json`` of a suite. A suite folder
    whose summary is damaged is one (:func:`read_suite` says what is wrong with it)."""
    p = Path(path)
    if not p.is_dir() or (p / "bag").exists():
        return False
    if (p / "runs").is_dir():
        return True
    try:
        data = json.loads((p / SUMMARY_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError, UnicodeDecodeError, RecursionError):
        return False
    return is_suite_summary(data)


def _fail(file: Path, field: str, message: str) -> SrrError:
    return SrrError(f"{file}: {field}: {message}")


def _inside(value: Any, file: Path, field: str) -> str | None:
    """A path of the summary (relative to the suite folder, POSIX) or None; bad input when
    it is another type or leaves the folder."""
    if value is None:
        return None
    if not isinstance(value, str) or not value:
        raise _fail(file, field, f"expected a path inside the suite folder or null, got "
                    f"{value!r}")
    p = PurePosixPath(value)
    if p.is_absolute() or ".." in p.parts or "\\" in value:
        raise _fail(file, field, f"{value!r} leaves the suite folder")
    return value


def read_suite(path: str | Path) -> dict[str, Any]:
    """A suite output folder's ``summary.json`` (format ``srr-suite/1``), with what
    :func:`diff_suites` reads of it checked: its ``name``, every run's ``id``, ``group``,
    ``verdict``, ``run_dir``, ``report`` and ``digest``, and every group's ``id`` and
    ``verdict``. :class:`SrrError` (exit 2) naming the file and the field otherwise."""
    folder = Path(path)
    file = folder / SUMMARY_NAME
    if not folder.is_dir():
        raise SrrError(f"{folder}: not a suite folder (no such directory)")
    if not file.is_file():
        raise SrrError(f"{file}: missing (not a finished suite folder: srr suite writes it "
                       "last)")
    try:
        data = json.loads(file.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError, OSError, RecursionError) as err:
        raise SrrError(f"{file}: not valid JSON: {err}") from err
    if not isinstance(data, dict):
        raise SrrError(f"{file}: expected a JSON object, got {type(data).__name__}")
    if data.get("format") != FORMAT:
        raise _fail(file, "format", f"{data.get('format')!r}, expected {FORMAT!r} (not the "
                    "summary of an srr suite, or of a newer srr)")
    if not isinstance(data.get("name"), str):
        raise _fail(file, "name", f"expected a string, got {data.get('name')!r}")
    runs, groups = data.get("runs"), data.get("groups")
    if not isinstance(runs, list):
        raise _fail(file, "runs", "expected a list of runs")
    if not isinstance(groups, list):
        raise _fail(file, "groups", "expected a list of groups")
    seen: set[str] = set()
    for i, r in enumerate(runs):
        if not isinstance(r, dict):
            raise _fail(file, f"runs[{i}]", "expected an object")
        for key in ("id", "group", "verdict"):
            if not isinstance(r.get(key), str) or not r[key]:
                raise _fail(file, f"runs[{i}].{key}", f"expected a string, got "
                            f"{r.get(key)!r}")
        if r["id"] in seen:
            raise _fail(file, f"runs[{i}].id", f"{r['id']!r} is there twice")
        seen.add(r["id"])
        for key in ("run_dir", "report"):
            _inside(r.get(key), file, f"runs[{i}].{key}")
        if r.get("digest") is not None and not isinstance(r["digest"], str):
            raise _fail(file, f"runs[{i}].digest", f"expected a string or null, got "
                        f"{r['digest']!r}")
    for i, g in enumerate(groups):
        if not isinstance(g, dict) or not isinstance(g.get("id"), str) \
                or not isinstance(g.get("verdict"), str):
            raise _fail(file, f"groups[{i}]", "expected an object with a string id and "
                        "verdict")
    checked: dict[str, Any] = data
    return checked


# --------------------------------------------------------------------------- comparing


def _at(root: Path, rel: Any) -> Path | None:
    return None if rel is None else root / rel


def _recorded(run: Mapping[str, Any]) -> bool:
    """Whether the suite kept a recording of ``run``: a run directory and a digest (a run
    that ended before its first tick has no digest: the suite wrote its INVALID summary)."""
    return run.get("run_dir") is not None and run.get("digest") is not None


def _pair(ra: Mapping[str, Any], rb: Mapping[str, Any], a: Path, b: Path,
          tolerances: Sequence[Tolerance]) -> RunPair:
    has_a, has_b = _recorded(ra), _recorded(rb)
    diff = None
    recording: Recording
    if has_a and has_b:
        diff = diff_runs(a / ra["run_dir"], b / rb["run_dir"], tolerances=tolerances,
                         digests_first=True)
        recording = "differs" if not diff.equal else (
            "identical" if diff.verdict == "IDENTICAL" else "within_tolerance")
    else:
        recording = "only_in_a" if has_a else "only_in_b" if has_b else "none"
    return RunPair(str(ra["id"]), str(ra["group"]), str(ra["verdict"]), str(rb["verdict"]),
                   _at(a, ra.get("run_dir")), _at(b, rb.get("run_dir")),
                   _at(a, ra.get("report")), _at(b, rb.get("report")), diff, recording)


def _unmatched(root: Path, r: Mapping[str, Any]) -> UnmatchedRun:
    return UnmatchedRun(str(r["id"]), str(r["group"]), str(r["verdict"]),
                        _at(root, r.get("run_dir")), _at(root, r.get("report")))


def _by_line(pairs: Sequence[RunPair], lines: Callable[[RunPair], Iterable[str]]
             ) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """Each line (``lines(pair)``) once, with the ids of the pairs that have it, in the
    order first seen."""
    out: dict[str, list[str]] = {}
    for p in pairs:
        for line in lines(p):
            ids = out.setdefault(line, [])
            if p.id not in ids:
                ids.append(p.id)
    return tuple((line, tuple(ids)) for line, ids in out.items())


def _info(path: Path, s: Mapping[str, Any]) -> SuiteInfo:
    started = s.get("started_at")
    return SuiteInfo(path, str(s["name"]), str(s.get("verdict", "?")),
                     started if isinstance(started, str) else None, len(s["runs"]))


def diff_suites(a: str | Path, b: str | Path, *,
                tolerances: Sequence[Tolerance | str] = ()) -> SuiteDiff:
    """Compare suite output folder ``a`` (the reference: last night's, main's) with ``b``.

    ``tolerances``: as :func:`harness.diff.diff_runs` takes them, for every pair. Raises
    :class:`SrrError` (exit 2) for bad input: a tolerance that does not parse, a folder that
    is not a suite's, a damaged suite ``summary.json``, or a pair of runs that
    :func:`~harness.diff.diff_runs` refuses (a damaged run summary, a bag that does not read
    back where it is read)."""
    tols = tuple(t if isinstance(t, Tolerance) else parse_tolerance(t) for t in tolerances)
    pa, pb = Path(a), Path(b)
    sa, sb = read_suite(pa), read_suite(pb)
    runs_a = {str(r["id"]): r for r in sa["runs"]}
    runs_b = {str(r["id"]): r for r in sb["runs"]}
    pairs = tuple(_pair(r, runs_b[i], pa, pb, tols) for i, r in runs_a.items() if i in runs_b)
    groups_b = {str(g["id"]): str(g["verdict"]) for g in sb["groups"]}
    group_changes = tuple(GroupChange(str(g["id"]), str(g["verdict"]), groups_b[str(g["id"])])
                          for g in sa["groups"]
                          if groups_b.get(str(g["id"]), g["verdict"]) != g["verdict"])
    notes: list[str] = []
    if sa["name"] != sb["name"]:
        notes.append(f"the suites are of different suite files: {sa['name']!r} (A) and "
                     f"{sb['name']!r} (B); runs are matched by their ids all the same")
    none = [p.id for p in pairs if p.recording == "none"]
    if none:
        notes.append(f"{len(none)} run(s) recorded nothing in either suite, so only their "
                     f"verdicts are compared: {', '.join(none)}")
    matched = {t for p in pairs if p.diff for topic in p.diff.topics for t in topic.tolerances}
    notes += [f"--tolerance {t.spec!r} matches no topic of any run" for t in tols
              if t not in matched]
    # the pairs' own notes, each once with the runs it is true of (a tolerance that matches
    # nothing is said once above, of the whole suite)
    pair_notes = _by_line(pairs, lambda p: [n for n in (p.diff.notes if p.diff else ())
                                            if not n.startswith("--tolerance ")])
    notes += [f"{', '.join(ids)}: {n}" for n, ids in pair_notes]
    return SuiteDiff(_info(pa, sa), _info(pb, sb), pairs,
                     tuple(_unmatched(pa, r) for i, r in runs_a.items() if i not in runs_b),
                     tuple(_unmatched(pb, r) for i, r in runs_b.items() if i not in runs_a),
                     group_changes, _by_line(pairs, lambda p: p.diff.changes if p.diff else ()),
                     tols, tuple(notes))
