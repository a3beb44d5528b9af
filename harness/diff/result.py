"""What ``srr diff`` finds, as frozen data: per topic, per field, per metric."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from harness.diff.tolerance import Tolerance

__all__ = [
    "DiffResult",
    "Divergence",
    "FieldDiff",
    "MetricDelta",
    "RunInfo",
    "TopicDiff",
    "TopicStatus",
    "Worst",
]

TopicStatus = Literal["identical", "within_tolerance", "differs", "only_in_a", "only_in_b"]


@dataclass(frozen=True)
class Divergence:
    """Where two topics first differ: the message ``index`` (0-based, per topic), the log
    times of that message in each run (None when it exists in one run only), the field
    ``path`` (``transforms[0].transform.translation.x``, ``data[1234]``, or ``(log time)``,
    ``(message)``, ``(type)``) and what differs there."""

    topic: str
    index: int
    stamp_a_ns: int | None
    stamp_b_ns: int | None
    path: str
    detail: str

    @property
    def t_ns(self) -> int:
        """The earlier of the two log times (the moment the runs part)."""
        stamps = [s for s in (self.stamp_a_ns, self.stamp_b_ns) if s is not None]
        return min(stamps) if stamps else 0

    def describe(self) -> str:
        def s(v: int | None) -> str:
            return "—" if v is None else f"{v / 1e9:.3f} s"

        when = (s(self.stamp_a_ns) if self.stamp_a_ns == self.stamp_b_ns
                else f"{s(self.stamp_a_ns)} (A) / {s(self.stamp_b_ns)} (B)")
        return f"{self.topic} message #{self.index} at {when}: {self.path}: {self.detail}"


@dataclass(frozen=True)
class FieldDiff:
    """Differences of one numeric field over the aligned messages whose payloads differ.

    ``values``: values compared (elements, for arrays: ``data[*]``); ``differ``: values not
    equal; ``beyond``: values outside the tolerance (all that differ when there is none);
    ``max_abs`` / ``rms``: of ``|B − A|`` over the compared values; ``at_index`` /
    ``at_ns``: message index and A's log time of the largest difference."""

    path: str
    values: int
    differ: int
    beyond: int
    max_abs: float
    rms: float
    at_index: int
    at_ns: int
    tolerance: Tolerance | None

    @property
    def within(self) -> bool:
        return self.beyond == 0


@dataclass(frozen=True)
class Worst:
    """The message pair of a topic with the most differing values (for images: pixels
    bytes), as a moment worth a look."""

    index: int
    t_ns: int
    values: int


@dataclass(frozen=True)
class TopicDiff:
    """One topic of either run. ``sha256_*`` are recomputed from the bags (log time and
    payload, as the recorder digests them); ``messages_differ`` counts aligned pairs (by
    index) whose log time or payload differ, None for a topic compared by its digest only (a
    baseline's topic its reference recording does not keep: no messages of A's to pair);
    ``first`` is the first difference of any kind,
    ``first_beyond`` the first one no tolerance covers."""

    name: str
    type_a: str | None
    type_b: str | None
    count_a: int
    count_b: int
    sha256_a: str | None
    sha256_b: str | None
    status: TopicStatus
    messages_differ: int | None
    first: Divergence | None
    first_beyond: Divergence | None
    fields: tuple[FieldDiff, ...]
    mismatches: tuple[tuple[str, int], ...]  # (path, messages) of non-numeric differences
    time_shifts: int  # aligned messages whose log times differ
    worst: Worst | None
    tolerances: tuple[Tolerance, ...]  # the options that matched this topic

    @property
    def equal(self) -> bool:
        return self.status in ("identical", "within_tolerance")

    @property
    def msgtype(self) -> str:
        return self.type_a or self.type_b or ""


