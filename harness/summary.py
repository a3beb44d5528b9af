"""Reading a run directory's ``summary.json`` back, checked field by field (the typed summary
that every writer builds, and that reads these checked fields, is
:class:`harness.run.summary.RunSummary`).

Every command that reads a run directory (``report``, ``replay``, ``baseline bless``, ``diff``)
goes through :func:`read_summary`: a missing, unparsable or mis-typed summary is one
:class:`~harness.errors.SrrError` line naming the file and the field (exit 2), never a
traceback deeper in.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from harness import runmarker
from harness.errors import SrrError
from harness.validation import validate

#: The version of the summary format srr writes (as ``schema_version``) and reads. A summary
#: without the key, as srr wrote them before, is version 1; a summary of a version newer than
#: this one is refused wherever a summary is read.
SCHEMA_VERSION = 1

__all__ = [
    "SCHEMA_VERSION",
    "SUITE_FORMAT",
    "SUMMARY_NAME",
    "BaselineEntry",
    "ComparisonRow",
    "HealthRow",
    "MetricRow",
    "SummaryFile",
    "SutEndpoints",
    "TopicDigest",
    "VersionPair",
    "check_summary",
    "fail",
    "is_suite_summary",
    "read_summary",
    "recording_note",
    "replay_note",
    "versions_note",
]

SUMMARY_NAME = "summary.json"
#: The ``format`` of the ``summary.json`` that ``srr suite`` writes in its output folder.
SUITE_FORMAT = "srr-suite/1"

#: What a missing required key says: the file is not an srr run summary at all.
_MISSING = "missing (not an srr run summary)"


@dataclass(frozen=True)
class MetricRow:
    """One of ``metrics``: the metric's name, value (None: not measured), unit and which
    direction is better (further keys are not checked)."""

    name: str
    value: float | None
    unit: str
    direction: Literal["lower", "higher", "none"]


@dataclass(frozen=True)
class HealthRow:
    """One of ``health``: a health gate, whether it held, and why."""

    name: str
    ok: bool
    detail: str


@dataclass(frozen=True)
class TopicDigest:
    """One of ``topics``: a recorded topic's message count, combined SHA-256 and type."""

    count: int
    sha256: str
    type: str


@dataclass(frozen=True)
class ComparisonRow:
    """One of ``comparison``: a metric against the baseline's value, with its tolerance and
    status (further keys are not checked)."""

    name: str
    status: str
    value: float | None = None
    baseline: float | None = None
    delta: float | None = None
    tolerance: float | None = None
    unit: str = ""
    direction: str = ""


@dataclass(frozen=True)
class SutEndpoints:
    """One of ``sut_endpoints``: a system under test's plug-in and the topics it publishes and
    subscribes (what a replay withholds and feeds)."""

    plugin: str = ""
    publishes: tuple[str, ...] = ()
    subscribes: tuple[str, ...] = ()


@dataclass(frozen=True)
class VersionPair:
    """One of ``baseline.versions_differing``: the version the baseline was blessed with and
    the run's."""

    baseline: str
    run: str


@dataclass(frozen=True)
class BaselineEntry:
    """``baseline``: the baseline a run was judged against, as readers use it (every field
    may be missing from a summary of an earlier srr)."""

    path: str = ""
    blessed_by: str = ""
    reason: str = ""
    blessed_at: str = ""
    seed: int | None = None
    digest: str = ""
    digest_matches: bool = False
    config_checked: bool = False
    config_differences: tuple[str, ...] = ()
    reference: str | None = None
    topics_differing: tuple[str, ...] = ()
    versions_differing: dict[str, VersionPair] = field(default_factory=dict)


@dataclass(frozen=True)
class SummaryFile:
    """What every reader of ``summary.json`` relies on; keys not named here are not checked
    (:class:`harness.run.summary.RunSummary` reads the whole summary)."""

    scenario: str
    verdict: str
    seed: int
    digest: str
    metrics: tuple[MetricRow, ...]
    health: tuple[HealthRow, ...]
    topics: dict[str, TopicDigest]
    ticks: int = 0
    duration_s: float = 0.0
    simulated_s: float = 0.0
    srr_gt: bool = False
    scenario_file: str = ""
    baselines_dir: str = ""
    sut_endpoints: dict[str, SutEndpoints] | None = None
    replay_of: dict[str, Any] = field(default_factory=dict)
    comparison: tuple[ComparisonRow, ...] = ()
    baseline: BaselineEntry | None = None
    interrupted: bool = False
    reasons: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    systems_under_test: tuple[str, ...] = ()
    graphs: tuple[str, ...] = ()
    versions: dict[str, str] = field(default_factory=dict)
    scene_files: dict[str, str] | None = None
    exit_code: int = 3
    schema_version: int = SCHEMA_VERSION


