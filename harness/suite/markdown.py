"""A suite's pull-request summary (``srr suite --summary-md FILE``): GitHub-flavoured
Markdown built from the judged groups and the exit code the suite returns
(:class:`harness.suite.runner.SuiteResult`), never re-derived from files.

A headline (verdict, exit code, groups by verdict, runs, wall time), then only what a reviewer
must act on: the groups that did not pass, the regressed (and missing) metrics with their
mean over the repeats, 95 % confidence interval, baseline, delta and tolerance, the flaky
groups with where their repeats diverged, the runs that crashed, timed out or could not run,
the groups whose recording is not byte for byte their baseline's (folded away: which topics,
which versions), and links to every report. Groups keep the suite's order (worst verdict
first, then plan order); metrics are sorted by name. The text is capped
(:func:`harness.report.markdown.cap`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from harness.atomic import write_text_atomic
from harness.report.markdown import (
    COMMENT_LIMIT,
    cap,
    cell,
    code,
    link,
    num,
    table,
    verdict_mark,
)
from harness.run.markdown import default_link_base
from harness.suite.results import GROUP_ORDER, GroupResult, RunOutcome
from harness.summary import versions_note

if TYPE_CHECKING:
    from harness.suite.runner import SuiteResult

__all__ = ["suite_markdown", "write_markdown"]


def _reports(runs: Sequence[RunOutcome], base: str) -> str:
    parts = [link(f"#{r.spec.repeat}" if len(runs) > 1 else "report", base, r.report)
             for r in runs if r.report is not None]
    return " ".join(parts) or "—"


def _headline(result: SuiteResult) -> list[str]:
    s = result.summary
    groups = result.groups
    counts = [(v, sum(g.verdict == v for g in groups)) for v in GROUP_ORDER]
    by = " · ".join(f"{n} {v}" for v, n in counts if n) or "no groups"
    runs = sum(len(g.runs) for g in groups)
    name = code(s.get("name", "?"), in_table=False)
    return [f"## {verdict_mark(result.verdict)} srr suite {name}: "
            f"**{result.verdict}** (exit code {result.exit_code})", "",
            f"**{len(groups)} group(s), {runs} run(s)** in {float(s.get('wall_s', 0.0)):.1f} s "
            f"on {cell(s.get('executor', '?'))} × {cell(s.get('jobs', '?'))}: {by}", ""]


def _not_passing(groups: Sequence[GroupResult], base: str) -> list[str]:
    bad = [g for g in groups if g.exit_code != 0]
    if not bad:
        return []
    rows = [[f"{verdict_mark(g.verdict)} {g.verdict}", code(g.id), str(len(g.runs)),
             cell(g.reasons[0]) if g.reasons else "—", _reports(g.runs, base)] for g in bad]
    return ["### Groups that did not pass", "",
            *table(["verdict", "group", "repeats", "first reason", "reports"], rows), ""]


def _delta(st: Any) -> float | None:
    mean, baseline = st.get("mean"), st.get("baseline")
    if isinstance(mean, (int, float)) and isinstance(baseline, (int, float)):
        return float(mean) - float(baseline)
    return None


def _regressed(groups: Sequence[GroupResult]) -> list[str]:
    rows = []
    for g in groups:
        for name, st in sorted(g.stats.items()):
            if st.get("status") not in ("regressed", "missing"):
                continue
            unit = str(st.get("unit") or "")
            ci = st.get("ci95")
            rows.append([
                code(g.id), code(name), num(st.get("mean"), unit),
                "—" if not ci else f"[{num(ci[0])}, {num(ci[1])}]", num(st.get("baseline")),
                "—" if _delta(st) is None else f"{_delta(st):+.4g}",
                "—" if st.get("tolerance") is None else f"±{num(st.get('tolerance'))}",
                str(st.get("n", 0)), str(st.get("status"))])
    if not rows:
        return []
    return ["### Regressed metrics", "",
            *table(["group", "metric", "mean", "95 % CI", "baseline", "delta", "tolerance",
                    "n", "status"], rows), ""]


def _flaky(groups: Sequence[GroupResult], base: str) -> list[str]:
    rows = []
    for g in groups:
        if not g.flaky or g.flaky_detail is None:
            continue
        d = g.flaky_detail
        verdicts = " / ".join(str(v) for v in d.get("verdicts", []))
        topics = ", ".join(code(t) for t in d.get("differing_topics", [])) or "—"
        rows.append([code(g.id), cell(verdicts), topics,
                     cell(d.get("first_divergence") or "—"), _reports(g.runs, base)])
    if not rows:
        return []
    return ["### Flaky groups", "",
            *table(["group", "repeats' verdicts", "differing topics", "first divergence",
                    "reports"], rows), ""]


def _broken(groups: Sequence[GroupResult], base: str) -> list[str]:
    rows = []
    for g in groups:
        for r in g.runs:
            if r.verdict != "INVALID":
                continue
            how = ("timed out" if r.timed_out else "crashed" if r.crash is not None else
                   "invalid")
            rows.append([code(r.spec.id), how, cell(r.reasons[0] if r.reasons else "—"),
                         link("log", base, r.log), link("report", base, r.report)])
    if not rows:
        return []
    return ["### Crashed, timed-out and invalid runs", "",
            *table(["run", "what", "reason", "log", "report"], rows), ""]


def _other_bytes(groups: Sequence[GroupResult], base: str) -> list[str]:
    """Groups (not flaky) whose recording is not byte for byte their baseline's: folded
    away, since their metrics were judged on their own; a drift a reviewer may want to see,
    or the mark of another machine (versions, OpenGL renderer)."""
    rows = []
    for g in groups:
        b = g.against_baseline
        if b is None or not g.recorded_other_bytes:
            continue
        topics = [str(t) for t in b.get("topics_differing") or ()]
        shown = ", ".join(code(t) for t in topics[:6]) + (" …" if len(topics) > 6 else "")
        versions = versions_note({"versions_differing": b.get("versions_differing")})
        rows.append([code(g.id), f"{g.verdict}", f"{len(topics)}: {shown}" if topics else "—",
                     cell(versions) if versions else "—", _reports(g.runs[:1], base)])
    if not rows:
        return []
    return [f"<details><summary>{len(rows)} group(s) recorded other bytes than their "
            "baselines</summary>", "",
            *table(["group", "verdict", "topics that differ", "versions (baseline → run)",
                    "report"], rows), "", "</details>", ""]


def _passing(groups: Sequence[GroupResult], base: str) -> list[str]:
    good = [g for g in groups if g.exit_code == 0]
    if not good:
        return []
    rows = [[f"{verdict_mark(g.verdict)} {g.verdict}", code(g.id), str(len(g.runs)),
             _reports(g.runs, base)] for g in good]
    return ["<details><summary>" f"{len(good)} group(s) passed" "</summary>", "",
            *table(["verdict", "group", "repeats", "reports"], rows), "", "</details>", ""]


def _blessed(blessed: Any) -> list[str]:
    """What ``--update-baselines`` did, after the verdicts it came after (a group judged
    against no baseline, then blessed, still says "no baseline")."""
    if not isinstance(blessed, Mapping):
        return []
    written, unchanged = blessed.get("written") or [], blessed.get("unchanged") or []
    lines = [f"**Baselines blessed** (`--update-baselines`, reason: "
             f"{cell(blessed.get('reason', ''))}): {len(written)} written, {len(unchanged)} "
             "unchanged; the verdicts above were judged before.", ""]
    lines += [f"- {code(Path(p).name)}" for p in written]
    lines = [*lines, ""] if written else lines
    refused = blessed.get("not_blessed") or []
    if refused:
        lines += [f"**Not blessed** ({len(refused)}):", "",
                  *(f"- {cell(str(why))}" for why in refused), ""]
    return lines


def suite_markdown(result: SuiteResult, *, link_base: str = "",
                   limit: int = COMMENT_LIMIT) -> str:
    """The summary of ``result`` as Markdown of at most ``limit`` bytes; report, log and
    suite-page links are the suite folder's relative paths under ``link_base``."""
    groups = result.groups
    lines = [*_headline(result)]
    if result.summary.get("interrupted"):
        lines += ["The suite was interrupted: the runs not finished are not judged.", ""]
    lines += _blessed(result.summary.get("baselines_blessed"))
    lines += [*_not_passing(groups, link_base), *_regressed(groups),
              *_flaky(groups, link_base), *_broken(groups, link_base),
              *_other_bytes(groups, link_base), *_passing(groups, link_base)]
    return cap(lines, limit, last=f"Suite page: {link('index.html', link_base, 'index.html')} · "
                                  f"{link('summary.json', link_base, 'summary.json')} · "
                                  f"{link('junit.xml', link_base, 'junit.xml')}")


def write_markdown(result: SuiteResult, path: Path, *, link_base: str | None = None,
                   limit: int = COMMENT_LIMIT) -> Path:
    """Write :func:`suite_markdown` to ``path`` (atomically); links default to the suite
    folder relative to ``path``'s folder."""
    base = default_link_base(result.out_dir, path) if link_base is None else link_base
    write_text_atomic(path, suite_markdown(result, link_base=base, limit=limit))
    return path
