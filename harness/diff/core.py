"""``diff_runs``: two run directories compared — recorded data topic by topic, metrics side by
side. Run A may be a baseline file instead (``baselines/<name>.json``): its reference
recording stands for A's bag, and the topics the reference does not keep (images, the dynamic
``/tf``) are compared by the per-topic digests the baseline holds.

The outcome (:attr:`DiffResult.equal`, exit 0 or 1) depends on the recorded data only: both
runs record the same topics with the same types and message counts, and every topic is
byte-identical (log times and payloads) or differs only in numeric fields within the
``--tolerance`` options. Metric values are compared (with run A as the baseline and the
tolerances of A's scenario) and shown, but they do not decide: two recordings that are equal
score equally, and the point of ``diff`` is to say where the data part.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Mapping, Sequence
from pathlib import Path
from typing import Any

from harness.diff.metrics import metric_deltas, summary_metrics
from harness.diff.result import DiffResult, RunInfo, TopicDiff
from harness.diff.tolerance import Tolerance, glob_match, parse_tolerance
from harness.diff.topics import diff_bags
from harness.errors import SrrError
from harness.recording.bagread import ros1_recording
from harness.recording.verify import check_read_back
from harness.scenario.schema import ToleranceSpec
from harness.summary import replay_note

__all__ = ["check_against_summary", "check_bag", "diff_runs", "is_baseline_file",
           "open_baseline", "open_run"]


def is_baseline_file(path: Path) -> bool:
    """Whether ``srr diff`` reads ``path`` as a baseline file (``baselines/<name>.json``)
    rather than a run directory (a run's own ``summary.json`` is neither: see
    :func:`diff_runs`)."""
    return path.suffix == ".json" and not path.is_dir() and not _run_summary(path)


def _run_summary(path: Path) -> bool:
    """``path`` is the ``summary.json`` of a run directory (one with its ``bag/``)."""
    return path.name == "summary.json" and (path.parent / "bag").is_dir()


def open_run(path: Path, *, bag_needed: bool = True) -> tuple[dict[str, Any], Path]:
    """(summary, bag directory) of a run directory; :class:`SrrError` (exit 2) naming what is
    missing or malformed. ``bag_needed=False``: the bag directory is not looked at (a caller
    that may compare the summaries' digests only checks it with :func:`check_bag` when it
    reads the bag)."""
    from harness.summary import read_summary

    summary = read_summary(path)
    topics = summary.get("topics", {})
    if not isinstance(topics, dict) or not all(isinstance(v, dict) for v in topics.values()):
        raise SrrError(f"{path / 'summary.json'}: topics: expected a mapping of topic → "
                       "{count, sha256, ...}")
    bag = path / "bag"
    if bag_needed:
        check_bag(bag)
    return summary, bag


def check_bag(bag: Path) -> None:
    """:class:`SrrError` (exit 2) when a run's ``bag/`` is missing or holds no recording."""
    if not bag.is_dir():
        raise SrrError(f"{bag}: missing (a run directory holds its recording in bag/)")
    if not (bag / "metadata.yaml").is_file() and ros1_recording(bag) is None:
        raise SrrError(f"{bag / 'metadata.yaml'}: missing (not a rosbag2 directory)")


def open_baseline(path: Path) -> tuple[dict[str, Any], Path, frozenset[str]]:
    """(a summary-like mapping, the reference recording, the topics it keeps) of a baseline
    file; :class:`SrrError` (exit 2) when it is malformed or has no reference recording."""
    from harness.regression import load_baseline
    from harness.regression.reference import reference_path

    base = load_baseline(path)
    if base is None:
        raise SrrError(f"{path}: no such baseline file")
    ref = reference_path(path)
    if base.reference is None or not ref.is_file():
        raise SrrError(f"{ref}: missing: this baseline has no reference recording to compare "
                       "messages with (bless it again: `srr baseline bless RUN_DIR`)")
    duration = (base.config or {}).get("duration")
    summary = {"scenario": base.scenario, "seed": base.seed, "verdict": "baseline",
               "simulated_s": duration, "digest": base.digest,
               "topics": {k: dict(v) for k, v in base.topics.items()},
               "metrics": [{"name": n, "value": m.value, "unit": m.unit,
                            "direction": m.direction} for n, m in base.metrics.items()]}
    kept = base.reference.get("topics")
    return summary, ref, frozenset(kept if isinstance(kept, Mapping) else ())


def _by_digest(topics: Sequence[TopicDiff], recorded: Mapping[str, Any],
               kept: frozenset[str]) -> tuple[TopicDiff, ...]:
    """A baseline's topics that its reference recording leaves out, compared by the digest
    and count the baseline holds: identical, or differs (no message to point at, no messages
    counted: ``messages_differ`` is None)."""
    out = {t.name: t for t in topics}
    for name, entry in recorded.items():
        if name in kept:
            continue
        t = out.get(name)
        sha, count = str(entry.get("sha256")), int(entry.get("count") or 0)
        if t is None:  # in the baseline, not in the run
            out[name] = TopicDiff(
                name=name, type_a=str(entry.get("type")), type_b=None, count_a=count,
                count_b=0, sha256_a=sha, sha256_b=None, status="only_in_a", messages_differ=None,
                first=None, first_beyond=None, fields=(), mismatches=(), time_shifts=0,
                worst=None, tolerances=())
            continue
        same = t.sha256_b == sha and t.count_b == count
        out[name] = dataclasses.replace(  # no messages of A's to pair: no divergence to show
            t, type_a=str(entry.get("type")), count_a=count, sha256_a=sha,
            status="identical" if same else "differs", messages_differ=None, first=None,
            first_beyond=None, fields=(), mismatches=(), time_shifts=0, worst=None)
    return tuple(out[n] for n in sorted(out))


