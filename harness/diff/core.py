"""``diff_runs``: two run directories compared — recorded data topic by topic, metrics side by
side.

The outcome (:attr:`DiffResult.equal`, exit 0 or 1) depends on the recorded data only: both
runs record the same topics with the same types and message counts, and every topic is
byte-identical (log times and payloads) or differs only in numeric fields within the
``--tolerance`` options. Metric values are compared (with run A as the baseline and the
tolerances of A's scenario) and shown, but they do not decide: two recordings that are equal
score equally, and the point of ``diff`` is to say where the data part.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from harness.diff.metrics import metric_deltas, summary_metrics
from harness.diff.result import DiffResult, RunInfo, TopicDiff
from harness.diff.tolerance import Tolerance, glob_match, parse_tolerance
from harness.diff.topics import diff_bags
from harness.errors import SrrError
from harness.recording.bagread import ros1_recording
from harness.recording.errors import BagError
from harness.scenario.schema import ToleranceSpec
from harness.summary import replay_note

__all__ = ["check_against_summary", "diff_runs", "open_run"]


def open_run(path: Path) -> tuple[dict[str, Any], Path]:
    """(summary, bag directory) of a run directory; :class:`SrrError` (exit 2) naming what is
    missing or malformed."""
    from harness.summary import read_summary

    summary = read_summary(path)
    topics = summary.get("topics", {})
    if not isinstance(topics, dict) or not all(isinstance(v, dict) for v in topics.values()):
        raise SrrError(f"{path / 'summary.json'}: topics: expected a mapping of topic → "
                       "{count, sha256, ...}")
    bag = path / "bag"
    if not bag.is_dir():
        raise SrrError(f"{bag}: missing (a run directory holds its recording in bag/)")
    if not (bag / "metadata.yaml").is_file() and ros1_recording(bag) is None:
        raise SrrError(f"{bag / 'metadata.yaml'}: missing (not a rosbag2 directory)")
    return summary, bag


def _info(path: Path, s: Mapping[str, Any]) -> RunInfo:
    sim = s.get("simulated_s")
    return RunInfo(path, str(s.get("scenario", "?")), s.get("seed"), str(s.get("verdict", "?")),
                   float(sim) if isinstance(sim, (int, float)) else None,
                   str(s.get("digest", "")), replay_note(s))


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
                          side: int) -> str | None:
    """Raise :class:`BagError` when the bag read back is not what ``summary.json`` recorded
    (per topic count and SHA-256 over log time and payload): a truncated or damaged MCAP can
    still parse. Returns a note when the summary has no digests to check against."""
    recorded = summary.get("topics") or {}
    if not recorded:
        return f"{bag.parent / 'summary.json'}: no per-topic digests; the bag is not checked"
    for t in topics:
        sha, count = (t.sha256_a, t.count_a) if side == 0 else (t.sha256_b, t.count_b)
        entry = recorded.get(t.name)
        if sha is None and entry is None:
            continue
        if sha is None or entry is None or entry.get("sha256") != sha \
                or entry.get("count") != count:
            got = "absent" if sha is None else f"{count} messages"
            want = "absent" if entry is None else f"{entry.get('count')} messages"
            raise BagError(f"{bag}: {t.name}: does not match summary.json (read back: {got}; "
                           f"recorded: {want}, digest differs): the bag is damaged or "
                           "truncated, or the summary belongs to another recording")
    return None


def diff_runs(a: str | Path, b: str | Path, *,
              tolerances: Sequence[Tolerance | str] = ()) -> DiffResult:
    """Compare run directory ``a`` (the baseline) with ``b`` (the candidate).

    ``tolerances``: :class:`Tolerance` objects or ``--tolerance`` strings
    (``TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]``). Raises :class:`SrrError` (exit 2) for bad
    input: a tolerance that does not parse, a directory that is not a run, a malformed
    ``summary.json``, a bag that does not read back or does not match its summary."""
    tols = tuple(t if isinstance(t, Tolerance) else parse_tolerance(t) for t in tolerances)
    pa, pb = Path(a), Path(b)
    sa, bag_a = open_run(pa)
    sb, bag_b = open_run(pb)
    ma = summary_metrics(sa, pa / "summary.json")
    mb = summary_metrics(sb, pb / "summary.json")
    topics = diff_bags(bag_a, bag_b, tols)
    notes: list[str] = []
    for t in tols:
        if not any(glob_match(td.name, t.topic) for td in topics):
            notes.append(f"--tolerance {t.spec!r} matches no topic of either run")
    for side, (s, bag) in enumerate(((sa, bag_a), (sb, bag_b))):
        note = check_against_summary(bag, s, topics, side)
        if note:
            notes.append(note)
    if sa.get("scenario") != sb.get("scenario"):
        notes.append(f"the runs are of different scenarios: {sa.get('scenario')!r} (A) and "
                     f"{sb.get('scenario')!r} (B)")
    metric_tols, problem = _scenario_tolerances(pa)
    if problem and (ma or mb):
        notes.append(problem)
    return DiffResult(_info(pa, sa), _info(pb, sb), topics, metric_deltas(ma, mb, metric_tols),
                      tols, tuple(notes))
