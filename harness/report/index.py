"""``index.html`` of a suite: every run's verdict, scenario and key regressions, linking to
its ``report.html`` by a relative path (the folder can be moved or downloaded as one CI
artifact and still works offline)."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any
from urllib.parse import quote

from jinja2 import Environment, StrictUndefined
from markupsafe import Markup

from harness.atomic import write_text_atomic
from harness.errors import SrrError
from harness.report.html import REPORT_NAME, fmt_value
from harness.report.templates import CSS, INDEX
from harness.summary import read_summary

__all__ = ["INDEX_NAME", "VERDICT_ORDER", "write_index"]

INDEX_NAME = "index.html"
# worst first: a run whose scores cannot be trusted, then regressions, failures, cut-short runs
VERDICT_ORDER = ("INVALID", "MISMATCH", "REGRESSED", "FAIL", "INTERRUPTED", "UNSCORED",
                 "PASS")
MAX_KEY = 3


def _rank(verdict: str) -> int:
    return VERDICT_ORDER.index(verdict) if verdict in VERDICT_ORDER else 0


def _excess(e: dict[str, Any]) -> float:
    """How many tolerances a regression moved (inf: undefined, missing or zero tolerance)."""
    delta, tol = e.get("delta"), e.get("tolerance") or 0.0
    if not isinstance(delta, (int, float)) or tol <= 0:
        return math.inf
    return abs(delta) / tol


def _key_lines(s: dict[str, Any]) -> list[str]:
    regressed = [e for e in s.get("comparison") or []
                 if e.get("status") in ("regressed", "missing")]
    regressed.sort(key=lambda e: -_excess(e))
    if regressed:
        return [f"{e['name']}: {fmt_value(e.get('value'), e.get('unit', ''))} vs "
                f"{fmt_value(e.get('baseline'), e.get('unit', ''))} ({e.get('status')})"
                for e in regressed]
    return [str(r) for r in s.get("reasons", [])]


def _row(run: Path, out_dir: Path) -> dict[str, Any]:
    label = Path(os.path.relpath(run.resolve(), out_dir.resolve())).as_posix()
    try:
        s = read_summary(run)
    except SrrError as err:
        return {"verdict": "INVALID", "scenario": run.name, "key": [str(err)], "more": 0,
                "sim_s": "", "seed": "", "href": None, "label": label}
    key = _key_lines(s)
    report = run / REPORT_NAME
    href = None
    if report.is_file():
        rel = os.path.relpath(report.resolve(), out_dir.resolve())
        href = quote(Path(rel).as_posix(), safe="/._-~")
    verdict = str(s.get("verdict", "INVALID"))
    sim = s.get("simulated_s")
    return {"verdict": verdict if verdict in VERDICT_ORDER else "INVALID",
            "scenario": str(s.get("scenario", run.name)), "key": key[:MAX_KEY],
            "more": max(0, len(key) - MAX_KEY),
            "sim_s": f"{sim:.1f}" if isinstance(sim, (int, float)) else "",
            "seed": s.get("seed", ""), "href": href, "label": label}


def write_index(out_dir: str | Path, runs: Sequence[str | Path], *,
                title: str = "srr suite") -> Path:
    """Write ``<out_dir>/index.html`` for ``runs`` (run directories) and return its path.

    Runs are listed worst verdict first (INVALID, REGRESSED, FAIL, INTERRUPTED, PASS), in the
    given order within a verdict; a directory without a readable ``summary.json`` is listed
    as INVALID with the reason. The banner shows the worst verdict of the suite."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = [_row(Path(r), out) for r in runs]
    rows.sort(key=lambda r: _rank(r["verdict"]))
    overall = rows[0]["verdict"] if rows else "INVALID"
    counts = [(v, sum(r["verdict"] == v for r in rows)) for v in VERDICT_ORDER]
    counts = [(v, n) for v, n in counts if n] or [("runs", 0)]
    env = Environment(autoescape=True, undefined=StrictUndefined, trim_blocks=True,
                      lstrip_blocks=True)
    text = env.from_string(INDEX).render(css=Markup(CSS), title=title, overall=overall,
                                         counts=counts, runs=rows)
    path = out / INDEX_NAME
    write_text_atomic(path, text)
    return path
