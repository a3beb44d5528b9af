"""One run's pull-request summary (``srr run --summary-md FILE``): GitHub-flavoured Markdown
built from the :class:`~harness.run.summary.RunSummary` whose verdict and exit code the run
returns: a headline, the reasons, the health gates that tripped, the regressed (and missing)
metrics with value, baseline, delta and tolerance, every other metric folded away, and a link
to the report. One run has no repeats, so no confidence interval: ``srr suite --repeat N``
gives one per metric."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any
from urllib.parse import quote

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
from harness.run.summary import RunSummary
from harness.summary import recording_note

__all__ = ["default_link_base", "run_markdown", "write_markdown"]


def default_link_base(target: Path, md_file: Path) -> str:
    """``target`` (a run or suite folder) relative to the folder the Markdown file is in, as
    a POSIX path ('' when they are the same folder), percent-encoded as a link's base (a
    ``#`` or ``?`` in a folder's name is not a URL's fragment or query): what a link in the
    file opens."""
    rel = os.path.relpath(Path(target).resolve(), Path(md_file).resolve().parent)
    return "" if rel == "." else quote(Path(rel).as_posix(), safe="/=,@")


def _comparison_row(e: Any) -> list[str]:
    unit = str(e.get("unit") or "")
    delta = e.get("delta")
    return [code(e.get("name", "?")), num(e.get("value"), unit), num(e.get("baseline")),
            "—" if not isinstance(delta, (int, float)) else f"{delta:+.4g}",
            "—" if e.get("tolerance") is None else f"±{num(e.get('tolerance'))}",
            cell(str(e.get("status", "")).replace("_", " "))]


def run_markdown(summary: RunSummary, *, link_base: str = "",
                 limit: int = COMMENT_LIMIT) -> str:
    """The summary of one run as Markdown of at most ``limit`` bytes; the report link is
    ``report.html`` under ``link_base`` (the run directory as the reader reaches it)."""
    s = summary
    lines = [f"## {verdict_mark(s.verdict)} srr run {code(s.scenario, in_table=False)}: "
             f"**{s.verdict}** (exit code {s.exit_code})", "",
             f"seed {s.seed}, {s.simulated_s:.1f} s simulated, {len(s.topics)} topics, "
             f"digest {code(s.digest[:16])} · {link('report', link_base, 'report.html')} · "
             f"{link('summary.json', link_base, 'summary.json')}", ""]
    recording = recording_note({"baseline": s.baseline.to_json() if s.baseline else None,
                                "topics": s.topics})
    if recording is not None:
        lines += [cell(recording, 1000), ""]
    if s.reasons:
        lines += [f"- {cell(r, 1000)}" for r in s.reasons] + [""]
    bad = [h for h in s.health if not h.ok]
    if bad:
        lines += [f"### Health gates that tripped ({len(bad)} of {len(s.health)})", "",
                  *table(["gate", "detail"], [[code(h.name), cell(h.detail)] for h in bad]),
                  ""]
    regressed = sorted((e for e in s.comparison if e.get("status") in ("regressed", "missing")),
                       key=lambda e: str(e.get("name")))
    headers = ["metric", "value", "baseline", "delta", "tolerance", "status"]
    if regressed:
        lines += ["### Regressed metrics", "",
                  *table(headers, [_comparison_row(e) for e in regressed]), ""]
    others = sorted((e for e in s.comparison if e.get("status") not in ("regressed", "missing")),
                    key=lambda e: str(e.get("name")))
    if others:
        lines += [f"<details><summary>{len(others)} other metric(s)</summary>", "",
                  *table(headers, [_comparison_row(e) for e in others]), "", "</details>", ""]
    elif not s.comparison and s.metrics:
        rows = [[code(m.get("name", "?")), num(m.get("value"), str(m.get("unit") or ""))]
                for m in sorted(s.metrics, key=lambda m: str(m.get("name")))]
        lines += [f"<details><summary>{len(rows)} metric(s), no baseline</summary>", "",
                  *table(["metric", "value"], rows), "", "</details>", ""]
    return cap(lines, limit)


def write_markdown(summary: RunSummary, run_dir: Path, path: Path, *,
                   link_base: str | None = None, limit: int = COMMENT_LIMIT) -> Path:
    """Write :func:`run_markdown` to ``path`` (atomically); links default to the run
    directory relative to ``path``'s folder."""
    base = default_link_base(run_dir, path) if link_base is None else link_base
    write_text_atomic(path, run_markdown(summary, link_base=base, limit=limit))
    return path
