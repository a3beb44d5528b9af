"""Judging a scored run: compare its metrics with its scenario's baseline, under the same
configuration only, and decide the verdict (:func:`harness.regression.decide`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.regression import (
    baseline_path,
    compare,
    config_differences,
    decide,
    load_baseline,
    with_defaults,
)
from harness.regression.reference import reference_path
from harness.run.baselines import baseline_name, scene_config
from harness.run.summary import BaselineRef, TopicRow
from harness.scenario import Scenario
from harness.scoring import Scores

__all__ = ["Judgement", "check_baseline", "differing_topics", "differing_versions", "judge"]


@dataclass(frozen=True)
class Judgement:
    """What judging gave: the summary's ``verdict``, ``exit_code``, ``reasons``, ``baseline``
    (None when there was none to compare with) and ``comparison`` fields."""

    verdict: str
    exit_code: int
    reasons: tuple[str, ...]
    baseline: BaselineRef | None
    comparison: tuple[dict[str, Any], ...]


def differing_topics(base: Mapping[str, Mapping[str, Any]],
                     run: Mapping[str, TopicRow]) -> tuple[str, ...]:
    """Topics whose SHA-256 differs between a baseline's per-topic table and a run's, or that
    only one of them recorded, in name order."""
    return tuple(sorted(name for name in set(base) | set(run)
                        if name not in base or name not in run
                        or base[name].get("sha256") != run[name].sha256))


def differing_versions(base: Mapping[str, str],
                       run: Mapping[str, str]) -> dict[str, dict[str, str]]:
    """``{name: {"baseline": ..., "run": ...}}`` for each version both recorded that differs,
    in name order: what besides the scene may have changed the bytes (a version only one side
    recorded is unknown on the other, not different)."""
    return {name: {"baseline": str(base[name]), "run": str(run[name])}
            for name in sorted(set(base) & set(run)) if str(base[name]) != str(run[name])}


def check_baseline(scenario: Scenario, bdir: Path) -> None:
    """Read ``scenario``'s baseline in ``bdir``, if it has one, before a run: a malformed file
    is refused then (:class:`~harness.regression.BaselineError`, exit 2), before anything is
    built or recorded, rather than after the run."""
    load_baseline(baseline_path(baseline_name(scenario), bdir))


def judge(scenario: Scenario, scores: Scores, bdir: Path, *, digest: str,
          scene_files: Mapping[str, str] | None, topics: Mapping[str, TopicRow],
          versions: Mapping[str, str], blessing: bool = False) -> Judgement:
    """Compare ``scores`` with the baseline of ``scenario`` in ``bdir``; ``digest`` is the
    run's combined digest and ``scene_files`` its model files' digests (its configuration);
    ``topics`` and ``versions``, the run's, say which topics differ from the baseline's
    recording and which versions from those it was blessed with. ``blessing``: the run is
    about to become the baseline (``--update-baseline``): it is judged against the one it
    replaces, and is RECORDED when there is none yet."""
    path = baseline_path(baseline_name(scenario), bdir)
    base = load_baseline(path) if scores.metrics else None
    cmp = compare(scores.metrics, base, scenario.scoring.tolerances) if base else None
    note = (f"no baseline at {path}: bless one with `srr baseline bless RUN_DIR --reason "
            "TEXT` or `srr run ... --update-baseline`")
    if blessing:
        note = (f"no baseline at {path} before this run: it becomes the first one "
                "(--update-baseline); nothing was compared")
    elif "@" in baseline_name(scenario):  # a sweep point's own baseline
        note = (f"no baseline at {path}: bless every sweep point with `srr suite SUITE "
                "--update-baselines --reason TEXT`")
    files = scene_files if base is not None and base.config is not None \
        and "scene_files" in base.config else None  # a baseline from before srr hashed them
    mismatch = [] if base is None or base.config is None else config_differences(
        with_defaults(base.config), scene_config(scenario, files))
    if cmp is not None and mismatch:  # a baseline of another configuration judges nothing
        cmp = cmp.not_compared()
    verdict = decide(scores.health, scores.metrics, cmp, note, mismatch,
                     record_only=scenario.scoring.record_only,
                     first_baseline=blessing and base is None)
    baseline = None if base is None else BaselineRef(
        path=str(path), blessed_by=base.blessed_by, reason=base.reason,
        blessed_at=base.blessed_at, seed=base.seed, digest=base.digest,
        digest_matches=base.digest == digest, config_checked=base.config is not None,
        topics_differing=() if base.digest == digest or not base.topics
        else differing_topics(base.topics, topics),
        versions_differing=differing_versions(base.versions, versions),
        config_differences=tuple(mismatch),
        reference=str(reference_path(path)) if base.reference
        and reference_path(path).is_file() else None)
    return Judgement(verdict.name, verdict.exit_code, tuple(verdict.reasons), baseline,
                     () if cmp is None else tuple(dataclasses.asdict(e) for e in cmp.entries))