def replay_note(summary: Mapping[str, Any]) -> str | None:
    """``open-loop replay of RUN (changed: --set X=Y, --sut NAME=module:Class)``, or None
    when the summary is not a replay's (its ``replay_of``): what the console, the report
    and ``srr diff`` say of a replay."""
    r = summary.get("replay_of")
    if not isinstance(r, Mapping):
        return None
    replaced: Mapping[str, Any] = r["replaced"] if isinstance(r.get("replaced"), Mapping) else {}
    overrides: list[Any] = r["overrides"] if isinstance(r.get("overrides"), list) else []
    changes = [f"--set {o}" for o in overrides] + [f"--sut {k}={v}" for k, v in replaced.items()]
    what = (f"changed: {', '.join(changes)}" if changes else
            "nothing changed: the recorded systems under test and settings")
    into = " into external ROS 2 nodes in lockstep" if r.get("mode") == "ros2-lockstep" else ""
    return f"open-loop replay{into} of {r.get('run_dir', '?')} ({what})"


def recording_note(summary: Mapping[str, Any], *, most: int = 4) -> str | None:
    """``recording identical to the baseline's``, or ``recording differs from the baseline's
    in 2 of 16 topics (/a, /b); versions differ: numpy 2.4.6 → 2.5.2``, or None without a
    baseline: what the console, the report and the Markdown summary say of the bytes (the
    metrics are judged on their own, within their tolerances). At most ``most`` names."""
    b = summary.get("baseline")
    if not isinstance(b, Mapping):
        return None
    if b.get("digest_matches"):
        return "recording identical to the baseline's"
    if summary.get("interrupted"):  # which topics differ says nothing of a run cut short
        return "recording cut short (interrupted): not the baseline's"
    if summary.get("stopped"):  # a gate (a plug-in's error, the disk) ended it early
        return "recording cut short (the run was stopped): not the baseline's"
    note = "recording differs from the baseline's"
    topics = [str(t) for t in b.get("topics_differing") or ()]
    if topics:
        shown = ", ".join(topics[:most]) + (", …" if len(topics) > most else "")
        # of the topics either side recorded: one only the baseline has differs too
        both = set(summary.get("topics") or ()) | set(topics)
        total = f" of {len(both)}" if summary.get("topics") else ""
        note += f" in {len(topics)}{total} topics ({shown})"
    versions = versions_note(b)
    if versions:
        note += f"; versions differ: {versions}"
    return note


def versions_note(baseline: Mapping[str, Any]) -> str:
    """``numpy 2.4.6 → 2.5.2, python 3.11.7 → 3.12.3`` from a summary's ``baseline`` entry
    (its ``versions_differing``: the baseline's, then the run's); empty when none differ."""
    versions = baseline.get("versions_differing")
    if not isinstance(versions, Mapping):
        return ""
    return ", ".join(f"{name} {v.get('baseline') or '—'} → {v.get('run') or '—'}"
                     for name, v in versions.items() if isinstance(v, Mapping))


def fail(path: Path, field: str, message: str) -> SrrError:
    return SrrError(f"{path}: {field}: {message}")


def read_summary(run_dir: str | Path) -> dict[str, Any]:
    """The run's ``summary.json``, its fields checked; :class:`SrrError` (exit 2) when the
    directory is not a finished run directory or the summary is malformed."""
    run = Path(run_dir)
    path = run / SUMMARY_NAME
    if not run.is_dir():
        raise SrrError(f"{run}: not a run directory (no such directory)")
    if not path.is_file():
        marker = runmarker.read(run)
        if marker is not None:
            raise SrrError(f"{path}: missing: the run did not finish (killed while "
                           f"{runmarker.killed_while(marker)}); `srr recover {run}` makes it "
                           "a finished run directory")
        if (run.parent / SUMMARY_NAME).is_file() and (run.parent / "bag") == run:
            raise SrrError(f"{path}: missing: {run} is the bag of the run directory "
                           f"{run.parent}: give that")
        raise SrrError(f"{path}: missing (not a finished run directory)")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError, OSError) as err:
        raise SrrError(f"{path}: not valid JSON: {err}") from err
    check_summary(data, path)
    checked: dict[str, Any] = data
    return checked


def is_suite_summary(data: Any) -> bool:
    """Whether ``data`` (a parsed ``summary.json``) is a suite's, not a run's: its ``format``
    says so, or (a summary from before the format was written) it has lists of ``runs``
    and ``groups`` and no ``scenario``."""
    return isinstance(data, dict) and (data.get("format") == SUITE_FORMAT or (
        "scenario" not in data and isinstance(data.get("runs"), list)
        and isinstance(data.get("groups"), list)))


def check_summary(data: Any, path: Path) -> None:
    """:class:`SrrError` naming ``path`` and the field when ``data`` is not a run summary
    (read as :class:`SummaryFile`) or is of a newer ``schema_version``: the one check of a
    summary, for every command and for :meth:`harness.run.summary.RunSummary.from_json`."""
    if not isinstance(data, dict):
        raise SrrError(f"{path}: expected a JSON object, got {type(data).__name__}")
    if is_suite_summary(data):
        raise SrrError(f"{path}: the summary of a suite, not of a run: the suite's page is "
                       f"{Path(path).parent / 'index.html'}, and each run's directory is "
                       "under its runs/ (srr report RUN_DIR renders one)")
    validate(SummaryFile, data, str(path), unknown="ignore", missing=_MISSING, yaml=False)
    version = data.get("schema_version", 1)
    if isinstance(version, int) and version > SCHEMA_VERSION:  # (its type: checked above)
        raise fail(path, "schema_version", f"{version} is newer than this srr reads "
                   f"(up to {SCHEMA_VERSION}); use a newer srr")
