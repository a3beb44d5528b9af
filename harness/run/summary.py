"""The typed run summary: :class:`RunSummary` is what every writer of a run directory's
``summary.json`` builds (a run and a replay, :mod:`harness.run.record`; ``srr recover``; a run
a suite settled) and writes, and what reads one back, checked by
:func:`harness.summary.check_summary`."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from harness.atomic import write_json_atomic
from harness.metrics.types import HealthResult
from harness.summary import (
    SCHEMA_VERSION,
    SUMMARY_NAME,
    check_summary,
    read_summary,
)

__all__ = ["SCHEMA_VERSION", "BaselineRef", "RunSummary", "TopicRow"]


@dataclass(frozen=True)
class TopicRow:
    """One recorded topic: its type, messages recorded and published (None: unknown, the run
    did not finish), rate over the simulated time, bytes, combined SHA-256 and durability."""

    type: str
    count: int
    sha256: str
    published: int | None = None
    rate_hz: float | None = None
    bytes: int | None = None
    durability: str | None = None

    def to_json(self) -> dict[str, Any]:
        return {"type": self.type, "count": self.count, "published": self.published,
                "rate_hz": self.rate_hz, "bytes": self.bytes, "sha256": self.sha256,
                "durability": self.durability}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> TopicRow:
        return cls(type=data["type"], count=data["count"], sha256=data["sha256"],
                   published=data.get("published"), rate_hz=data.get("rate_hz"),
                   bytes=data.get("bytes"), durability=data.get("durability"))


@dataclass(frozen=True)
class BaselineRef:
    """The baseline a run was judged against: where it is, who blessed it when and why, its
    seed and digest (and whether the run's digest matches), whether its configuration was
    checked and how it differs, and its reference recording (None without one)."""

    path: str
    blessed_by: str
    reason: str
    blessed_at: str
    seed: int | None
    digest: str
    digest_matches: bool
    config_checked: bool = False
    config_differences: tuple[str, ...] = ()
    reference: str | None = None
    # topics whose digest differs from the baseline's, or that only one side recorded
    topics_differing: tuple[str, ...] = ()
    # each version both sides recorded that differs: {"baseline": ..., "run": ...}
    versions_differing: Mapping[str, Mapping[str, str]] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "path": self.path, "blessed_by": self.blessed_by, "reason": self.reason,
            "blessed_at": self.blessed_at, "seed": self.seed, "digest": self.digest,
            "digest_matches": self.digest_matches, "config_checked": self.config_checked,
            "config_differences": list(self.config_differences), "reference": self.reference}
        # written only when there is something to say (a summary of an earlier srr, which
        # had neither, reads and writes back unchanged)
        if self.topics_differing:
            out["topics_differing"] = list(self.topics_differing)
        if self.versions_differing:
            out["versions_differing"] = {k: dict(v) for k, v in self.versions_differing.items()}
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> BaselineRef:
        return cls(path=str(data.get("path", "")), blessed_by=str(data.get("blessed_by", "")),
                   reason=str(data.get("reason", "")),
                   blessed_at=str(data.get("blessed_at", "")), seed=data.get("seed"),
                   digest=str(data.get("digest", "")),
                   digest_matches=bool(data.get("digest_matches")),
                   config_checked=bool(data.get("config_checked")),
                   config_differences=tuple(data.get("config_differences") or ()),
                   reference=data.get("reference"),
                   topics_differing=tuple(data.get("topics_differing") or ()),
                   versions_differing={
                       str(name): {"baseline": str(v.get("baseline", "")),
                                   "run": str(v.get("run", ""))}
                       for name, v in (data.get("versions_differing") or {}).items()})


def _json_shaped(value: Any) -> Any:
    """``value`` as JSON holds it: every tuple a list, every mapping a dict (recursively)."""
    if isinstance(value, Mapping):
        return {k: _json_shaped(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_shaped(v) for v in value]
    return value


@dataclass(frozen=True)
class RunSummary:
    """A run's ``summary.json``, typed: what ran (scenario, seed, simulated time), how it
    ended (``interrupted``, ``stopped``; ``recovered`` by ``srr recover``), its health gates,
    metrics and recorded topics, and the verdict with its reasons and the baseline it was
    compared with. Optional parts are None (or False) when a run has none, and are then not
    written. :meth:`to_json` gives the mapping ``summary.json`` holds, in srr's key order;
    :meth:`from_json` reads one back, including summaries from earlier srr versions (keys it
    does not know are kept in ``more`` and written back after the others)."""

    schema_version: ClassVar[int] = SCHEMA_VERSION

    scenario: str
    scenario_file: str
    seed: int
    srr_gt: bool
    duration_s: float
    simulated_s: float
    ticks: int
    tick_hz: int
    interrupted: bool
    health: tuple[HealthResult, ...]
    metrics: tuple[Mapping[str, Any], ...]
    topics: Mapping[str, TopicRow]
    digest: str
    versions: Mapping[str, str]
    verdict: str
    exit_code: int
    reasons: tuple[str, ...] = ()
    stopped: str | None = None
    recovered: bool = False
    recovery: Mapping[str, Any] | None = None
    warnings: tuple[str, ...] = ()
    graphs: tuple[Any, ...] = ()
    systems_under_test: tuple[str, ...] = ()
    sut_endpoints: Mapping[str, Any] | None = None
    output: Mapping[str, Any] | None = None
    scene_files: Mapping[str, str] | None = None
    command: str | None = None
    replay_of: Mapping[str, Any] | None = None
    world_map: Any = None
    unrecorded: Mapping[str, Any] | None = None
    baselines_dir: str | None = None
    baseline: BaselineRef | None = None
    comparison: tuple[Mapping[str, Any], ...] = ()
    more: Mapping[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Every health gate held."""
        return all(h.ok for h in self.health)

    def to_json(self) -> dict[str, Any]:
        """The mapping ``summary.json`` holds (written with sorted keys), ``schema_version``
        included: JSON-shaped (lists, not tuples; dicts, not other mappings), so that it
        equals what ``json.load`` reads back from the file (a metric's ``windows`` were
        tuples in memory and lists on disk)."""
        out: dict[str, Any] = {
            "schema_version": SCHEMA_VERSION, "scenario": self.scenario,
            "scenario_file": self.scenario_file, "seed": self.seed,
            "srr_gt": self.srr_gt, "duration_s": self.duration_s,
            "simulated_s": self.simulated_s, "ticks": self.ticks, "tick_hz": self.tick_hz,
            "interrupted": self.interrupted}
        if self.recovered:
            out["recovered"] = True
        if self.recovery is not None:
            out["recovery"] = dict(self.recovery)
        out |= {"stopped": self.stopped, "warnings": list(self.warnings),
                "health": [dataclasses.asdict(h) for h in self.health],
                "metrics": [dict(m) for m in self.metrics], "graphs": list(self.graphs),
                "systems_under_test": list(self.systems_under_test)}
        for key in ("sut_endpoints", "output"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        out |= {"topics": {n: t.to_json() for n, t in self.topics.items()},
                "digest": self.digest, "versions": dict(self.versions)}
        for key in ("scene_files", "command", "replay_of", "world_map", "unrecorded",
                    "baselines_dir"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        out |= {"verdict": self.verdict, "exit_code": self.exit_code,
                "reasons": list(self.reasons),
                "baseline": None if self.baseline is None else self.baseline.to_json(),
                "comparison": [dict(c) for c in self.comparison]}
        plain: dict[str, Any] = _json_shaped(out | dict(self.more))
        return plain

    @classmethod
    def from_json(cls, data: Mapping[str, Any], path: Path | str = SUMMARY_NAME) -> RunSummary:
        """A summary from its mapping, checked as :func:`read_summary` checks it (``path``
        names it in errors): :class:`SrrError` when malformed or of a newer version."""
        where = Path(path)
        check_summary(data, where)
        known = {f.name for f in dataclasses.fields(cls)} | {"schema_version"}
        baseline = data.get("baseline")
        return cls(
            scenario=data["scenario"], scenario_file=str(data.get("scenario_file", "")),
            seed=data["seed"], srr_gt=bool(data.get("srr_gt", False)),
            duration_s=data.get("duration_s", 0.0), simulated_s=data.get("simulated_s", 0.0),
            ticks=data.get("ticks", 0), tick_hz=data.get("tick_hz", 0),
            interrupted=bool(data.get("interrupted", False)),
            health=tuple(HealthResult(h["name"], h["ok"], h["detail"]) for h in data["health"]),
            metrics=tuple(data["metrics"]),
            topics={n: TopicRow.from_json(t) for n, t in data["topics"].items()},
            digest=data["digest"], versions=dict(data.get("versions", {})),
            verdict=data["verdict"], exit_code=data.get("exit_code", 3),
            reasons=tuple(str(r) for r in data.get("reasons", [])),
            stopped=data.get("stopped"), recovered=bool(data.get("recovered", False)),
            recovery=data.get("recovery"), warnings=tuple(data.get("warnings", [])),
            graphs=tuple(data.get("graphs", [])),
            systems_under_test=tuple(data.get("systems_under_test", [])),
            sut_endpoints=data.get("sut_endpoints"), output=data.get("output"),
            scene_files=data.get("scene_files"), command=data.get("command"),
            replay_of=data.get("replay_of"), world_map=data.get("world_map"),
            unrecorded=data.get("unrecorded"), baselines_dir=data.get("baselines_dir"),
            baseline=None if baseline is None else BaselineRef.from_json(baseline),
            comparison=tuple(data.get("comparison", [])),
            more={k: v for k, v in data.items() if k not in known})

    @classmethod
    def read(cls, run_dir: str | Path) -> RunSummary:
        """The summary of the finished run directory ``run_dir`` (:func:`read_summary`)."""
        return cls.from_json(read_summary(run_dir), Path(run_dir) / SUMMARY_NAME)

    def write(self, run_dir: str | Path) -> Path:
        """Write ``run_dir``'s ``summary.json`` atomically: the run is complete from here."""
        path = Path(run_dir) / SUMMARY_NAME
        write_json_atomic(path, self.to_json())
        return path
