"""Baselines on disk: ``baselines/<scenario>.json``.

A baseline holds the blessed run's metric values (with unit and direction), its per-topic
counts and digests, the versions and seed it ran with, the comparable part of its scenario
(:mod:`harness.regression.config`; absent in baselines blessed before it was recorded), and
who blessed it and why.
"""

from __future__ import annotations

import getpass
import json
import os
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from harness.atomic import write_json_atomic
from harness.errors import SrrError
from harness.regression.reference import reference_path, write_reference

__all__ = ["BASELINE_VERSION", "Baseline", "BaselineError", "BaselineMetric", "baseline_path",
           "load_baseline", "save_baseline"]

BASELINE_VERSION = 1


class BaselineError(SrrError):
    """A baseline file is unreadable or malformed."""


@dataclass(frozen=True)
class BaselineMetric:
    value: float | None
    unit: str
    direction: str


@dataclass(frozen=True)
class Baseline:
    scenario: str
    metrics: Mapping[str, BaselineMetric]
    topics: Mapping[str, Mapping[str, Any]]
    digest: str
    seed: int
    versions: Mapping[str, str]
    blessed_by: str
    reason: str
    blessed_at: str
    source_run: str
    format_version: int = BASELINE_VERSION
    extra: Mapping[str, Any] = field(default_factory=dict)
    config: Mapping[str, Any] | None = None
    reference: Mapping[str, Any] | None = None  # file, bytes, per-topic counts

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["metrics"] = {k: asdict(v) for k, v in sorted(self.metrics.items())}
        data["topics"] = {k: dict(v) for k, v in sorted(self.topics.items())}
        return data


def baseline_path(scenario: str, root: Path = Path("baselines")) -> Path:
    return Path(root) / f"{scenario}.json"


def load_baseline(path: Path) -> Baseline | None:
    """The baseline at ``path``, or None if there is none; malformed files raise."""
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(data, dict):
            raise TypeError(f"expected a JSON object, got {type(data).__name__}")
        if not isinstance(data.get("metrics"), dict):
            raise TypeError("metrics: expected a mapping of metric name → value, unit, "
                            "direction")
        metrics = {k: _metric(k, v) for k, v in data["metrics"].items()}
        if not isinstance(data.get("topics", {}), dict):
            raise TypeError("topics: expected a mapping")
        if not isinstance(data.get("scenario"), str):
            raise TypeError("scenario: expected a string")
        if isinstance(data.get("seed"), bool) or not isinstance(data.get("seed"), int):
            raise TypeError(f"seed: expected an integer, got {data.get('seed')!r}")
        return Baseline(
            scenario=data["scenario"], metrics=metrics, topics=data.get("topics", {}),
            digest=data.get("digest", ""), seed=int(data["seed"]),
            versions=data.get("versions", {}), blessed_by=data.get("blessed_by", ""),
            reason=data.get("reason", ""), blessed_at=data.get("blessed_at", ""),
            source_run=data.get("source_run", ""),
            format_version=int(data.get("format_version", BASELINE_VERSION)),
            extra=data.get("extra", {}), config=_mapping(data.get("config"), "config"),
            reference=_mapping(data.get("reference"), "reference"),
        )
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise BaselineError(f"{path}: not a valid baseline: {err}") from err


def _metric(name: str, v: Any) -> BaselineMetric:
    value = v.get("value") if isinstance(v, dict) else None
    if (not isinstance(v, dict) or isinstance(value, bool)
            or not (value is None or isinstance(value, int | float))
            or not isinstance(v.get("unit"), str) or not isinstance(v.get("direction"), str)):
        raise TypeError(f"metrics.{name}: expected value (a number or null), unit and "
                        f"direction, got {v!r:.60}")
    return BaselineMetric(None if value is None else float(value), v["unit"], v["direction"])


def _mapping(value: Any, field: str) -> Mapping[str, Any] | None:
    if value is not None and not isinstance(value, dict):
        raise TypeError(f"{field}: expected a mapping, got {type(value).__name__}")
    return value


def who() -> str:
    """The person blessing: ``SRR_BLESSED_BY``, else the login name."""
    name = os.environ.get("SRR_BLESSED_BY")
    if name:
        return name
    try:
        return getpass.getuser()
    except (KeyError, OSError):
        return "unknown"


def save_baseline(path: Path, summary: Mapping[str, Any], *, reason: str,
                  source_run: str, config: Mapping[str, Any] | None = None,
                  bag: Path | None = None) -> Baseline:
    """Write a baseline from a run's ``summary.json`` content (atomically); ``config`` is the
    comparable part of the run's scenario (:func:`~harness.regression.config.comparable_config`);
    ``bag``: the run's bag, whose small topics become the reference recording next to the
    JSON (:mod:`harness.regression.reference`; without it an old reference is removed)."""
    if not reason.strip():
        raise SrrError("--reason: say why this run becomes the baseline")
    metrics = {m["name"]: BaselineMetric(m["value"], m["unit"], m["direction"])
               for m in summary.get("metrics", [])}
    topics = {name: {"count": t["count"], "sha256": t["sha256"], "type": t["type"]}
              for name, t in summary.get("topics", {}).items()}
    baseline = Baseline(
        scenario=summary["scenario"], metrics=metrics, topics=topics,
        digest=summary.get("digest", ""), seed=int(summary["seed"]),
        versions=dict(summary.get("versions", {})), blessed_by=who(), reason=reason.strip(),
        blessed_at=time.strftime("%Y-%m-%dT%H:%M:%S%z"), source_run=source_run,
        config=dict(config) if config is not None else None,
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    ref_path = reference_path(path)
    if bag is not None:
        info = write_reference(bag, ref_path)
        baseline = replace(baseline, reference={"file": ref_path.name, "bytes": info.bytes,
                                                "topics": info.counts})
    else:
        ref_path.unlink(missing_ok=True)
    write_json_atomic(path, baseline.to_json())
    return baseline