def _same_in_summaries(sa: Mapping[str, Any], sb: Mapping[str, Any]) -> frozenset[str]:
    """The topics both summaries record with the same type, message count and SHA-256 (over
    log times and payloads): identical, whatever their messages are."""
    ta, tb = sa.get("topics") or {}, sb.get("topics") or {}
    return frozenset(n for n, ea in ta.items() if (eb := tb.get(n)) is not None
                     and isinstance(ea.get("sha256"), str) and ea.get("sha256")
                     and (ea.get("sha256"), ea.get("count"), ea.get("type"))
                     == (eb.get("sha256"), eb.get("count"), eb.get("type")))


def _identical(name: str, entry: Mapping[str, Any], tolerances: Sequence[Tolerance]
               ) -> TopicDiff:
    """A topic both runs' summaries record alike, as :func:`diff_bags` would give it."""
    count, sha = int(entry.get("count") or 0), str(entry.get("sha256"))
    return TopicDiff(name=name, type_a=str(entry.get("type")), type_b=str(entry.get("type")),
                     count_a=count, count_b=count, sha256_a=sha, sha256_b=sha,
                     status="identical", messages_differ=0, first=None, first_beyond=None,
                     fields=(), mismatches=(), time_shifts=0, worst=None,
                     tolerances=tuple(t for t in tolerances if glob_match(name, t.topic)))


def _info(path: Path, s: Mapping[str, Any]) -> RunInfo:
    sim = s.get("simulated_s")
    return RunInfo(path, str(s.get("scenario", "?")), s.get("seed"), str(s.get("verdict", "?")),
                   float(sim) if isinstance(sim, (int, float)) else None,
                   str(s.get("digest", "")), replay_note(s))


def _resolved(run: Path) -> dict[str, Any] | None:
    """The run's resolved scenario (``scenario.yaml``) as a mapping with every default; None
    when it is missing or does not load (the metric tolerances' note says so)."""
    from harness.scenario import load_scenario, scenario_to_mapping

    file = run / "scenario.yaml"
    if not file.is_file():
        return None
    try:
        return scenario_to_mapping(load_scenario(file))
    except SrrError:
        return None


def _changes(a: Path, b: Path, sa: Mapping[str, Any], sb: Mapping[str, Any]) -> tuple[str, ...]:
    """What differs between two runs' inputs, A → B: every resolved scenario field (the
    systems under test too), then the versions both recorded (srr, Python, MuJoCo, the
    OpenGL renderer, ...) in one line."""
    from harness.regression import scenario_differences

    out: list[str] = []
    ma, mb = _resolved(a), _resolved(b)
    if ma is not None and mb is not None:
        out += scenario_differences(ma, mb)
    va, vb = sa.get("versions"), sb.get("versions")
    if isinstance(va, Mapping) and isinstance(vb, Mapping):
        moved = [f"{k} {va[k]} → {vb[k]}" for k in sorted(set(va) & set(vb))
                 if str(va[k]) != str(vb[k])]
        if moved:
            out.append("versions: " + ", ".join(moved))
    return tuple(out)


def _count_only(topics: Sequence[TopicDiff], a: RunInfo, b: RunInfo) -> str | None:
    """A note when topics differ only in how many messages they have (one run is longer, or
    was cut short): their status says ``differs`` with no message that differs."""
    only = [t.name for t in topics if t.status == "differs" and t.messages_differ == 0
            and t.first_beyond is not None and t.first_beyond.path == "(message)"]
    if not only:
        return None
    shown = ", ".join(only[:4]) + (", …" if len(only) > 4 else "")
    lengths = ""
    if a.simulated_s is not None and b.simulated_s is not None \
            and a.simulated_s != b.simulated_s:
        lengths = (f"; A has {a.simulated_s:g} s of simulated time, "
                   f"B {b.simulated_s:g} s")
    return (f"{len(only)} topic(s) differ only in how many messages they have ({shown}): "
            f"the messages both runs recorded are identical{lengths}")


def _scenario_tolerances(run: Path) -> tuple[dict[str, ToleranceSpec], str | None]:
    from harness.scenario import load_scenario

    file = run / "scenario.yaml"
    if not file.is_file():
        return {}, f"{file}: missing; metric tolerances are the defaults per unit"
    try:
        return dict(load_scenario(file).scoring.tolerances), None
    except SrrError as err:
        return {}, f"{file} does not load ({err}); metric tolerances are the defaults per unit"