@dataclass(frozen=True)
class MetricDelta:
    """A metric of both runs' ``summary.json``: ``delta = B − A``; ``status`` as the
    baseline comparison calls it with A as the baseline (``regressed``: B is worse by more
    than the tolerance; ``missing``: only A has it; ``new``: only B)."""

    name: str
    unit: str
    direction: str
    value_a: float | None
    value_b: float | None
    delta: float | None
    tolerance: float
    status: str

    @property
    def better(self) -> str:
        """``A``, ``B`` or ``""`` (same within tolerance, or no better direction)."""
        return {"improved": "B", "regressed": "A"}.get(self.status, "")


@dataclass(frozen=True)
class RunInfo:
    path: Path
    scenario: str
    seed: Any
    verdict: str
    simulated_s: float | None
    digest: str
    replay: str | None = None  # harness.summary.replay_note: what the run replays, changed

    def describe_replay(self, label: str, other: RunInfo, other_label: str) -> str | None:
        """``B is an open-loop replay of A (RUN; changed: …)`` when this run replays
        ``other`` (``… replay into external ROS 2 nodes in lockstep of A …`` for
        ``srr replay --ros2``), ``B is an open-loop replay of RUN (changed: …)`` when it
        replays another run, None when it is no replay."""
        if self.replay is None:
            return None
        kind, of, rest = self.replay.partition(f" of {other.path.resolve()} (")
        if of and kind.startswith("open-loop replay"):
            return f"{label} is an {kind} of {other_label} ({other.path.resolve()}; {rest}"
        return f"{label} is an {self.replay}"


@dataclass(frozen=True)
class DiffResult:
    """``srr diff A B``. ``equal`` (exit 0) depends on the recorded data only: the same
    topics, with the same types and counts, each identical or within tolerance. Metrics are
    shown side by side but do not decide it. ``changes``: what differs between the runs'
    inputs, A → B (resolved scenario fields, systems under test included, and versions),
    one line each; empty when A is a baseline file."""

    a: RunInfo
    b: RunInfo
    topics: tuple[TopicDiff, ...]
    metrics: tuple[MetricDelta, ...]
    tolerances: tuple[Tolerance, ...]
    notes: tuple[str, ...]
    changes: tuple[str, ...] = ()

    @property
    def equal(self) -> bool:
        return all(t.equal for t in self.topics)

    @property
    def exit_code(self) -> int:
        return 0 if self.equal else 1

    @property
    def replay_notes(self) -> tuple[str, ...]:
        """What either run replays and what the replay changed (``B is an open-loop replay
        of A (…; changed: --set …)``); empty when neither is a replay."""
        notes = (self.b.describe_replay("B", self.a, "A"),
                 self.a.describe_replay("A", self.b, "B"))
        return tuple(n for n in notes if n is not None)

    @property
    def differing(self) -> tuple[TopicDiff, ...]:
        return tuple(t for t in self.topics if not t.equal)

    @property
    def first_divergence(self) -> Divergence | None:
        """The earliest difference no tolerance covers, over every topic (ties: topic
        name)."""
        firsts = [t.first_beyond for t in self.topics if t.first_beyond is not None]
        return min(firsts, key=lambda d: (d.t_ns, d.topic)) if firsts else None

    @property
    def verdict(self) -> str:
        if not self.equal:
            return "DIFFERENT"
        if all(t.status == "identical" for t in self.topics):
            return "IDENTICAL"
        return "EQUAL_WITHIN_TOLERANCE"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (``--json``): paths as strings, non-finite numbers as strings."""
        def clean(v: Any) -> Any:
            if isinstance(v, float) and not math.isfinite(v):
                return str(v)
            if isinstance(v, Path):
                return str(v)
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            if isinstance(v, (list, tuple)):
                return [clean(x) for x in v]
            return v

        out = clean(dataclasses.asdict(self))
        first = self.first_divergence
        out.update(verdict=self.verdict, equal=self.equal, exit_code=self.exit_code,
                   first_divergence=None if first is None else clean(dataclasses.asdict(first)))
        return dict(out)
