"""``srr diff SUITE_A SUITE_B --html FILE``: the suite comparison on one self-contained page,
in the style of the diff and suite pages (``templates/suitediff.html``).

From the top: the verdict and counts, both suites' cards, what changed between the matched
runs' inputs (each line with the runs it is true of), the group verdicts that changed, every
matched run — those that differ first, each with its verdicts, its recording's status, what
differs (topics, first divergence, metrics moved with their values) and links — and the runs
only in A or only in B.

Each matched run that differs gets the run diff's page (:func:`harness.diff.write_diff`,
both runs' videos side by side) beside this one, in ``FILE.pairs/<run id>.html``, linked as
"details"; the runs' own ``report.html`` are linked too. Links are relative to the page. No
script and no request.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from urllib.parse import quote

from harness import __version__
from harness.atomic import write_text_atomic
from harness.diff import write_diff
from harness.report.html import fmt_value
from harness.report.plots import BASELINE, CANDIDATE
from harness.report.templates import template
from harness.suite.diff import RunPair, SuiteDiff, SuiteInfo, runs_named
from harness.suite.plan import safe_file_name

__all__ = ["render_suite_diff", "write_suite_diff"]

_RECORDING_TEXT = {"identical": "identical", "within_tolerance": "within tolerance",
                   "differs": "differs", "only_in_a": "only in A", "only_in_b": "only in B",
                   "none": "none"}


def _link(target: Path | None, page_dir: Path) -> str | None:
    """``target`` relative to the page's folder, quoted; None when there is no such file."""
    if target is None or not target.is_file():
        return None
    rel = Path(os.path.relpath(target.resolve(), page_dir.resolve())).as_posix()
    return quote(rel, safe="/._-~")


def _what(p: RunPair) -> list[str]:
    """What differs in pair ``p``, a line each: topics, first divergence, metrics."""
    d = p.diff
    out: list[str] = []
    if p.recording == "only_in_a":
        out.append("only A recorded anything (B ended before its first tick)")
    elif p.recording == "only_in_b":
        out.append("only B recorded anything (A ended before its first tick)")
    elif p.recording == "none":
        out.append("neither run recorded anything")
    if d is not None:
        differing = [t for t in d.topics if t.status != "identical"]
        if differing:
            out.append(f"{len(differing)} of {len(d.topics)} topics: " + ", ".join(
                t.name if t.status == "differs" else f"{t.name} ({_RECORDING_TEXT[t.status]})"
                for t in differing))
        first = d.first_divergence
        if first is not None:
            out.append(f"first divergence: {first.describe()}")
    out += [f"{m.name}: {fmt_value(m.value_a, m.unit)} → {fmt_value(m.value_b, m.unit)} "
            f"(tolerance ±{m.tolerance:.3g}, {m.status})" for m in p.moved]
    return out


def _row(p: RunPair, page_dir: Path, details: Mapping[str, Path]) -> dict[str, Any]:
    row = "verdict" if not p.equal else "moved" if p.changed else "identical"
    return {"id": p.id, "verdict_a": p.verdict_a, "verdict_b": p.verdict_b,
            "verdict_changed": p.verdict_changed, "recording": p.recording,
            "recording_text": _RECORDING_TEXT[p.recording], "row": row, "what": _what(p),
            "details": _link(details.get(p.id), page_dir),
            "report_a": _link(p.report_a, page_dir), "report_b": _link(p.report_b, page_dir)}


def _card(s: SuiteInfo, style: Any) -> dict[str, Any]:
    info = [("suite folder", str(s.path)), ("suite", s.name), ("verdict", s.verdict),
            ("started", s.started_at or "?"), ("runs", str(s.runs))]
    return {"key": style.key, "label": style.label, "color": style.color, "info": info}


def render_suite_diff(result: SuiteDiff, *, page: Path | None = None,
                      details: Mapping[str, Path] | None = None) -> str:
    """The page's HTML. ``page``: where it will be (links are relative to its folder);
    ``details``: each pair's own diff page, by run id."""
    page_dir = (page or Path("suite-diff.html")).absolute().parent
    pairs = sorted(result.pairs, key=lambda p: (p.equal, not p.changed))  # stable: A's order
    unmatched = [(side, [{"id": r.id, "verdict": r.verdict,
                          "report": _link(r.report, page_dir)} for r in runs])
                 for side, runs in (("A", result.only_in_a), ("B", result.only_in_b))]
    toc = [("suites", "Suites")]
    if result.groups:
        toc.append(("groups", "Group verdicts"))
    toc += [("runs", "Matched runs"), ("only-in-a", "Only in A"), ("only-in-b", "Only in B")]
    return template("suitediff.html").render(
        verdict=result.verdict, verdict_text=result.verdict.replace("_", " "),
        exit_code=result.exit_code, a=result.a, b=result.b, counts=result.counts(), toc=toc,
        notes=list(result.notes),
        suites=[_card(result.a, BASELINE), _card(result.b, CANDIDATE)],
        changes=[{"text": c, "runs": f"({runs_named(ids, len(result.pairs))})"}
                 for c, ids in result.changes],
        tolerances=[t.spec for t in result.tolerances], groups=list(result.groups),
        pairs=[_row(p, page_dir, details or {}) for p in pairs], unmatched=unmatched,
        srr_version=__version__)


def write_suite_diff(result: SuiteDiff, path: str | Path, *, video: bool = True) -> Path:
    """Write the page to ``path`` and, for every matched run that differs (a verdict, a
    recording not identical, a metric moved), the run diff's page into ``<path>.pairs/``
    (``video=False``: without the runs' camera videos); returns the page's path."""
    path = Path(path)
    details: dict[str, Path] = {}
    folder = path.parent / f"{path.name}.pairs"
    used: set[str] = set()
    for p in result.pairs:
        if p.diff is None or not p.changed:
            continue
        name = safe_file_name(p.id)
        while name in used:  # two ids that read alike as file names
            name += "_"
        used.add(name)
        folder.mkdir(exist_ok=True)
        details[p.id] = write_diff(p.diff, folder / f"{name}.html", video=video)
    write_text_atomic(path, render_suite_diff(result, page=path, details=details))
    return path
