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
from harness.errors import ScenarioError, SrrError
from harness.metrics.types import Direction
from harness.regression.reference import reference_path, write_reference
from harness.validation import validate

__all__ = ["BASELINE_VERSION", "Baseline", "BaselineError", "BaselineMetric", "baseline_path",
           "load_baseline", "same_substance", "save_baseline"]

#: The version of the baseline format srr writes (as ``format_version``) and reads. A
#: baseline without the key is version 1; one of a newer version is refused wherever a
#: baseline is read, as a summary of a newer ``schema_version`` is.
BASELINE_VERSION = 1


class BaselineError(SrrError):
    """A baseline file is unreadable or malformed."""


@dataclass(frozen=True)
class BaselineMetric:
    """One of ``metrics``: the blessed value (None: not measured), unit and which direction
    is better (``lower``, ``higher`` or ``none``)."""

    value: float | None
    unit: str
    direction: Direction


@dataclass(frozen=True, kw_only=True)
class Baseline:
    """A baseline, as its file holds it (read through :mod:`harness.validation`; keys it does
    not know are ignored, fields with a default may be left out)."""

    scenario: str
    metrics: Mapping[str, BaselineMetric]
    topics: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    digest: str = ""
    seed: int
    versions: Mapping[str, str] = field(default_factory=dict)
    blessed_by: str = ""
    reason: str = ""
    blessed_at: str = ""
    source_run: str = ""
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
    """The baseline at ``path``, or None if there is none; a malformed file, or one of a
    newer ``format_version``, raises :class:`BaselineError` naming the file and the field
    (``metrics.<name>.direction``): the one check of a baseline file, for every command."""
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise BaselineError(f"{path}: not a valid baseline: {err}") from err
    if not isinstance(data, dict):
        raise BaselineError(f"{path}: not a valid baseline: expected a JSON object, got "
                            f"{type(data).__name__}")
    try:
        base = validate(Baseline, data, str(path), unknown="ignore", yaml=False)
    except ScenarioError as err:
        raise BaselineError(f"{path}: not a valid baseline: {err.field}: {err.message}") \
            from err
    if base.format_version > BASELINE_VERSION:
        raise BaselineError(f"{path}: not a valid baseline: format_version: "
                            f"{base.format_version} is newer than this srr reads (up to "
                            f"{BASELINE_VERSION}); use a newer srr")
    return base


def who() -> str:
    """The person blessing: ``SRR_BLESSED_BY``, else the login name."""
    name = os.environ.get("SRR_BLESSED_BY")
    if name:
        return name
    try:
        return getpass.getuser()
    except (KeyError, OSError):
        return "unknown"


#: What blessing the same run again changes: who, when, why and from which run directory.
_BLESSING = ("blessed_at", "blessed_by", "reason", "source_run", "reference")


def same_substance(old: Baseline, new: Baseline) -> bool:
    """Whether two baselines hold the same scenario, seed, metrics, per-topic digests,
    versions and configuration: whether blessing ``new`` over ``old`` would change anything
    but who blessed which run when and why (the reference recording follows the digests)."""
    a, b = old.to_json(), new.to_json()
    return all(a[k] == b[k] for k in a if k not in _BLESSING)


def save_baseline(path: Path, summary: Mapping[str, Any], *, reason: str,
                  source_run: str, config: Mapping[str, Any] | None = None,
                  bag: Path | None = None, keep_unchanged: bool = False) -> Baseline | None:
    """Write a baseline from a run's ``summary.json`` content (atomically); ``config`` is the
    comparable part of the run's scenario (:func:`~harness.regression.config.comparable_config`);
    ``bag``: the run's bag, whose small topics become the reference recording next to the
    JSON (:mod:`harness.regression.reference`; without it an old reference is removed).
    With ``keep_unchanged``, a baseline already there that :func:`same_substance` finds equal
    (and whose reference recording is in place when ``bag`` is given) is left as it is, and
    None is returned: a bulk re-bless then rewrites only what changed."""
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
    ref_path = reference_path(path)
    if keep_unchanged:
        try:
            old = load_baseline(path)
        except BaselineError:  # a damaged file is replaced, as without keep_unchanged
            old = None
        if old is not None and same_substance(old, baseline) and (
                bag is None or (old.reference is not None and ref_path.is_file())):
            return None
    path.parent.mkdir(parents=True, exist_ok=True)
    if bag is not None:
        info = write_reference(bag, ref_path)
        baseline = replace(baseline, reference={"file": ref_path.name, "bytes": info.bytes,
                                                "topics": info.counts})
    else:
        ref_path.unlink(missing_ok=True)
    write_json_atomic(path, baseline.to_json())
    return baseline