def check_against_summary(bag: Path, summary: Mapping[str, Any], topics: Sequence[TopicDiff],
                          side: int, skipped: Collection[str] = ()) -> str | None:
    """Raise :class:`BagError` when the bag read back is not what ``summary.json`` recorded
    (per topic count and SHA-256 over log time and payload): a truncated or damaged MCAP can
    still parse. Returns a note when the summary has no digests to check against.
    ``skipped``: topics that were not read back (not checked)."""
    recorded = summary.get("topics") or {}
    if not recorded:
        return f"{bag.parent / 'summary.json'}: no per-topic digests; the bag is not checked"
    read = {t.name: (t.count_a, t.sha256_a) if side == 0 else (t.count_b, t.sha256_b)
            for t in topics if t.name not in skipped}
    check_read_back(bag, {k: v for k, v in recorded.items() if k not in skipped},
                    {k: (c or 0, sha) for k, (c, sha) in read.items()})
    return None


def diff_runs(a: str | Path, b: str | Path, *,
              tolerances: Sequence[Tolerance | str] = (),
              digests_first: bool = False) -> DiffResult:
    """Compare run directory ``a`` (the baseline) with ``b`` (the candidate).

    ``tolerances``: :class:`Tolerance` objects or ``--tolerance`` strings
    (``TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]``). Raises :class:`SrrError` (exit 2) for bad
    input: a tolerance that does not parse, a directory that is not a run, a malformed
    ``summary.json``, a bag that does not read back or does not match its summary.

    ``digests_first`` (what ``srr diff SUITE_A SUITE_B`` does for each pair of runs): a topic
    both summaries record with the same type, count and SHA-256 is identical without its
    messages being read, and the bags are read (and checked against their summaries) for the
    other topics only — not opened at all when there are none. The summaries are trusted:
    a bag damaged since its run is not noticed where the digests agree."""
    tols = tuple(t if isinstance(t, Tolerance) else parse_tolerance(t) for t in tolerances)
    pa, pb = Path(a), Path(b)
    kept: frozenset[str] | None = None  # A is a baseline: the topics its reference keeps
    for p in (pa, pb):
        if _run_summary(p):
            raise SrrError(f"{p}: the summary of the run {p.parent}: give the run directory "
                           f"(srr diff {pa.parent if p is pa else pa} "
                           f"{pb.parent if p is pb else pb})")
    if is_baseline_file(pa):
        sa, bag_a, kept = open_baseline(pa)
    else:
        sa, bag_a = open_run(pa, bag_needed=not digests_first)
    if is_baseline_file(pb):
        raise SrrError(f"{pb}: a baseline file can only be A, the reference: give it first "
                       f"(srr diff {pb} RUN_DIR)")
    sb, bag_b = open_run(pb, bag_needed=not digests_first)
    ma = summary_metrics(sa)
    mb = summary_metrics(sb)
    same = _same_in_summaries(sa, sb) if digests_first and kept is None else frozenset()
    read = not same or not same >= set(sa.get("topics") or ()) | set(sb.get("topics") or ())
    topics: tuple[TopicDiff, ...] = ()
    if read:
        if digests_first:  # (a baseline's reference recording was found when it was opened)
            if kept is None:
                check_bag(bag_a)
            check_bag(bag_b)
        topics = diff_bags(bag_a, bag_b, tols, skip=same)
    if same:
        alike = (_identical(n, sa["topics"][n], tols) for n in same)
        topics = tuple(sorted((*topics, *alike), key=lambda t: t.name))
    notes: list[str] = []
    if kept is not None:
        recorded = sa["topics"]
        topics = _by_digest(topics, recorded, kept)
        sa = dict(sa, topics={k: v for k, v in recorded.items() if k in kept})
        notes.append(f"A is the baseline {pa}: its reference recording keeps {len(kept)} of "
                     f"its {len(recorded)} topics; the others are compared by their digests "
                     "only (no messages counted: — in the differ column)")
    for t in tols:
        if not any(glob_match(td.name, t.topic) for td in topics):
            notes.append(f"--tolerance {t.spec!r} matches no topic of either run")
    read_back = topics if kept is None else tuple(t for t in topics if t.name in kept)
    for side, (s, bag) in enumerate(((sa, bag_a), (sb, bag_b)) if read else ()):
        note = check_against_summary(bag, s, read_back if side == 0 else topics, side, same)
        if note:
            notes.append(note)
    if sa.get("scenario") != sb.get("scenario"):
        notes.append(f"the runs are of different scenarios: {sa.get('scenario')!r} (A) and "
                     f"{sb.get('scenario')!r} (B)")
    info_a, info_b = _info(pa, sa), _info(pb, sb)
    count_only = _count_only(topics, info_a, info_b)
    if count_only:
        notes.append(count_only)
    metric_tols, problem = _scenario_tolerances(pb if kept is not None else pa)
    if problem and (ma or mb):
        notes.append(problem)
    changes = () if kept is not None else _changes(pa, pb, sa, sb)
    return DiffResult(info_a, info_b, topics, metric_deltas(ma, mb, metric_tols),
                      tols, tuple(notes), changes)
